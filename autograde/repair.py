"""Before grading: put a student's notebook back in the shape nbgrader expects, and read its receipts.

Everything here works on the submitted notebook as data (it runs none of it) and returns notes that
go to the student's line in ``report.csv``:

* ``clean_colab``: drop the metadata Colab adds;
* ``match_cells``: graded cells that lost their nbgrader metadata (a retyped or pasted cell, a
  front-end that strips metadata), carry it under another name, or appear twice are matched back
  to the instructor's cells by cell id, then by content (the names a solution cell defines, the
  prompt a written answer follows); a graded cell that cannot be found is reported;
* ``restore_locked_cells``: locked test cells the student deleted are put back;
* ``receipt_verdict``: the completion point of a predict-then-run exercise, from the receipts in
  the student's own outputs, checked against the notebook's execution record.
"""

from __future__ import annotations

import ast
import copy
import re
from datetime import datetime

import nbformat

COLAB_CELL_KEYS = ("executionInfo", "colab", "outputId")
LOCK_RE = re.compile(r"^\[prediction (?P<again>already )?locked\] (?P<ex>ex\d): \((?P<choice>[a-d])\) at "
                     r"(?P<at>\S+?)(?:;.*)?$")
RUN_RE = re.compile(r"^\[experiment started\] (?P<ex>ex\d) at (?P<at>\S+) \(prediction locked at (?P<locked>\S+)\)$")
ANY_RECEIPT = re.compile(r"\[(prediction (already )?locked|experiment started)\] ex\d")
# Calls that run (part of) an exercise's experiment without run_exercise.
EXPERIMENT_CALLS = {"run", "run_seed", "two_world_eval", "experiment_ex1", "experiment_ex2", "experiment_ex3",
                    "run_loop", "imagination_stage", "train_in_imagination"}


def source(cell) -> str:
    s = cell.get("source", "")
    return "".join(s) if isinstance(s, list) else s


def gid(cell) -> str | None:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


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
    try:
        tree = ast.parse("\n".join("" if l.lstrip().startswith(("%", "!")) else l for l in src.splitlines()))
    except SyntaxError:
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


def _stdout_lines(cell) -> list[str]:
    lines = []
    for o in cell.get("outputs", []):
        if o.get("output_type") == "stream" and o.get("name") == "stdout":
            text = o.get("text", "")
            lines += ("".join(text) if isinstance(text, list) else text).splitlines()
    return lines


def _all_output_text(cell) -> str:
    parts = []
    for o in cell.get("outputs", []):
        for key in ("text",):
            t = o.get(key, "")
            parts.append("".join(t) if isinstance(t, list) else str(t))
        data = o.get("data", {})
        for v in data.values():
            parts.append("".join(v) if isinstance(v, list) else str(v))
        parts += [str(o.get("evalue", ""))] + [str(t) for t in o.get("traceback", [])]
    return "\n".join(parts)


def _calls(src: str) -> set[str]:
    try:
        tree = ast.parse("\n".join("" if l.lstrip().startswith(("%", "!")) else l for l in src.splitlines()))
    except SyntaxError:
        return set()
    out = set()
    todo = list(tree.body)
    while todo:                  # what runs when the cell runs: not the bodies of functions it defines
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        todo.extend(ast.iter_child_nodes(node))
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name):
                out.add(f.id)
            elif isinstance(f, ast.Attribute) and f.attr != "run":      # subprocess.run is not ours
                out.add(f.attr)
    return out


def receipt_verdict(nb, exercise: str) -> tuple[bool, str]:
    """Did the student's own outputs show the prediction locked before the experiment ran?

    The lock receipt counts only in the output of the ``<ex>_prediction`` cell, which must call
    ``lock_prediction``; the experiment receipt only in the output of a cell that calls
    ``run_exercise``. The lock cell must have run first (execution counts), the receipt times
    must agree with each other and with that order, and no cell may have run the experiment's
    functions before the lock. Receipt-like text anywhere else is ignored and reported.
    """
    ex = exercise
    code = [c for c in nb.cells if c.cell_type == "code"]
    lock_cell = next((c for c in code if gid(c) == f"{ex}_prediction"), None)
    if lock_cell is None or "lock_prediction(" not in source(lock_cell):
        return False, f"{ex}: the prediction cell (with lock_prediction) is missing or no longer locks"
    run_cells = [c for c in code if re.search(rf"run_exercise\(\s*['\"]{ex}['\"]", source(c))]
    stray = [i + 1 for i, c in enumerate(nb.cells)
             if c is not lock_cell and c not in run_cells and ANY_RECEIPT.search(_all_output_text(c))
             or c.cell_type != "code" and ANY_RECEIPT.search(source(c))]
    stray_note = (f"; receipt-like text in cell(s) {', '.join(map(str, stray))} was ignored: only the "
                  f"receipts printed by lock_prediction and run_exercise count") if stray else ""
    locks = [m for m in map(LOCK_RE.match, _stdout_lines(lock_cell)) if m and m["ex"] == ex]
    if not locks:
        return False, f"{ex}: no prediction receipt in the output of your prediction cell (run it){stray_note}"
    if len(locks) > 1 or any("[warning]" in l for l in _stdout_lines(lock_cell)):
        return False, f"{ex}: the prediction cell's receipts are inconsistent (or say the experiment ran first){stray_note}"
    lock = locks[0]
    runs = [(c, m) for c in run_cells for m in map(RUN_RE.match, _stdout_lines(c)) if m and m["ex"] == ex]
    if not runs:
        return False, f"{ex}: no experiment receipt in your notebook (run the experiment cell){stray_note}"
    run_cell, run = runs[0]
    try:
        started, locked = datetime.fromisoformat(run["at"]), datetime.fromisoformat(run["locked"])
        lock_at = datetime.fromisoformat(lock["at"])
    except ValueError:
        return False, f"{ex}: the receipts are unreadable (were they edited?){stray_note}"
    if lock_at != locked:
        return False, f"{ex}: the experiment used a prediction that this notebook's prediction cell never locked{stray_note}"
    if locked >= started:
        return False, f"{ex}: the experiment ran before the prediction was locked{stray_note}"
    n_lock, n_run = lock_cell.get("execution_count"), run_cell.get("execution_count")
    if not isinstance(n_lock, int) or not isinstance(n_run, int):
        return False, f"{ex}: the receipts are there but the cells have no execution record (were the outputs pasted in?){stray_note}"
    if n_lock >= n_run:
        return False, (f"{ex}: by the execution record the experiment cell ran (In [{n_run}]) before the "
                       f"prediction cell (In [{n_lock}]){stray_note}")
    early = [f"In [{c.get('execution_count')}]" for c in code
             if c is not lock_cell and isinstance(c.get("execution_count"), int)
             and c.get("execution_count") < n_lock and _calls(source(c)) & EXPERIMENT_CALLS]
    if early and not lock["again"]:
        return False, (f"{ex}: the experiment's functions ran directly ({', '.join(early)}) before the "
                       f"prediction was locked{stray_note}")
    return True, f"{ex}: prediction locked at {run['locked']}, experiment ran at {run['at']}: in order{stray_note}"
