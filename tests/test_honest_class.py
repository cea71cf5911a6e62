"""Grading is fair to every honest student: the honest class (autograde/classes/honest.py), hand-ins
made the way learners make them and really executed, each earns every point the instructor's own
solutions earn, completion points included; graded as one class, and as two grading runs at the
same time on this machine (two `grade.py` processes), the scores are the same.
"""

import csv
import subprocess
import sys
import unicodedata
import zipfile
from pathlib import Path

import nbformat
import pytest

from autograde import answer_key, checks, grade
from autograde.course import ASSIGNMENT, COURSE_ID, EXERCISES
from autograde.classes import honest as honest_class

ROOT = Path(__file__).resolve().parents[1]


TIMEOUT = 60
# the functions whose instructor's answer is, statement for statement, the package's own
KEY_EQUALS_ANSWER = {t.function for t in checks.TESTS.values()
                     if answer_key.copies(nbformat.read(ROOT / "solutions" / f"{t.notebook}.ipynb", as_version=4).cells, t)}


@pytest.fixture(scope="module")
def honest(executed_solutions, tmp_path_factory):
    executed = executed_solutions
    tmp = tmp_path_factory.mktemp("honest")
    subs = honest_class.write_zip(tmp / "class.zip", executed, tmp / "learners")
    course = tmp / "course"
    course.mkdir()
    report = grade.grade_class(subs, course, timeout=TIMEOUT, log=print)
    return course, report, subs, tmp


def gradebook(course) -> dict:
    """{student: {notebook: {grade cell: score}}} from the course's sqlite gradebook."""
    from nbgrader.api import Gradebook

    out = {}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for sub in gb.assignment_submissions(ASSIGNMENT):
            out[sub.student.id] = {nb.name: {g.name: g.score for g in nb.grades} for nb in sub.notebooks}
    return out


def max_scores(course) -> dict:
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        a = gb.find_assignment(ASSIGNMENT)
        return {nb.name: {c.name: c.max_score for c in [*nb.grade_cells, *nb.task_cells]} for nb in a.notebooks}


def automatic(scores: dict) -> dict:
    """The points the grader gives by itself: test cells and completion points (the one-sentence
    answers wait for the instructor)."""
    return {nb: {g: s for g, s in cells.items() if g.endswith(("_tests", "_order"))} for nb, cells in scores.items()}


def test_the_instructors_solutions_earn_every_automatic_and_completion_point(honest):
    course, report, _, _ = honest
    got, top = automatic(gradebook(course)["solutions"]), automatic(max_scores(course))
    assert got == top, report["solutions"]
    assert {g for cells in got.values() for g in cells} >= {f"{ex}_order" for ex in EXERCISES}
    assert all(ok for ok, _ in report["solutions"]["completion"].values())


def test_the_tripwire_fires_on_no_honest_hand_in(honest):
    """Every honest function is defined again by the probe as the kernel had it (autograde/recreate.py):
    no verdict of this class needs a human."""
    _, report, _, _ = honest
    fired = {s: r.get("tripwires") for s, r in report.items() if r.get("tripwires")}
    assert not fired, fired


@pytest.mark.parametrize("student", sorted(s for s in honest_class.STUDENTS if s != "solutions"))
def test_every_honest_variant_earns_what_the_solutions_earn(honest, student):
    course, report, _, _ = honest
    sid = unicodedata.normalize("NFC", student)
    book = gradebook(course)
    assert sid in book, (student, report.get(sid))
    assert automatic(book[sid]) == automatic(book["solutions"]), (student, honest_class.STUDENTS[student],
                                                                 report[sid]["verdicts"], report[sid]["notes"])
    notes = " | ".join(n for n in report[sid]["notes"] if "answer key, for the instructor" not in n)
    assert "no credit" not in notes and "for the instructor" not in notes, notes
    # a flag for the instructor where a function is the package's own, names aside (answer_key.py):
    # here only the functions whose instructor's answer is the package's, never a score changed
    flagged = {t.function for t in checks.TESTS.values() for n in report[sid]["notes"]
               if "answer key, for the instructor" in n and f"`{t.function}`" in n}
    assert flagged <= KEY_EQUALS_ANSWER, flagged


def test_look_alike_ids_are_noted_for_both_students(honest):
    course, _, _, _ = honest
    rows = {r["student_id"]: r["notes"] for r in csv.DictReader(open(course / "report.csv", newline=""))}
    a, b = honest_class.LOOKALIKE
    assert "looks like" in rows[a] and b in rows[a], rows[a]
    assert "looks like" in rows[b] and a in rows[b], rows[b]
    assert "looks like" not in rows["solutions"]


SLOW_CHECK = "import time\ntime.sleep(25)   # my own long check, added last and never run\n"


def test_two_runs_graded_at_once_score_as_graded_alone(honest):
    """Two `grade.py` runs on one machine at the same time, each in its own course folder: a regrade
    of one student, and the rest of the class. The one student is the solutions with a slow check
    of the learner's own (a cell that sleeps 25 s before the reward test): while its kernel waits,
    the other run's tasks start and end, with their clean-ups. Every student scores what grading
    alone gives. Before grading runs were isolated, both runs gave task i the uid 61000 + i and a
    task's clean-up killed every process of its uid on the host, so the other run's first clean-up
    killed this student's sleeping kernel."""
    course, _, subs, tmp = honest
    alone = gradebook(course)
    parts = {"one": tmp / "one.zip", "rest": tmp / "rest.zip"}
    with zipfile.ZipFile(subs) as src, zipfile.ZipFile(parts["one"], "w") as one, \
            zipfile.ZipFile(parts["rest"], "w") as rest:
        for m in src.namelist():
            if not m.startswith("solutions_"):
                rest.writestr(m, src.read(m))
                continue
            nb = nbformat.reads(src.read(m).decode(), as_version=4)
            if m.endswith("02_reward.ipynb"):
                tests = next(i for i, c in enumerate(nb.cells) if c.metadata.get("nbgrader", {}).get("grade_id")
                             == "reward_impl_tests")
                nb.cells.insert(tests, nbformat.v4.new_code_cell(SLOW_CHECK))
            one.writestr(m.replace("solutions_", "slow_", 1), nbformat.writes(nb))
    procs = []
    for part, z in parts.items():
        (tmp / f"course_{part}").mkdir()
        procs.append(subprocess.Popen([sys.executable, "-m", "autograde.grade", str(z), "--course",
                                       str(tmp / f"course_{part}"), "--timeout", str(TIMEOUT)],
                                      stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
    outs = [p.communicate(timeout=1800)[0] for p in procs]
    assert all(p.returncode == 0 for p in procs), [o[-3000:] for o in outs]
    together = gradebook(tmp / "course_rest") | gradebook(tmp / "course_one")
    assert sorted(together) == sorted([s for s in alone if s != "solutions"] + ["slow"])
    for student in together:
        expected = alone["solutions" if student == "slow" else student]
        assert automatic(together[student]) == automatic(expected), (student, outs[0][-2000:])
