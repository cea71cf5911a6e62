"""The completion point of a predict-then-run exercise, read from the receipts in a hand-in.

``pusht.predict`` prints two receipts: the lock (``[prediction locked] ex1: (b) at L``, or
``[prediction already locked] ex1: (b) at L; ...`` when the lock cell runs again, the first lock
being kept, across restarts too, in ``.pusht_predictions.json``) and the experiment's
(``[experiment started] ex1 at S (prediction locked at L)``, which quotes the lock the store held
when the experiment started). The point is earned when the hand-in shows that the lock came
before the experiment:

1. a cell that calls ``lock_prediction`` printed a lock receipt at L, and no warning that the
   experiment had run before it;
2. a cell that calls ``run_exercise`` for the exercise printed an experiment receipt that quotes
   that same L (the experiment used the lock this notebook shows), with S not before L;
3. both cells carry an execution count (outputs pasted into a cell that never ran have none);
4. where the execution record places the lock (a fresh lock receipt, run before the experiment,
   and no count seen twice: one session), no cell ran the exercise's experiment functions
   (``EXPERIMENTS``, called, handed to a call, or called by a function the cell defines and
   calls) before it. A cell that the notebook itself places before the lock cell is
   not an early peek for the calls the notebook gave it (notebook 06 runs round 0 with ``run``
   before its prediction by design).

The counts are one piece of evidence, not the judge of order: a restart starts them again at 1,
so a lock made before a restart can carry a larger count than the experiment after it, and a
lock cell run again afterwards (to look at it) carries the largest count of all. The receipts'
times and the lock they quote decide the order; the counts decide only rule 4, where they can.

What this cannot catch: a learner who calls the experiment's functions directly before locking
and then restarts the kernel (or re-runs the lock cell) leaves the record an honest restart
leaves; one who calls them under another name (an alias, ``import ... as``) is not seen calling
them; one who hands ``run_exercise`` something else than the experiment gets a receipt all the
same; and one who deletes ``.pusht_predictions.json`` and runs everything again in order leaves
an honest-looking record; a hand-edited notebook whose receipts, times and counts agree cannot be
told from a real one. The receipts make the honest route the easy one; they are not proof.
"""

from __future__ import annotations

import ast
import re
from datetime import datetime

from . import cellcode

# Searched for in each printed line: text the learner printed without a newline just before may
# share the receipt's line.
LOCK_RE = re.compile(r"\[prediction (?P<again>already )?locked\] (?P<ex>ex\d): \((?P<choice>[a-d])\) at "
                     r"(?P<at>\S+?)(?:;.*)?$")
RUN_RE = re.compile(r"\[experiment started\] (?P<ex>ex\d) at (?P<at>\S+) \(prediction locked at (?P<locked>\S+)\)$")
ANY_RECEIPT = re.compile(r"\[(prediction (already )?locked|experiment started)\] ex\d")
WARNING = "[warning]"

# The functions that run (part of) each exercise's experiment, whatever cell calls them: the
# notebook's own experiment function and the package's functions it is built from.
_PIPELINE = {"run", "run_seed", "run_many", "start_many", "agent_stage", "two_world_eval",
             "imagination_stage", "train_in_imagination"}
EXPERIMENTS = {
    "ex1": _PIPELINE | {"experiment_ex1"},
    "ex2": _PIPELINE | {"experiment_ex2"},
    "ex3": {"experiment_ex3", "run_loop", "collect_episodes", "train_model_round", "train_agent_round",
            "measure_round"},
    # notebook 07: the actor trained and evaluated in the recipe's model (the pipeline's), and the
    # planner in the recipe's and the chapter's (``pusht.nb.planning.experiment``, ``plan_in``, ``pusht.plan``)
    "ex4": _PIPELINE | {"experiment_ex4", "experiment", "plan_in", "plan_rollout", "cem_plan"},
}


def _outputs(cell) -> list:
    outs = cell.get("outputs") if isinstance(cell, dict) else None
    return [o for o in outs if isinstance(o, dict)] if isinstance(outs, list) else []


def _stdout(cell) -> list[str]:
    """The cell's printed lines, consecutive stream outputs joined first: where the kernel (or the
    front-end that saved it) cut the text into messages must not cut a receipt in two."""
    text = [cellcode.text(o.get("text")) for o in _outputs(cell)
            if o.get("output_type") == "stream" and o.get("name") == "stdout"]
    return "".join(text).splitlines()


def _all_output_text(cell) -> str:
    parts = []
    for o in _outputs(cell):
        parts.append(cellcode.text(o.get("text")))
        data = o.get("data")
        if isinstance(data, dict):
            parts += [cellcode.text(v) for v in data.values()]
        tb = o.get("traceback")
        parts += [cellcode.text(o.get("evalue"))] + ([cellcode.text(t) for t in tb] if isinstance(tb, list) else [])
    return "\n".join(parts)


def _calls_to(tree, name: str, exercise: str | None = None) -> bool:
    """Does the cell call ``name`` (for ``exercise``, where it is given as a literal first
    argument or as ``exercise=``) anywhere, functions it defines included?"""
    for node in ast.walk(tree) if tree is not None else ():
        if isinstance(node, ast.Call):
            f = node.func
            if (f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None) != name:
                continue
            if exercise is None:
                return True
            first = node.args[0] if node.args else next((k.value for k in node.keywords if k.arg == "exercise"), None)
            if isinstance(first, ast.Constant) and first.value == exercise:
                return True
            if first is not None and not isinstance(first, ast.Constant):
                return True              # a variable: the receipt's own exercise name decides
    return False


def _count(cell):
    n = cell.get("execution_count")
    return n if isinstance(n, int) and not isinstance(n, bool) else None


def _norm(src: str) -> str:
    return "\n".join(line.rstrip() for line in src.strip().splitlines())


def _notebook_calls_before_lock(nb, release, exercise: str) -> dict:
    """For each cell of ``nb`` that is one of the release's own cells placed before the release's
    lock cell (the same cell id, or the same text), the experiment calls the release gave it."""
    if release is None:
        return {}
    rcells = release.cells
    lock_at = next((i for i, c in enumerate(rcells) if cellcode.gid(c) == f"{exercise}_prediction"), None)
    if lock_at is None:
        return {}
    before = [c for c in rcells[:lock_at] if c.cell_type == "code"]
    by_id = {c.get("id"): c for c in before if c.get("id")}
    by_text = {_norm(cellcode.source(c)): c for c in before}
    allowed = {}
    for i, cell in enumerate(nb.cells):
        if cell.get("cell_type") != "code":
            continue
        twin = by_text.get(_norm(cellcode.source(cell))) or by_id.get(cell.get("id"))
        if twin is not None:
            allowed[i] = cellcode.top_level_calls(cellcode.parse(cellcode.source(twin))) & EXPERIMENTS[exercise]
    return allowed


def receipt_verdict(nb, exercise: str, release=None) -> tuple[bool, str]:
    """(earned, the line for report.csv and the feedback) for ``exercise``'s completion point.

    ``release``: the release version of the notebook, to know which cells the notebook itself
    places before the lock (module doc, rule 4)."""
    ex = exercise
    cells = [c if isinstance(c, dict) else {} for c in nb.cells]
    trees = {i: cellcode.parse(cellcode.source(c)) for i, c in enumerate(cells) if c.get("cell_type") == "code"}
    lock_cells = [i for i, t in trees.items() if _calls_to(t, "lock_prediction", ex)]
    if not lock_cells:               # the prediction cell, or a copy of it, locks this exercise
        return False, f"{ex}: the prediction cell (with lock_prediction) is missing or no longer locks"
    run_cells = [i for i, t in trees.items() if _calls_to(t, "run_exercise", ex)]
    stray = [i + 1 for i, c in enumerate(cells)
             if (i not in lock_cells and i not in run_cells and ANY_RECEIPT.search(_all_output_text(c)))
             or (c.get("cell_type") != "code" and ANY_RECEIPT.search(cellcode.source(c)))]
    note = (f"; receipt-like text in cell(s) {', '.join(map(str, stray))} was ignored: only the receipts "
            f"printed by lock_prediction and run_exercise count") if stray else ""

    locks = [(i, m) for i in lock_cells for m in map(LOCK_RE.search, _stdout(cells[i])) if m and m["ex"] == ex]
    if not locks:
        return False, f"{ex}: no prediction receipt in the output of your prediction cell (run it){note}"
    if any(line.startswith(WARNING) and f" {ex}:" in line for i in lock_cells for line in _stdout(cells[i])):
        return False, f"{ex}: your prediction cell says the experiment had already run when it locked{note}"
    runs = [(i, m) for i in run_cells for m in map(RUN_RE.search, _stdout(cells[i])) if m and m["ex"] == ex]
    if not runs:
        return False, f"{ex}: no experiment receipt in your notebook (run the experiment cell){note}"
    try:
        lock_times = {i_m: datetime.fromisoformat(i_m[1]["at"]) for i_m in locks}
        run_times = {i_m: (datetime.fromisoformat(i_m[1]["at"]), datetime.fromisoformat(i_m[1]["locked"]))
                     for i_m in runs}
    except ValueError:
        return False, f"{ex}: the receipts are unreadable (were they edited?){note}"
    try:
        pairs = [(lk, rn) for rn, (started, quoted) in run_times.items() for lk, at in lock_times.items()
                 if at == quoted]
        # the same millisecond is in order: run_exercise prints its receipt only once a lock exists
        in_order = [(lk, rn) for lk, rn in pairs if run_times[rn][1] <= run_times[rn][0]]
    except TypeError:                # a time without its zone beside one with it
        return False, f"{ex}: the receipts are unreadable (were they edited?){note}"
    if not pairs:
        return False, (f"{ex}: the experiment used a prediction that this notebook's prediction cell never "
                       f"showed (was the prediction locked again after the experiment? then run the "
                       f"experiment cell again){note}")
    if not in_order:
        return False, f"{ex}: the experiment ran before the prediction was locked{note}"
    (li, lock), (ri, run) = in_order[0]
    n_lock, n_run = _count(cells[li]), _count(cells[ri])
    if n_lock is None or n_run is None:
        return False, (f"{ex}: the receipts are there but the cells have no execution record (were the "
                       f"outputs pasted in?){note}")
    counts = [_count(c) for c in cells if c.get("cell_type") == "code" and _count(c) is not None]
    one_session = len(counts) == len(set(counts))    # a count seen twice: a restart in between
    if not lock["again"] and n_lock < n_run and one_session:       # the counts place the lock: rule 4
        allowed = _notebook_calls_before_lock(nb, release, ex)
        early = [f"In [{_count(cells[i])}]" for i, t in trees.items()
                 if i not in lock_cells and i not in run_cells and _count(cells[i]) is not None
                 and _count(cells[i]) < n_lock
                 and cellcode.top_level_calls(t) & EXPERIMENTS[ex] - allowed.get(i, set())]
        if early:
            return False, (f"{ex}: the experiment's functions ran directly ({', '.join(early)}) before the "
                           f"prediction was locked{note}")
    return True, f"{ex}: prediction locked at {run['locked']}, experiment ran at {run['at']}: in order{note}"
