"""Grading on a Dask cluster gives exactly what grading on this machine gives, and a worker that
dies mid-task loses no student.

A real ``distributed.LocalCluster`` of two worker processes (each started with the course's
``autograde.dask_preload``, as a remote worker would be), real nbgrader, real kernels. The class
is small (three students, five notebooks) so that it is graded three times within a minute or
two: here, on the cluster, and on the cluster with one worker killed while it grades.
"""

import csv
import logging
import os
import signal
import threading
import time
import zipfile
from pathlib import Path

import pytest

from autograde import feedback, grade, schedule
from autograde.course import ASSIGNMENT, COURSE_ID
from autograde.classes.synthetic import build

ROOT = Path(__file__).resolve().parents[1]


STUDENTS = ("perfect", "wrong", "raises")
NOTEBOOKS = ("02_reward", "03_imagination_actor")      # "raises" hands in only 03
TIMEOUT = 120   # seconds per cell, as the grader's default: a loaded machine must not time out a correct cell


@pytest.fixture(scope="module")
def small_class(executed_notebooks, tmp_path_factory):
    executed, errors = executed_notebooks
    if any(errors.values()):
        pytest.skip("a notebook fails on its own; see test_notebooks")
    path = tmp_path_factory.mktemp("dask") / "class.zip"
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in build(executed).items():
            if name.startswith(tuple(f"{s}_" for s in STUDENTS)) and any(nb in name for nb in NOTEBOOKS):
                zf.writestr(name, data)
    return path


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       preload=["autograde.dask_preload"],
                                       silence_logs=logging.ERROR)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def outcome(course: Path) -> dict:
    """What an instructor gets: the gradebook's export, the report and every feedback page."""
    pages = {p.relative_to(course / "feedback").as_posix(): p.read_text()
             for p in sorted((course / "feedback").rglob("*.html"))}
    with open(course / "grades.csv", newline="") as f:
        grades = list(csv.DictReader(f))
    return {"grades.csv": grades, "report.csv": (course / "report.csv").read_text(), "feedback": pages}


@pytest.fixture(scope="module")
def here(small_class, tmp_path_factory):
    course = tmp_path_factory.mktemp("here")
    grade.grade_class(small_class, course, timeout=TIMEOUT, jobs=2, share=False, progress=False)
    return outcome(course)


def test_the_dask_path_gives_the_same_grades_feedback_and_exports(small_class, client, here, tmp_path):
    report = grade.grade_class(small_class, tmp_path, timeout=TIMEOUT, scheduler=client, share=False,
                               progress=False)
    assert sorted(report) == sorted(STUDENTS)
    there = outcome(tmp_path)
    assert sorted(r["student_id"] for r in there["grades.csv"]) == sorted(STUDENTS)
    scores = {r["student_id"]: float(r["raw_score"]) for r in there["grades.csv"]}
    assert scores["perfect"] > scores["wrong"] and scores["perfect"] > scores["raises"]
    assert there["grades.csv"] == here["grades.csv"]
    assert there["report.csv"] == here["report.csv"]
    assert sorted(there["feedback"]) == sorted(here["feedback"]) and len(there["feedback"]) >= 4
    for page in here["feedback"]:
        assert there["feedback"][page] == here["feedback"][page], page


def test_a_worker_killed_mid_task_loses_no_student(small_class, client, here, tmp_path):
    done = {}
    job = threading.Thread(target=lambda: done.update(report=grade.grade_class(
        small_class, tmp_path, timeout=TIMEOUT, scheduler=client, share=False, progress=False)))
    job.start()
    killed = None
    deadline = time.monotonic() + 120
    while killed is None and time.monotonic() < deadline and job.is_alive():
        busy = {w: keys for w, keys in client.processing().items() if any("grade-" in str(k) for k in keys)}
        if busy:
            time.sleep(3)                           # let it get well into the notebooks
            victim = next(iter(busy))
            pid = client.run(os.getpid, workers=[victim])[victim]
            os.kill(pid, signal.SIGKILL)
            killed = victim
        time.sleep(0.2)
    job.join(timeout=600)
    assert killed is not None, "no grading task was ever seen running"
    assert not job.is_alive() and "report" in done
    with open(tmp_path / "grades.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted(r["student_id"] for r in rows) == sorted(STUDENTS)      # each student exactly once
    assert rows == here["grades.csv"]                                     # with the right scores
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{tmp_path / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        assert sorted(s.id for s in gb.students) == sorted(STUDENTS)
        assert len(gb.find_assignment(ASSIGNMENT).submissions) == len(STUDENTS)


def test_a_worker_that_cannot_grade_is_named(client, monkeypatch):
    monkeypatch.setattr(schedule, "_worker_can_grade", lambda: "cannot import 'nbgrader'")
    with pytest.raises(RuntimeError, match="cannot import 'nbgrader'.*preload"):
        schedule.run_dask([("someone", ["02_reward.ipynb"])], client, lambda i, t: None, lambda t, o: None)


def test_feedback_joins_the_printed_text_that_the_kernel_happened_to_send_in_pieces():
    piece = lambda name, text: {"output_type": "stream", "name": name, "text": text}  # noqa: E731
    shown = {"output_type": "display_data", "data": {"text/plain": "fig"}, "metadata": {}}
    outs = feedback._coalesce_streams([piece("stdout", "a\n"), piece("stdout", ["b\n", "c\n"]), piece("stderr", "w\n"),
                                    piece("stdout", "d\n"), shown, piece("stdout", "e\n")])
    assert [(o["output_type"], o.get("text")) for o in outs] == [
        ("stream", "a\nb\nc\n"), ("stream", "w\n"), ("stream", "d\n"), ("display_data", None), ("stream", "e\n")]
