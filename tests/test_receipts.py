"""Completion points from what the learner did (autograde/receipts.py).

The receipts' times and the lock the experiment quotes decide the order; the execution counts are
one piece of evidence, used where they can place the lock. Each test edits the record of the
instructor's own executed notebooks the way a learner's session (a restart, a re-run, another
front-end) or a cheat changes it; tests/test_honest_class.py grades really executed variants.
"""

import copy
import re
from pathlib import Path

import nbformat
import pytest

from autograde import cellcode
from autograde import receipts
from autograde.course import EXERCISES            # {"ex1": "04_imagination_gap", ..., "ex4": "07_planning"}

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def handed_in(executed_solutions):
    executed = executed_solutions
    out = {}
    for ex, name in EXERCISES.items():
        nb = nbformat.read(executed / f"{name}.ipynb", as_version=4)
        nb.cells = [c for c in nb.cells if "injected-parameters" not in c.metadata.get("tags", [])]
        out[ex] = nb
    return out


def release(ex):
    return nbformat.read(ROOT / "notebooks" / f"{EXERCISES[ex]}.ipynb", as_version=4)


def verdict(nb, ex):
    return receipts.receipt_verdict(nb, ex, release(ex))


def lock_cell(nb, ex):
    return next(c for c in nb.cells if cellcode.gid(c) == f"{ex}_prediction")


def run_cell(nb, ex):
    return next(c for c in nb.cells if f'run_exercise("{ex}"' in cellcode.source(c))


def insert_ran_before(nb, ex, src):
    """``src`` as a new cell placed and run just before the lock, the counts after it moved up."""
    nb = copy.deepcopy(nb)
    lock = lock_cell(nb, ex)
    n = lock.execution_count
    for c in nb.cells:
        if c.cell_type == "code" and isinstance(c.execution_count, int) and c.execution_count >= n:
            c.execution_count += 1
    cell = nbformat.v4.new_code_cell(src, execution_count=n)
    nb.cells.insert(nb.cells.index(lock), cell)
    return nb


@pytest.mark.parametrize("ex", sorted(EXERCISES))
def test_the_instructors_solutions_earn_the_point(handed_in, ex):
    ok, why = verdict(handed_in[ex], ex)
    assert ok, why
    assert "ignored" not in why


def test_a_cell_the_notebook_places_before_the_lock_is_not_a_peek(handed_in):
    """Notebook 06 runs round 0 with `run` before its prediction by design."""
    nb = handed_in["ex3"]
    n_lock = lock_cell(nb, "ex3").execution_count
    baseline = [c for c in nb.cells if c.cell_type == "code" and "run(" in cellcode.source(c)
                and c.execution_count < n_lock]
    assert baseline, "06 no longer runs a pipeline before its lock: this test checks nothing"
    assert verdict(nb, "ex3")[0]
    # the same cell, edited by the learner to run the loop itself, is a peek
    edited = copy.deepcopy(nb)
    cell = next(c for c in edited.cells if cellcode.source(c) == cellcode.source(baseline[0]))
    cell.source += "\npeek = loop.run_loop(cfg, cache_dir=CACHE, model_cache=CACHE)\n"
    ok, why = verdict(edited, "ex3")
    assert not ok and "ran directly" in why


@pytest.mark.parametrize("ex", sorted(EXERCISES))
def test_the_learners_own_call_to_an_experiment_function_before_the_lock_costs_the_point(handed_in, ex):
    for name in sorted(receipts.EXPERIMENTS[ex]):
        nb = insert_ran_before(handed_in[ex], ex, f"peek = {name}(cfg)\n")
        ok, why = verdict(nb, ex)
        assert not ok and "ran directly" in why, (name, why)
        later = copy.deepcopy(nb)           # the same call after the lock is the learner's business
        early = next(c for c in later.cells if cellcode.source(c) == f"peek = {name}(cfg)\n")
        early.execution_count = max(c.get("execution_count") or 0 for c in later.cells) + 1
        assert verdict(later, ex)[0], name


@pytest.mark.parametrize("ex", sorted(EXERCISES))
def test_a_restart_after_the_lock_keeps_the_point(handed_in, ex):
    """Lock, restart, run the rest without the lock cell: the counts start again at 1, so the lock
    cell carries a larger count than the experiment; its receipt and the lock the experiment
    quotes say the lock came first."""
    nb = copy.deepcopy(handed_in[ex])
    lock = lock_cell(nb, ex)
    after = [c for c in nb.cells if c.cell_type == "code" and c is not lock]
    for k, c in enumerate(after, start=1):
        c.execution_count = k
    assert run_cell(nb, ex).execution_count <= lock.execution_count
    assert verdict(nb, ex)[0], verdict(nb, ex)[1]


@pytest.mark.parametrize("ex", sorted(EXERCISES))
def test_running_the_lock_cell_again_afterwards_keeps_the_point(handed_in, ex):
    nb = copy.deepcopy(handed_in[ex])
    lock = lock_cell(nb, ex)
    m = next(filter(None, map(receipts.LOCK_RE.match, receipts._stdout(lock))))
    lock.outputs = [nbformat.v4.new_output("stream", name="stdout", text=(
        f"[prediction already locked] {ex}: ({m['choice']}) at {m['at']}; the first lock is kept\n"))]
    lock.execution_count = max(c.get("execution_count") or 0 for c in nb.cells) + 1
    assert verdict(nb, ex)[0]


@pytest.mark.parametrize("ex", sorted(EXERCISES))
def test_receipts_cut_into_several_outputs_still_count(handed_in, ex):
    """Front-ends and kernels cut printed text into messages (VS Code saves one output per
    line; a flush can fall inside a line)."""
    nb = copy.deepcopy(handed_in[ex])
    for cell in (lock_cell(nb, ex), run_cell(nb, ex)):
        text = "".join(o["text"] for o in cell.outputs if o.get("output_type") == "stream")
        cut = text.index(" at ") + 2
        cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=t) for t in (text[:cut], text[cut:])]
    assert verdict(nb, ex)[0]


def test_a_magic_on_the_experiment_cell_is_still_the_experiment_cell(handed_in):
    nb = copy.deepcopy(handed_in["ex1"])
    cell = run_cell(nb, "ex1")
    cell.source = "%%time\n" + cellcode.source(cell)
    assert verdict(nb, "ex1")[0]


def test_records_that_do_not_show_the_lock_first_cost_the_point(handed_in):
    base = handed_in["ex1"]

    def edited(edit):
        nb = copy.deepcopy(base)
        edit(nb)
        return verdict(nb, "ex1")

    def relocked_later(nb):            # locked again after the experiment (the store deleted)
        lock = lock_cell(nb, "ex1")
        for o in lock.outputs:
            o["text"] = re.sub(r"at \S+", "at 2099-01-01T00:00:00.000+00:00", o["text"], count=1)
    ok, why = edited(relocked_later)
    assert not ok and "never showed" in why

    def started_first(nb):
        run = run_cell(nb, "ex1")
        for o in run.outputs:
            if "text" in o:
                o["text"] = re.sub(r"started\] ex1 at \S+", "started] ex1 at 2000-01-01T00:00:00.000+00:00", o["text"])
    ok, why = edited(started_first)
    assert not ok and "before the prediction was locked" in why

    def pasted(nb):
        for c in nb.cells:
            if c.cell_type == "code":
                c.execution_count = None
    ok, why = edited(pasted)
    assert not ok and "no execution record" in why

    def printed_elsewhere(nb):         # the receipts moved into a print cell
        lock, run = lock_cell(nb, "ex1"), run_cell(nb, "ex1")
        text = receipts._stdout(lock) + receipts._stdout(run)
        lock.outputs, run.outputs = [], []
        nb.cells.append(nbformat.v4.new_code_cell(f"print({chr(10).join(text)!r})", execution_count=99,
                                                  outputs=[nbformat.v4.new_output("stream", name="stdout",
                                                                                  text="\n".join(text) + "\n")]))
    ok, why = edited(printed_elsewhere)
    assert not ok and "was ignored" in why


def test_a_malformed_hand_in_gets_a_verdict_never_an_exception(handed_in):
    """Whatever a front-end or a hand edit left in the JSON, the grader answers and goes on."""
    odd_outputs = [{"output_type": "display_data", "data": {"application/json": [1, 2, 3]}},
                   {"output_type": "error", "ename": "E", "evalue": None, "traceback": None},
                   {"output_type": "stream", "name": "stdout", "text": [1, None, "x\r\n"]}, "not an output"]
    for ex in sorted(EXERCISES):
        nb = copy.deepcopy(handed_in[ex])
        nb.cells += [nbformat.from_dict({"cell_type": "code", "source": None, "metadata": {"nbgrader": "x"},
                                         "outputs": odd_outputs, "execution_count": 3.0}),
                     nbformat.from_dict({"cell_type": "code", "source": "1" + "+1" * 5000, "metadata": {},
                                         "outputs": [], "execution_count": None})]
        assert verdict(nb, ex)[0]
        naive = copy.deepcopy(handed_in[ex])          # a time without its zone beside one with it
        for o in lock_cell(naive, ex).outputs:
            o["text"] = re.sub(r"(at \S+?)\+00:00", r"\1", o["text"], count=1)
        assert verdict(naive, ex)[0] is False
