"""The protocol every LMS plug-in follows, and what the plug-ins share.

An LMS is one module of ``autograde/lms/`` (``canvas.py``, ``moodle.py``, ``blackboard.py``) holding
one :class:`Lms`, listed once in the registry (``autograde/lms/__init__.py``). It does four things,
each called by the generic module that owns that step, as nbgrader's preprocessors are composed
in a list:

* **read a download** (``lms_layouts``): :meth:`Lms.looks_like` says whether one member's path
  follows the LMS's naming, :meth:`Lms.vouched` may claim more members once all were looked at,
  :meth:`Lms.read` reads every member into an :class:`LmsFile` (or why it names no student);
* **name a student** (``lms_layouts.summarise``, ``intake``): :meth:`Lms.summarise` makes the
  student's record (``{"system", "name", "ids", "late", "submitted_at", "attempt"}``) and notes,
  :meth:`Lms.notebook_ids` each graded notebook's own upload id where the LMS returns pages by it;
* **write an import file** (``lms_export``): :meth:`Lms.settings` checks the LMS's section of
  course.yaml's ``lms:``, :meth:`Lms.import_sheet` fills a :class:`Sheet` from a :class:`SheetJob`;
  an LMS without one (:attr:`Lms.import_file` None) says why in :attr:`Lms.no_import`;
* **write a feedback package** (``lms_feedback``): :meth:`Lms.feedback_entries` names one
  :class:`StudentReturn`'s files as the LMS takes them back, :meth:`Lms.feedback_readme` tells the
  instructor how to upload them.

A plug-in imports only this module and ``autograde.text``; what it needs of the course (the
assignment's name, the other LMSs' titles) comes in its arguments.
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Callable

from ..text import clean_text, spreadsheet_text

RECEIPT_BYTES = 64 * 1024      # a receipt is a few hundred bytes; a bigger .txt is not one

# parse_notebook(file name) -> (prefix or None, notebook, re-upload counter) or None: intake's _Names.parse
NotebookParser = Callable[[str], "tuple[str | None, str, int] | None"]


# --- reading a download ---------------------------------------------------------------------------
@dataclass
class LmsFile:
    """One member of an LMS download as the LMS named it: whose, and what the student uploaded."""
    system: str
    lms_id: str                   # Canvas user id ("12345", "anon_x1Y2z"), Moodle participant id, Blackboard username
    name: str | None              # the student's name as the LMS wrote it (None where it wrote none)
    original: str | None          # the name the student gave the file; None for a file the LMS made
    made_by_lms: str = ""         # for such a file: "receipt", "text entry", "URL"
    late: bool | None = None
    rank: tuple = ()              # the LMS's own order of uploads: larger is newer
    when: datetime | None = None  # Blackboard: the attempt's time from the name
    file_id: str | None = None    # Canvas: the attachment id
    marker: str = ""              # Canvas: how the late marker was written ("LATE", "-late")
    label: str = ""               # how a note names this upload
    claims: str | None = None     # another student's LMS id that the student's own file name claims
    receipt: dict = field(default_factory=dict)   # Blackboard receipts: name, username, submitted, submitted_text


def word_char(c: str) -> bool:
    """Ruby's [[:word:]]: letters, marks, digits, connector punctuation (``_``)."""
    return c.isalnum() or c == "_" or unicodedata.category(c)[0] in "MN" or unicodedata.category(c) == "Pc"


# --- the import files -----------------------------------------------------------------------------
@dataclass
class Standing:
    """One student's score as the gradebook has it."""
    points: float                                   # every graded point (pending answers not counted)
    max_points: float                               # the assignment's total
    pending: list[tuple[str, str, float]] = field(default_factory=list)   # (notebook, grade id, max)
    notes: list[str] = field(default_factory=list)  # what the instructor should know about the score

    @property
    def pending_points(self) -> float:
        return sum(m for _, _, m in self.pending)


@dataclass
class Sheet:
    """One import file being assembled."""
    file: str
    header: list[str] = field(default_factory=list)
    lead: list[list[str]] = field(default_factory=list)                # rows before the students'
    rows: list[tuple[str, list[str]]] = field(default_factory=list)   # (student, row)
    pending: list[str] = field(default_factory=list)
    missing: dict[str, list[str]] = field(default_factory=dict)        # reason -> students
    conflicts: list[tuple[list[str], str]] = field(default_factory=list)   # (students, why)
    info: list[str] = field(default_factory=list)


@dataclass
class SheetJob:
    """What an LMS's import sheet is made from (``lms_export.write_lms_exports``)."""
    report: dict                                    # grade_class's per-student report
    standings: dict[str, Standing]                  # the gradebook's scores
    settings: dict                                  # this LMS's section of course.yaml's lms:, checked
    lms_max: float | None                           # the maximum the LMS's assignment is out of
    points: Callable[[Standing], str]               # a student's points as the file writes them
    now: datetime
    assignment: str                                 # the assignment's name (course.yaml)
    title: Callable[[str], str]                     # any LMS's title by its tag ("the hand-in came from ...")


def place(sheet: Sheet, claims: dict, report: dict, standings: dict, lms_points, make_row) -> None:
    """Rows for every identifier claimed by exactly one student whose score is final."""
    for key, students in sorted(claims.items(), key=lambda kv: kv[1][0]):
        if len(students) > 1:
            sheet.conflicts.append((students, f"{', '.join(students)}: all claim {key[0]} {key[1]!r}; none is "
                                              f"exported (check in the LMS which hand-in is whose)"))
            continue
        s = students[0]
        st = standings.get(s)
        if st is None:
            sheet.missing.setdefault("no score: the course has no gradebook entry for this student", []).append(s)
            continue
        if st.pending:
            sheet.pending.append(s)
            continue
        sheet.rows.append((s, make_row(key, s, student_label(report[s], s), lms_points(st))))


def lms_record(rep) -> dict | None:
    """``rep["lms"]`` when it is a usable identity, else None."""
    lms = (rep or {}).get("lms") if isinstance(rep, dict) else None
    if not isinstance(lms, dict) or not isinstance(lms.get("system"), str):
        return None
    ids = lms.get("ids")
    return {**lms, "ids": ids if isinstance(ids, dict) else {}}


def student_label(rep, student: str) -> str:
    """The student's name for a file: the LMS's, else the id; no control characters, no formula."""
    lms = lms_record(rep)
    name = clean_text(str(lms.get("name") or "")) if lms else ""
    return spreadsheet_text(name or student)


# --- the feedback packages ------------------------------------------------------------------------
SUMMARY = "summary.html"
NAME_CHARS = 60                      # of a student's name in a member name (the ids decide, the name only reads)


@dataclass
class StudentReturn:
    """One student's files: the summary first, then the notebook pages ({file name: its path}, read
    only when a package is written, one at a time, so a large class is never all in memory)."""
    student: str
    lms: dict | None
    summary: bytes
    pages: dict[str, Path] = field(default_factory=dict)
    withheld: int = 0                 # notes for the instructor left off the page

    def files(self) -> list[tuple[str, bytes | Path]]:
        return [(SUMMARY, self.summary), *sorted(self.pages.items())]


def safe_id(student: str) -> bool:
    return bool(student) and student not in (".", "..") and not any(c in student for c in "/\\\0") and \
        not any(unicodedata.category(c)[0] == "C" for c in student)


def digits_only(text) -> bool:
    return isinstance(text, str) and text.isascii() and text.isdigit()


# --- the protocol ---------------------------------------------------------------------------------
class Lms:
    """One LMS: its download read, its students named, its import file and its feedback package.

    A plug-in subclasses this and sets the attributes; a method left as it is here is a step the
    LMS does not take (no vouching, no per-notebook ids, no import file)."""
    name: str = ""                   # the tag in records and folder ids ("canvas")
    title: str = ""                  # as a sentence names it ("Canvas")
    id_key: str = ""                 # the key of ``record["ids"]`` that names the student in the LMS
    newest: str = ""                 # which of several uploads of one notebook is graded, as a note says it
    import_file: str | None = None   # the import file's name in the course folder, or None
    no_import: str = ""              # where there is none: the line the export notes say
    feedback_zip: str = ""           # the feedback package's name under feedback_return/
    feedback_folder: str | None = None   # the same files as a folder too, for an LMS they are attached to by hand

    # read a download
    def looks_like(self, parts: list[str], parse_notebook: NotebookParser) -> bool:
        """Whether one member's path (its components) follows this LMS's naming."""
        raise NotImplementedError

    def vouched(self, parts: list[list[str]], looks: list[set[str]], parse_notebook: NotebookParser) -> list[int]:
        """Members ``looks_like`` did not claim that follow this LMS's naming all the same."""
        return []

    def read(self, members: list[list[str]], parse_notebook: NotebookParser,
             read_text: Callable[[int], bytes]) -> tuple[list, list[str]]:
        """([LmsFile, or why the member names no student of this LMS], warnings), one per member."""
        raise NotImplementedError

    # name a student
    def summarise(self, files: list[LmsFile], graded: list[LmsFile], newest: LmsFile) -> tuple[dict, list[str]]:
        """(the student's record, notes in words) from all their files, those graded, and the newest."""
        raise NotImplementedError

    def notebook_ids(self, graded: list[tuple[str, LmsFile]]) -> dict | None:
        """{notebook: the id of its graded upload} where feedback returns under it, else None."""
        return None

    # write an import file
    def settings(self, raw: dict) -> tuple[dict, list[str]]:
        """This LMS's section of course.yaml's ``lms:`` over its defaults, and what in it is unusable."""
        return {}, []

    def import_sheet(self, job: SheetJob) -> Sheet:
        raise NotImplementedError

    # write a feedback package
    def feedback_entries(self, r: StudentReturn) -> list[tuple[str, bytes | Path]] | str:
        """[(member name, bytes or page path)] of this student in the package, or why none."""
        raise NotImplementedError

    def feedback_readme(self, n: int) -> list[str]:
        """README.txt's lines on this LMS's package of ``n`` students."""
        raise NotImplementedError
