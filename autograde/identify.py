"""Which of the assignment's notebooks is an uploaded file? Decided by what it holds, not by its name.

Students rename files: ``Copy of 05_horizon.ipynb`` (Colab), ``05_horizon (1).ipynb`` (a browser's
second download), ``05_horizon_final.ipynb`` (by hand). Intake reads every name it can, and this
module looks inside: each released notebook leaves marks that a student keeps when they work in it,

* the grade ids of its nbgrader cells (``metadata.nbgrader.grade_id``: nbgrader's own key for a
  graded cell, which Jupyter and Colab carry along as cell metadata),
* its cell ids (nbformat 4.5's ``id``, kept by Jupyter when a notebook is saved),
* the text of each cell the student is not asked to change (markdown, read-only code), compared
  with runs of whitespace collapsed, so a re-indented or re-wrapped cell still counts,

and marks that two released notebooks share (a common first cell, a setup line) are dropped. The
share of N's marks an upload holds is counted for ids (grade ids and cell ids) and for texts apart,
and the larger counts: a notebook saved by a tool that drops cell ids still holds N's texts, and
one whose every markdown cell was rewritten still holds its ids. An upload is notebook N when it
holds at least :data:`MIN_SHARE` of N's marks and at least :data:`MARGIN` times the share of any
other notebook's. Otherwise nothing is decided, and the
caller says so (intake: graded by its name where the name tells, else "needs a human").

Nothing here runs or renders the upload: it reads its JSON, already decoded and size-capped by
``intake.decode_notebook``.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

MIN_SHARE = 0.30      # of a release notebook's own marks; an untouched release holds all of them
MARGIN = 2.0          # the best share over the runner-up's
MIN_TEXT = 20         # characters (whitespace collapsed) for a cell's text to count as a mark


@dataclass(frozen=True)
class Match:
    """The verdict on one upload: ``notebook`` (a release file name) or None, the share of that
    notebook's marks found, and the runner-up with its share (for the words)."""
    notebook: str | None
    share: float
    runner_up: str | None = None
    runner_up_share: float = 0.0

    def words(self) -> str:
        """How the verdict was reached, for a note the student and the instructor read."""
        if self.notebook:
            return f"it holds {self.share:.0%} of {self.notebook}'s own cells (by their ids or their texts)"
        if self.runner_up and self.share >= MIN_SHARE:
            return (f"it holds {self.share:.0%} of one notebook's own cells and {self.runner_up_share:.0%} of "
                    f"{self.runner_up}'s: too close to tell")
        return (f"it holds at most {self.share:.0%} of any notebook's own cells (by their ids or their texts; "
                f"at least {MIN_SHARE:.0%} are needed)")


def _text(source) -> str:
    if isinstance(source, list):
        return "".join(x for x in source if isinstance(x, str))
    return source if isinstance(source, str) else ""


def _text_key(source) -> str | None:
    text = " ".join(_text(source).split())
    if len(text) < MIN_TEXT:
        return None
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def marks(nb, *, release: bool = False) -> set[tuple[str, str]]:
    """The marks of a notebook (module docstring). ``release``: only the cells a student is not
    asked to change count by their text (a release's solution cells are what students replace)."""
    out: set[tuple[str, str]] = set()
    cells = nb.get("cells") if isinstance(nb, dict) else None
    for cell in cells if isinstance(cells, list) else []:
        if not isinstance(cell, dict):
            continue
        meta = cell.get("metadata") if isinstance(cell.get("metadata"), dict) else {}
        grading = meta.get("nbgrader") if isinstance(meta.get("nbgrader"), dict) else {}
        if isinstance(grading.get("grade_id"), str):
            out.add(("id", "grade:" + grading["grade_id"]))
        if isinstance(cell.get("id"), str) and cell["id"]:
            out.add(("id", "cell:" + cell["id"]))
        if release and grading.get("solution"):
            continue
        key = _text_key(cell.get("source"))
        if key:
            out.add(("text", key))
    return out


def _answer_cell(cell) -> bool:
    meta = cell.get("metadata") if isinstance(cell, dict) and isinstance(cell.get("metadata"), dict) else {}
    grading = meta.get("nbgrader") if isinstance(meta.get("nbgrader"), dict) else {}
    return bool(grading.get("solution")) and isinstance(grading.get("grade_id"), str)


class Identifier:
    """Built once from the release (``{file name: notebook}``); :meth:`identify` judges uploads."""

    def __init__(self, release: dict):
        own = {name: marks(nb, release=True) for name, nb in release.items()}
        seen: dict[tuple[str, str], int] = {}
        for m in own.values():
            for mark in m:
                seen[mark] = seen.get(mark, 0) + 1
        self.marks = {name: {m for m in ms if seen[m] == 1} for name, ms in own.items()}
        # each notebook's answer cells as released: a hand-in whose answers are all these is unworked
        self.blanks = {name: {c["metadata"]["nbgrader"]["grade_id"]: " ".join(_text(c.get("source")).split())
                              for c in nb.get("cells", []) if _answer_cell(c)} for name, nb in release.items()}
        empty = [name for name, ms in self.marks.items() if not ms]
        if empty:
            raise ValueError(f"release notebooks with no mark of their own, which no upload could be "
                             f"told apart by: {', '.join(empty)}")

    def share(self, name: str, got: set) -> float:
        """The share of ``name``'s marks in ``got``: the larger of its ids' and its texts'."""
        best = 0.0
        for kind in ("id", "text"):
            mine = {m for m in self.marks[name] if m[0] == kind}
            if mine:
                best = max(best, len(mine & got) / len(mine))
        return best

    def unworked(self, nb, name: str) -> bool:
        """Whether ``nb``'s answer cells (nbgrader solution cells, by grade id) are all as ``name``
        was released: a copy of the hand-out, not the student's work. False when it holds none."""
        blanks = self.blanks.get(name) or {}
        found = {c["metadata"]["nbgrader"]["grade_id"]: " ".join(_text(c.get("source")).split())
                 for c in (nb.get("cells") if isinstance(nb.get("cells"), list) else []) if _answer_cell(c)}
        shared = [g for g in found if g in blanks]
        return bool(shared) and all(found[g] == blanks[g] for g in shared)

    def identify(self, nb) -> Match:
        got = marks(nb)
        shares = sorted(((self.share(name, got), name) for name in self.marks), reverse=True)
        (best, name), (second, other) = shares[0], shares[1] if len(shares) > 1 else (0.0, None)
        if best >= MIN_SHARE and best >= MARGIN * second:
            return Match(name, best, other, second)
        return Match(None, best, other if best >= MIN_SHARE else None, second)
