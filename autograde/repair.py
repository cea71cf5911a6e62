"""Before grading: put a student's notebook back in the shape nbgrader expects.

Everything here works on the submitted notebook as data (it runs none of it) and returns notes that
go to the student's line in ``report.csv``:

* ``clean_colab``: drop the metadata Colab adds;
* ``match_cells``: graded cells that lost their nbgrader metadata (a retyped or pasted cell, a
  front-end that strips metadata), carry it under another name, or appear twice are matched back
  to the instructor's cells by cell id, then by content (the names a solution cell defines, the
  prompt a written answer follows); a graded cell that cannot be found is reported;
* ``restore_locked_cells``: locked test cells the student deleted are put back.

The completion points of the predict-then-run exercises are read from the receipts by
``receipts.py``.
"""

from __future__ import annotations

import ast
import copy
import re

import nbformat
from .cellcode import gid, parse, source

COLAB_CELL_KEYS = ("executionInfo", "colab", "outputId")


def clean_colab(nb) -> bool:
    """Drop the metadata Colab adds; True if there was any."""
    found = False
    for key in ("colab", "accelerator", "gpuClass"):
        found |= nb.metadata.pop(key, None) is not None
    nb.metadata.setdefault("kernelspec", {"display_name": "Python 3", "language": "python", "name": "python3"})
    for cell in nb.cells:
        for key in COLAB_CELL_KEYS:
            found |= cell.metadata.pop(key, None) is not None
    return found


def _defined_names(src: str) -> set[str]:
    """Top-level names a code cell defines (functions, classes, assignments)."""
    tree = parse(src)
    if tree is None:
        return set(re.findall(r"^def (\w+)\(", src, re.M))
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return names


def match_cells(nb, release) -> list[str]:
    """Give each of the release's graded cells exactly one home in ``nb``; returns notes."""
    notes = []
    graded = [c for c in release.cells if gid(c)]
    for rc in graded:
        g = gid(rc)
        holders = [c for c in nb.cells if gid(c) == g]
        meta = rc.metadata["nbgrader"]
        if len(holders) > 1:
            keep = _pick_duplicate(holders, rc)
            for c in holders:
                if c is not keep:
                    c.metadata.pop("nbgrader", None)
            notes.append(f"the graded cell '{g}' appeared {len(holders)} times; the "
                         f"{'last' if not meta.get('locked') else 'original'} one is graded")
            continue
        if holders:
            continue
        if meta.get("locked"):
            continue                       # restore_locked_cells puts it back from the release
        found = _find_home(nb, release, rc)
        if found is None:
            notes.append(f"the graded cell '{g}' is missing (deleted?): it scores 0; keep the cells "
                         f"you were given and write your answer inside them")
            continue
        found.metadata["nbgrader"] = copy.deepcopy(dict(meta))
        found.cell_type = rc.cell_type
        notes.append(f"the graded cell '{g}' had lost its grading metadata (a retyped or pasted "
                     f"cell?); it was recognised by its content and is graded as usual")
    return notes


def _pick_duplicate(holders, rc):
    if rc.metadata["nbgrader"].get("locked"):
        same = [c for c in holders if source(c) == source(rc)]
        return same[0] if same else holders[0]
    if rc.cell_type == "code":
        return holders[-1]                 # the last definition is the one that runs
    answered = [c for c in holders if source(c).strip() and "YOUR ANSWER HERE" not in source(c)]
    return (answered or holders)[-1]


def _find_home(nb, release, rc):
    """The student's cell that plays the role of release cell ``rc`` (which has no holder)."""
    free = [c for c in nb.cells if not gid(c)]
    rid = rc.get("id")
    for c in free:
        if rid and c.get("id") == rid and c.cell_type == rc.cell_type:
            return c
    if rc.cell_type == "code":
        want = _defined_names(source(rc))
        cands = [c for c in free if c.cell_type == "code" and want and want <= _defined_names(source(c))]
        return cands[-1] if cands else None
    # a written answer: the markdown cell right after the (read-only) prompt that precedes it
    i = release.cells.index(rc)
    prompt = source(release.cells[i - 1]) if i else None
    for j, c in enumerate(nb.cells[:-1]):
        if prompt is not None and source(c) == prompt:
            nxt = nb.cells[j + 1]
            if not gid(nxt) and nxt.cell_type in ("markdown", "raw"):
                return nxt
    return None


def restore_locked_cells(nb, release) -> list[str]:
    """Put back locked graded cells the student deleted, after the cell that precedes them in the
    release. Returns the grade ids restored."""
    present = {gid(c) for c in nb.cells if gid(c)}
    restored = []
    for i, cell in enumerate(release.cells):
        meta = cell.metadata.get("nbgrader", {})
        if meta.get("locked") and meta.get("grade") and gid(cell) not in present:
            prev = {gid(c) or c.get("id") for c in release.cells[:i]}
            pos = max([j + 1 for j, c in enumerate(nb.cells) if (gid(c) or c.get("id")) in prev], default=len(nb.cells))
            nb.cells.insert(pos, nbformat.from_dict(copy.deepcopy(dict(cell))))
            present.add(gid(cell))
            restored.append(gid(cell))
    return restored
