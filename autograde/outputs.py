"""The graded copy of a notebook, kept to a size its feedback page can always be made from; and a
page all the same where there is no graded copy to make it from. Never no page for a graded notebook.

A student's cell may print any amount (``bigout`` prints a 25 MB line, ``flood`` prints until the
cell timeout). nbgrader writes every byte of it into the autograded notebook, and a copy too large
to read back (``task.MAX_NOTEBOOK_BYTES``) used to leave the student with no feedback page at all.
``CapOutput`` is the last step of nbgrader's autograde in the worker (``autograde_steps``), so it
runs after ``SaveAutoGrades`` has put the scores in the gradebook: the scores are those of every
output, and only what is written to the graded copy, and so shown on the page, is cut. What is cut
says so where it was, on the page:

    [output truncated: 38.0 MB of output not shown]

Bounds: any one output at most ``OUTPUT_BYTES`` (printed text keeps its beginning; an image or HTML
output over it is left out whole), all of a notebook's outputs together ``NOTEBOOK_OUTPUT_BYTES``
(past it, outputs are left out). An error is never left out (only its traceback is shortened past
the budget): the student sees what raised. A chapter notebook's outputs while grading are well under
1 MB, so an honest notebook's graded copy is never cut. The feedback page cuts further
(``feedback.FEEDBACK_OUTPUT_CHARS``, ``FEEDBACK_NOTEBOOK_CHARS``).

Where no graded copy can be read (a hand-in whose own cells make it larger than the grader reads
back), or nbgrader made none (it could not finish the notebook: output that kept coming after the
cell's time ran out, a kernel that died), ``stand_in`` makes the page from the notebook as handed in,
without outputs, under a first cell that says why; the scores on it are the gradebook's.
"""

from __future__ import annotations

import json
from functools import lru_cache

from nbformat import v4

OUTPUT_BYTES = 2 << 20             # one output in the graded copy (the page shows 20,000 characters of it)
NOTEBOOK_OUTPUT_BYTES = 8 << 20    # all outputs of one graded notebook together
ERROR_LINE_CHARS = 20_000          # one traceback line, or an error's value
NOTE = "[output truncated: {mb} MB of output not shown]"


def _size(o) -> int:
    """An output's size as written (characters of its JSON; its text's length for a stream)."""
    if o.get("output_type") == "stream":
        t = o.get("text", "")
        return len(t) if isinstance(t, str) else sum(map(len, t))
    return len(json.dumps(o))


def _mb(n: int) -> str:
    return f"{n / 1e6:.1f}"


def note(cut: int):
    """The output that says ``cut`` bytes of a cell's output are not shown: display data, not a
    stream, so that no page joins it to the stream it follows and cuts it off with it."""
    return v4.new_output("display_data", data={"text/plain": NOTE.format(mb=_mb(cut))})


def _short_error(o, lines: int | None) -> None:
    o["evalue"] = str(o.get("evalue", ""))[:ERROR_LINE_CHARS]
    tb = [str(t)[:ERROR_LINE_CHARS] for t in o.get("traceback", [])]
    if lines is not None and len(tb) > lines:
        tb = tb[:lines] + ["[traceback truncated]"]
    o["traceback"] = tb


def cap_cell(cell, left: int) -> int:
    """Cut ``cell``'s outputs to ``OUTPUT_BYTES`` each and ``left`` bytes in all, with a note where
    something was cut; returns what is left of the notebook's budget."""
    kept, cut = [], 0
    for o in cell.get("outputs", []):
        if o.get("output_type") == "error":
            _short_error(o, None)
            if _size(o) > left:
                _short_error(o, 0)
            left = max(left - _size(o), 0)
            kept.append(o)
            continue
        size = _size(o)
        room = min(OUTPUT_BYTES, left)
        if size <= room:
            kept.append(o)
            left -= size
            continue
        if o.get("output_type") == "stream" and room > 0:
            text = o["text"] if isinstance(o["text"], str) else "".join(o["text"])
            o["text"] = text[:room]
            kept.append(o)
            left -= room
            cut += size - room
        else:
            cut += size
    if cut:
        kept.append(note(cut))
    cell["outputs"] = kept
    return left


@lru_cache(maxsize=1)
def _cap_output():
    # made on first use: nbgrader's preprocessors take seconds to import, and only the worker needs them
    from nbgrader.preprocessors import NbGraderPreprocessor

    class CapOutput(NbGraderPreprocessor):
        """nbgrader's last autograde step here: the graded copy's outputs cut (``cap_cell``), with notes."""

        def preprocess(self, nb, resources):
            left = NOTEBOOK_OUTPUT_BYTES
            for cell in nb.cells:
                if cell.cell_type == "code" and cell.get("outputs"):
                    left = cap_cell(cell, left)
            return nb, resources

    CapOutput.__module__, CapOutput.__qualname__ = __name__, "CapOutput"
    return CapOutput


def __getattr__(name):          # outputs.CapOutput, made on first use
    if name == "CapOutput":
        return _cap_output()
    raise AttributeError(name)


def autograde_steps(config=None) -> list:
    """nbgrader autograde's steps (``Autograde.autograde_preprocessors``, as ``config`` sets them or
    nbgrader's own), with ``CapOutput`` last: after ``SaveAutoGrades`` has scored every output."""
    from nbgrader.converters import Autograde

    steps = (config.Autograde.get("autograde_preprocessors") if config is not None else None) or \
        Autograde.class_traits()["autograde_preprocessors"].make_dynamic_default()
    cap = _cap_output()
    return [s for s in steps if s is not cap] + [cap]


STAND_IN_NOTE = ("**{why}** This page shows your notebook as you handed it in, without its outputs{left}. "
                 "Your scores are those of the graded run; your instructor has the same note.")
TOO_LARGE = "The graded copy of this notebook is {mb} MB, too large to make a feedback page from."
NOT_FINISHED = ("The grader could not finish running this notebook (its output did not stop, or its kernel died or "
                "ran out of time), so there is no graded copy of its outputs.")


def stand_in(handed_in: str, size: int | None, source_chars: int = 20_000, total_chars: int = 2_000_000) -> str:
    """A notebook to make the feedback page from where there is no graded copy to make it from: one
    over the size the grader reads back (``size`` bytes: a hand-in whose own cells are that large;
    its outputs alone never are, ``CapOutput``), or none at all (``size`` None: nbgrader could not
    finish the notebook, e.g. output that kept coming after the cell's time ran out). The notebook
    as handed in (``handed_in``, JSON text, which intake bounded), outputs removed, each cell's text
    cut at ``source_chars`` and all of them at ``total_chars``, under a first cell that says so. Its
    graded cells keep their nbgrader metadata, so the page shows their scores from the gradebook.
    Never None: a hand-in that cannot be read gives the note alone."""
    import nbformat

    try:
        nb = nbformat.reads(handed_in, as_version=4)
    except Exception:          # noqa: BLE001  prepare_student repaired it; cannot happen, costs nothing
        nb = v4.new_notebook()
    cells, budget, dropped = [], total_chars, 0
    for cell in nb.cells:
        if budget <= 0:
            dropped += 1
            continue
        src = cell.get("source", "")
        src = "".join(src) if isinstance(src, list) else str(src)
        if len(src) > min(source_chars, budget):
            src = src[:min(source_chars, budget)] + ("\n# [... cut: the page is capped in size]\n"
                                                     if cell.cell_type == "code" else "\n\n*[... cut]*\n")
        budget -= len(src)
        cell["source"] = src
        if cell.cell_type == "code":
            cell["outputs"], cell["execution_count"] = [], None
        cell.pop("attachments", None)
        cells.append(cell)
    left = f" ({dropped} cells at the end left out: the page is capped in size)" if dropped else ""
    why = NOT_FINISHED if size is None else TOO_LARGE.format(mb=_mb(size))
    nb.cells = [v4.new_markdown_cell(STAND_IN_NOTE.format(why=why, left=left))] + cells
    return nbformat.writes(nb)
