"""Per student, before anything runs: each notebook repaired, its receipts and graded functions read.

``prepare_student`` decodes every upload (``intake``), puts the graded cells back in shape
(``repair``), gives the completion verdicts (``receipts``), follows each graded function through
the notebook (``delegation``) and flags copies of the package's answers (``answer_key``). Nothing
here runs student code.
"""

from __future__ import annotations

from . import answer_key, cellcode, checks, delegation, intake, receipts, repair
from .course import EXERCISES

MAX_CODE_CHARS = 1_000_000     # all code cells of one notebook: what is parsed and followed at most


def prepare_student(uploads: dict, release: dict) -> tuple[dict, list[str], dict, dict]:
    """(repaired notebooks by file name, notes, completion verdicts, delegations by test id)."""
    notebooks, notes, completion, delegated = {}, [], {}, {}
    for name, up in sorted(uploads.items()):
        try:
            nb = intake.decode_notebook(up.data)
        except ValueError as e:
            notes.append(f"{name}: {e}; it scores 0")
            continue
        try:
            notes += _prepare_notebook(name, nb, release[name], completion, delegated)
        except Exception as e:       # noqa: BLE001  one odd hand-in never stops the class
            notes.append(f"{name}: could not be read for grading ({type(e).__name__}: {str(e)[:200]}); it "
                         f"scores 0. {intake.REDOWNLOAD}")
            continue
        notebooks[name] = nb
    return notebooks, notes, completion, delegated


def _prepare_notebook(name: str, nb, release, completion: dict, delegated: dict) -> list[str]:
    """Repair one notebook in place, read its receipts and follow its graded functions; returns
    its notes (``completion`` and ``delegated`` are filled in)."""
    notes = []
    code = sum(len(cellcode.source(c)) for c in nb.cells if isinstance(c, dict) and c.get("cell_type") == "code")
    if code > MAX_CODE_CHARS:
        raise ValueError(f"its code cells hold {code:,} characters, more than the {MAX_CODE_CHARS:,} the grader reads "
                         f"(a chapter notebook holds under 30,000)")
    if repair.clean_colab(nb):
        notes.append(f"{name}: saved by Colab; its extra metadata was removed")
    notes += [f"{name}: {n}" for n in repair.match_cells(nb, release)]
    for g in repair.restore_locked_cells(nb, release):
        notes.append(f"{name}: the locked test cell '{g}' was missing and was put back; never delete test cells")
    for ex, stem in EXERCISES.items():
        if name.startswith(stem):
            completion[ex] = receipts.receipt_verdict(nb, ex, release)
    for test in checks.TESTS.values():
        if name.startswith(test.notebook):
            copy = answer_key.copies(nb.cells, test)
            if copy:
                notes.append(f"{name}: answer key, for the instructor: {copy}")
            found = delegation.delegations(test, nb.cells, release)
            if found.definite:
                delegated[test.test_id] = found.definite
            elif found.ambiguous:
                notes.append(f"{name}: for the instructor: the grader cannot tell whether `{test.function}` "
                             f"reaches the package's own `{test.function}` ({'; '.join(found.ambiguous[:3])}); "
                             f"its score stands. Read that code; the student need do nothing unless you ask")
    return notes
