"""A function the kernel ran that the grader could not run again is never a silent 0
(autograde/tripwire.py): the score stays 0 until the instructor decides, and report.csv, the class
report, the LMS import files and the student's own page say so. It fires on no honest hand-in
(tests/test_honest_class.py, tests/test_honest_variants.py)."""

import csv
import zipfile
from pathlib import Path

import nbformat
import pytest

from autograde import checks, grade, sandbox, tripwire
from autograde.cellcode import gid

ROOT = Path(__file__).resolve().parents[1]


def executed(test_id: str, error: bool = False, run: bool = True) -> str:
    cell = nbformat.v4.new_code_cell("pass")
    cell.metadata["nbgrader"] = {"grade_id": test_id, "grade": True, "points": 4}
    cell.execution_count = 3 if run else None
    if error:
        cell.outputs = [nbformat.v4.new_output("error", ename="AssertionError", evalue="", traceback=[])]
    return nbformat.writes(nbformat.v4.new_notebook(cells=[cell]))


def verdict(kind: str, errors=()) -> dict:
    return {"test_id": "reward_impl_tests", "passed": kind == "passed", "message": "m", "kind": kind,
            "errors": list(errors)}


def test_the_kernel_ran_the_test_cell_when_it_ran_to_its_end():
    assert tripwire.kernel_ran(executed("reward_impl_tests"), "reward_impl_tests")
    assert not tripwire.kernel_ran(executed("reward_impl_tests", error=True), "reward_impl_tests")
    assert not tripwire.kernel_ran(executed("reward_impl_tests", run=False), "reward_impl_tests")
    assert not tripwire.kernel_ran(executed("other"), "reward_impl_tests")
    assert not tripwire.kernel_ran("not json", "reward_impl_tests")


@pytest.mark.parametrize("kind,errors,fires", [
    ("undefined", [], True), ("timeout", [], True), ("unchecked", [], True),
    ("raised", ["NameError: name 'SCALES' is not defined"], True),
    ("raised", ["ModuleNotFoundError: No module named 'mine'"], True),
    ("raised", ["RuntimeError: shape mismatch"], False),       # the function's own failure
    ("wrong", [], False), ("toolarge", [], False), ("delegation", [], False), ("passed", [], False)])
def test_the_wire_fires_only_where_the_probe_could_not_define_or_run_it(kind, errors, fires):
    assert bool(tripwire.reason(verdict(kind, errors), True)) is fires
    assert tripwire.reason(verdict(kind, errors), False) is None      # the kernel failed too: a real 0


def test_the_judge_says_why_in_one_word():
    test = checks.REWARD
    n = len(test.cases)
    undefined = {"fresh": 1, "status": "ok", "setup": [],
                 "results": ["`reward_from_obs` is not defined by the cells above the test cell"] * n}
    assert checks.judge(test, undefined).kind == "undefined"
    raised = dict(undefined, results=["NameError: name 'SCALES' is not defined"] * n)
    v = checks.judge(test, raised)
    assert v.kind == "raised" and v.errors == ["NameError: name 'SCALES' is not defined"]
    assert checks.judge(test, dict(undefined, status="timeout")).kind == "timeout"
    assert checks.judge(test, None).kind == "not_probed"


# --- end to end: one honest student, one whose function the probe cannot define again ---------------
# The constant is computed at the top level with the package's own reward, which the probe process
# does not have (its implementations raise): the kernel runs the function, the probe cannot.
UNRECREATABLE = '''
import pusht.reward as _package
_ZERO = _package.reward_from_obs(torch.zeros(1, 6), torch.zeros(6), torch.ones(6))[0].sum().item() * 0.0


def reward_from_obs(norm_obs, mean, std):
    obs = norm_obs * std + mean
    pos_err = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang_err = torch.atan2(obs[..., 4], obs[..., 5]).abs()
    reward = -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE) + _ZERO
    return reward, pos_err, ang_err
'''


@pytest.mark.slow                  # grades in the sandbox
@pytest.mark.skipif(not sandbox.available()[0], reason="no sandbox here")
def test_an_unrecreatable_function_is_flagged_everywhere_and_the_instructor_decides(tmp_path):
    from autograde import manual_grade

    sol = nbformat.read(ROOT / "solutions" / "02_reward.ipynb", as_version=4)
    odd = nbformat.read(ROOT / "solutions" / "02_reward.ipynb", as_version=4)
    for cell in odd.cells:
        if gid(cell) == "reward_impl":
            cell.source = UNRECREATABLE
    subs = tmp_path / "class.zip"
    with zipfile.ZipFile(subs, "w") as zf:
        zf.writestr("ann_02_reward.ipynb", nbformat.writes(sol))
        zf.writestr("ben_02_reward.ipynb", nbformat.writes(odd))
    course = tmp_path / "course"
    course.mkdir()
    report = grade.grade_class(subs, course, timeout=60, log=print)

    assert not report["ann"].get("tripwires"), report["ann"]
    assert report["ann"]["verdicts"]["reward_impl_tests"][0] == 4
    wires = report["ben"].get("tripwires")
    assert wires and "reward_impl_tests" in wires[0] and "instructor" in wires[0], report["ben"]
    assert report["ben"]["verdicts"]["reward_impl_tests"][0] == 0           # not final, but 0 until decided
    rows = {r["student_id"]: r for r in csv.DictReader(open(course / "report.csv", newline=""))}
    assert "NEEDS A HUMAN" in rows["ben"]["notes"] and "NEEDS A HUMAN" not in rows["ann"]["notes"]
    page = (course / "class_report.html").read_text()
    assert "grader could not run it" in page
    fb = (course / "feedback" / "ben" / "ch3.2" / "02_reward.html").read_text() \
        if (course / "feedback" / "ben" / "ch3.2").is_dir() else \
        next((course / "feedback" / "ben").rglob("02_reward.html")).read_text()
    assert "your instructor has been told" in fb

    # the instructor decides; the next run keeps the decision and the wire is down
    manual_grade.set_manual_grade("ben", "02_reward", "reward_impl_tests", 4.0, "ran in the notebook", course=course)
    again = grade.grade_class(subs, course, timeout=60, log=print)
    assert not again["ben"].get("tripwires"), again["ben"]
    assert again["ben"]["verdicts"]["reward_impl_tests"][0] == 4
