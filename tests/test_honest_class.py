"""Grading is fair to every honest student: the honest class (autograde/honest_class.py), hand-ins
made the way learners make them and really executed, each earns every point the instructor's own
solutions earn, completion points included; graded as one class and as two sections graded at the
same time on this machine (two `grade.py` processes), the scores are the same.
"""

import csv
import subprocess
import sys
import unicodedata
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "autograde"))

import grade  # noqa: E402
import honest_class  # noqa: E402

TIMEOUT = 60


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
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=grade.COURSE_ID) as gb:
        for sub in gb.assignment_submissions(grade.ASSIGNMENT):
            out[sub.student.id] = {nb.name: {g.name: g.score for g in nb.grades} for nb in sub.notebooks}
    return out


def max_scores(course) -> dict:
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=grade.COURSE_ID) as gb:
        a = gb.find_assignment(grade.ASSIGNMENT)
        return {nb.name: {c.name: c.max_score for c in [*nb.grade_cells, *nb.task_cells]} for nb in a.notebooks}


def automatic(scores: dict) -> dict:
    """The points the grader gives by itself: test cells and completion points (the one-sentence
    answers wait for the instructor)."""
    return {nb: {g: s for g, s in cells.items() if g.endswith(("_tests", "_order"))} for nb, cells in scores.items()}


def test_the_instructors_solutions_earn_every_automatic_and_completion_point(honest):
    course, report, _, _ = honest
    got, top = automatic(gradebook(course)["solutions"]), automatic(max_scores(course))
    assert got == top, report["solutions"]
    assert {g for cells in got.values() for g in cells} >= {"ex1_order", "ex2_order", "ex3_order"}
    assert all(ok for ok, _ in report["solutions"]["completion"].values())


@pytest.mark.parametrize("student", sorted(s for s in honest_class.STUDENTS if s != "solutions"))
def test_every_honest_variant_earns_what_the_solutions_earn(honest, student):
    course, report, _, _ = honest
    sid = unicodedata.normalize("NFC", student)
    book = gradebook(course)
    assert sid in book, (student, report.get(sid))
    assert automatic(book[sid]) == automatic(book["solutions"]), (student, honest_class.STUDENTS[student],
                                                                 report[sid]["verdicts"], report[sid]["notes"])
    notes = " | ".join(report[sid]["notes"])
    assert "no credit" not in notes and "for the instructor" not in notes, notes


def test_look_alike_ids_are_noted_for_both_students(honest):
    course, _, _, _ = honest
    rows = {r["student_id"]: r["notes"] for r in csv.DictReader(open(course / "report.csv", newline=""))}
    a, b = honest_class.LOOKALIKE
    assert "looks like" in rows[a] and b in rows[a], rows[a]
    assert "looks like" in rows[b] and a in rows[b], rows[b]
    assert "looks like" not in rows["solutions"]


def test_two_sections_graded_at_once_score_as_graded_alone(honest):
    """Two `grade.py` runs on one machine at the same time (two sections of the class, each in its
    own course folder): every student's scores are those of grading the class alone. Before the
    grading runs were isolated, one run's clean-up killed the other's kernels (the same student
    uids in both runs, killed host-wide)."""
    course, _, subs, tmp = honest
    alone = gradebook(course)
    order = sorted(honest_class.STUDENTS)
    sections = {}
    for k, part in enumerate(("a", "b")):
        sections[part] = tmp / f"section_{part}.zip"
        (tmp / f"course_{part}").mkdir()
        with zipfile.ZipFile(subs) as src, zipfile.ZipFile(sections[part], "w") as dst:
            for m in src.namelist():
                student = next(s for s in order if m.startswith(f"{s}_"))
                if order.index(student) % 2 == k:
                    dst.writestr(m, src.read(m))
    procs = [subprocess.Popen([sys.executable, str(ROOT / "autograde" / "grade.py"), str(z),
                               "--course", str(tmp / f"course_{part}"), "--timeout", str(TIMEOUT)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for part, z in sections.items()]
    outs = [p.communicate(timeout=1800)[0] for p in procs]
    assert all(p.returncode == 0 for p in procs), [o[-3000:] for o in outs]
    together = {}
    for part in sections:
        together.update(gradebook(tmp / f"course_{part}"))
    assert sorted(together) == sorted(alone)
    for student in alone:
        assert automatic(together[student]) == automatic(alone[student]), student
