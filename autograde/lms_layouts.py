"""The bulk downloads of Canvas, Moodle and Blackboard: how each names its files, read back.

``intake`` uses this module when a class download is in one LMS's own layout; it decides which
student a file belongs to by the LMS's id of that student (Canvas user id, Moodle participant id,
Blackboard username), never by free text, and keeps the LMS's identifiers in ``Intake.lms``.
Every name here comes from an untrusted archive and is only ever parsed, never used as a path
(``intake`` has already refused hostile names before any of this runs).

What each LMS documents, and where
----------------------------------
The naming is read from each LMS's own source code where it is open (Canvas, Moodle): that code
is what writes the zip, so it is the documentation that cannot be out of date. Instructure's
and Anthology's help pages for "Download Submissions" / "Download Assignment" were searched for
and are not in the reference store this was written from; what they would add is which menu to
use, not the names.

Each LMS's naming, with where it was read and what is inferred where its sources are silent, is
in the docstring of its plug-in: ``autograde/lms/canvas.py`` (Canvas's "Download Submissions"),
``autograde/lms/moodle.py`` ("Download all submissions") and ``autograde/lms/blackboard.py``
(Blackboard Learn Original's "Assignment File Download"). This module holds what is the same for
all of them: which LMS a download is in (:func:`detect`), and each member read and each student
summarised by that LMS's plug-in (:func:`read`, :func:`summarise`).

In every layout, a student's own file name that is itself an LMS name of *another* student of
the same LMS (``bob_999_888_02_reward.ipynb`` in Canvas, ``Bob_999_assignsubmission_file_...`` in
Moodle, ``<assignment>_bob_attempt_..._...`` in Blackboard) is graded for nobody, as intake does
with ``<folder>/<other>_<notebook>.ipynb``; any other start of the name (``s042_02_reward.ipynb``)
is the student's own naming and is ignored.
"""

from __future__ import annotations

from collections import Counter
from typing import Callable

from .lms import PLUGINS, SYSTEMS, TITLE, plugin
from .lms.base import RECEIPT_BYTES, LmsFile, NotebookParser, word_char  # noqa: F401  (public names, moved)
from .lms.blackboard import parse_receipt, parse_receipt_date  # noqa: F401  (public names, moved)
from .lms.canvas import canvas_splits  # noqa: F401  (a public name, moved)
from .lms.moodle import MOODLE_FLAT  # noqa: F401  (a public name, moved)


class LayoutError(ValueError):
    """The class download as a whole cannot be read (e.g. it mixes two LMSs' layouts): nothing is
    graded, and the message says what to do instead."""


# --- the whole download --------------------------------------------------------------------------
def looks_like(parts: list[str], parse_notebook: NotebookParser) -> set[str]:
    """The LMSs whose naming this member's path (components) follows (``Lms.looks_like``)."""
    return {lms.name for lms in PLUGINS if lms.looks_like(parts, parse_notebook)}


def detect(members: list[list[str]], parse_notebook: NotebookParser) -> tuple[str | None, bool, str]:
    """(the LMS whose layout the download is in, or None; whether one folder around everything is
    to be skipped; a line for the instructor when the answer is not clear-cut, else "").

    A download is an LMS's when more than half its files follow that LMS's naming (an LMS names
    every file it puts in the zip). Raises ValueError when files follow two LMSs' namings that
    no one file shares: two downloads merged into one, which cannot be graded as one class.
    """
    variants = [(False, members)]
    if members and all(len(p) >= 2 for p in members) and len({p[0] for p in members}) == 1:
        variants.append((True, [p[1:] for p in members]))
    note = ""
    for wrapper, parts in variants:
        looks = [looks_like(p, parse_notebook) for p in parts]
        for lms in PLUGINS:
            for i in lms.vouched(parts, looks, parse_notebook):
                looks[i] = looks[i] | {lms.name}
        count = Counter(s for one in looks for s in one)
        only = {s: [p for p, one in zip(parts, looks) if one == {s}] for s in SYSTEMS}
        mixed = [s for s in SYSTEMS if only[s]]
        if len(mixed) >= 2:
            examples = "; ".join(f"{len(only[s])} named as {TITLE[s]} names them, e.g. {'/'.join(only[s][0])!r}"
                                 for s in mixed)
            raise LayoutError(f"this download mixes the layouts of {' and '.join(TITLE[s] for s in mixed)} "
                             f"({examples}): download each LMS's submissions on their own and grade them "
                             f"one at a time")
        if count:
            best = max(SYSTEMS, key=lambda s: count[s])
            if 2 * count[best] > len(parts):
                return best, wrapper, ""
            note = note or (f"{count[best]} of {len(parts)} files are named as {TITLE[best]} names them, the "
                            f"rest are not: the download is read as <student>_<notebook>.ipynb and "
                            f"<student>/<notebook>.ipynb files")
    return None, False, note


def read(system: str, members: list[list[str]], parse_notebook: NotebookParser,
         read_text: Callable[[int], bytes]) -> tuple[list, list[str]]:
    """([LmsFile, or why the member names no student of this LMS], warnings for the instructor),
    one per member (its path components, any wrapper folder removed). ``read_text(i)`` returns at
    most RECEIPT_BYTES of member i (for Blackboard's receipts) or raises ValueError."""
    return plugin(system).read(members, parse_notebook, read_text)


# --- one student's record ------------------------------------------------------------------------
def summarise(system: str, files: list[LmsFile], graded: list[LmsFile]) -> tuple[dict, list[str]]:
    """(the student's ``Intake.lms`` record, notes in words) from all their files in the download
    and those graded."""
    newest = max(graded or [f for f in files if f.made_by_lms != "receipt"] or files, key=lambda f: f.rank)
    return plugin(system).summarise(files, graded, newest)
