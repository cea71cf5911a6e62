"""Grading a hostile class: no cheat gains a point, no student reads or changes another's work,
nothing survives the batch, and honest-but-unusual submissions get every point they earn.

The class is ``autograde/classes/hostile.py`` (one student per attack or oddity, each described in
its ``STUDENTS``), graded with the instructor's one command beside a correct student, with real
nbgrader, its sqlite gradebook and the bubblewrap sandbox.
"""

import csv
import re
import secrets
import unicodedata
from pathlib import Path

import pytest

from autograde import grade, sandbox
from autograde.course import ASSIGNMENT, COURSE_ID, NOTEBOOKS
from autograde.classes.hostile import STUDENTS, write_zip
from autograde.classes.synthetic import build as synthetic

ROOT = Path(__file__).resolve().parents[1]


TIMEOUT = 30
IDS = {"Ann Lee": "Ann_Lee"}          # the folder-safe form of LMS ids (intake.normalise_student_id)
LEASED: list = []                     # the uids the class's grading run leased (sandbox.recording_leases)


@pytest.fixture(scope="module")
def hostile(executed_solutions, tmp_path_factory):
    executed = executed_solutions
    ok, why = sandbox.available()
    if not ok:
        pytest.skip(f"no sandbox on this machine ({why}); .ci/run installs bubblewrap")
    tmp = tmp_path_factory.mktemp("hostile")
    course = tmp / "course"
    course.mkdir()
    token = secrets.token_hex(16)
    canary = course / "instructor_only.txt"
    canary.write_text(f"CANARY {token}\n")
    perfect = {k: v for k, v in synthetic(executed).items() if k.startswith("perfect_")}
    subs = write_zip(tmp / "class.zip", executed, canary=str(canary), extra=perfect)
    with sandbox.recording_leases() as leased:
        report = grade.grade_class(subs, course, timeout=TIMEOUT, log=print)
    LEASED[:] = leased
    return course, report, token, tmp


def scores(course, student, notebook):
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        try:
            return {g.name: g.score for g in gb.find_submission_notebook(notebook, ASSIGNMENT, student).grades}
        except MissingEntry:
            return None


def all_text(course, student):
    folder = course / "autograded" / student / ASSIGNMENT
    fb = course / "feedback" / student / ASSIGNMENT
    return "".join(p.read_text(errors="replace") for d in (folder, fb) if d.exists() for p in d.iterdir())


def outputs(course, student):
    """What the student's cells printed when the grader ran them (not their source)."""
    import nbformat

    text = []
    for path in (course / "autograded" / student / ASSIGNMENT).glob("*.ipynb"):
        for cell in nbformat.read(path, as_version=4).cells:
            for o in cell.get("outputs", []):
                text.append(o.get("text", "") + o.get("evalue", "") + o.get("ename", ""))
    return "\n".join(text)


@pytest.mark.parametrize("student", sorted(s for s, (_, pts) in STUDENTS.items() if pts is not None))
def test_every_student_gets_exactly_what_their_answer_earns(hostile, student):
    course, report, _, _ = hostile
    sid = IDS.get(student, unicodedata.normalize("NFC", student))
    what, expected = STUDENTS[student]
    got = scores(course, sid, "02_reward")
    assert got is not None, f"{student} ({what}) was not graded: {report.get(sid)}"
    assert got["reward_impl_tests"] == expected, (student, what, report[sid]["verdicts"], report[sid]["notes"])


def test_the_perfect_student_is_untouched_by_the_class(hostile):
    course, report, _, _ = hostile
    got = {nb: scores(course, "perfect", nb) for nb in ("02_reward", "03_imagination_actor", "04_imagination_gap")}
    assert got["02_reward"]["reward_impl_tests"] == 4
    assert got["03_imagination_actor"]["lambda_return_impl_tests"] == 4
    assert got["04_imagination_gap"]["dream_impl_tests"] == 3 and got["04_imagination_gap"]["ex1_order"] == 1
    assert scores(course, "perfect", "05_horizon")["ex2_order"] == 1


def test_no_score_outside_its_range_and_grades_csv_equals_the_gradebook(hostile):
    from nbgrader.api import Gradebook

    course, report, _, _ = hostile
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for s in report:
            for nb in NOTEBOOKS:
                for g in (scores(course, s, nb[:-6]) or {}).values():
                    assert g is None or 0 <= g <= 4
        totals = {s.id: 0.0 for s in gb.students}          # a student with nothing graded scores 0
        totals.update({s.student.id: s.score for s in gb.assignment_submissions(ASSIGNMENT)})
    text = (course / "grades.csv").read_text()
    assert "hacked" not in text
    rows = {r["student_id"]: float(r["raw_score"]) for r in csv.DictReader(text.splitlines())}
    assert rows == pytest.approx(totals)
    assert not (course / "manual_grades.csv").exists()


def test_nobody_read_the_course(hostile):
    course, report, token, _ = hostile
    out = outputs(course, "snoop")
    assert "SEEN" in out and "LIST" in out, f"the snooping cell did not run to the end:\n{out[-2000:]}"
    assert "FOUND" not in out and out.count("DENIED") == 3
    assert "files; []" in out, "the kernel could see course files: " + out[out.index("SEEN"):][:500]
    assert token not in all_text(course, "snoop")


def test_nothing_survives_the_batch(hostile, leftovers, processes_of):
    """No process runs as a uid this run leased, but under a grading task that holds it now: another
    grading run on this machine (any other uid of the range, or these after this run gave them
    back) is none of this run's business (conftest.leftovers_of)."""
    import os

    if os.geteuid() != 0:
        pytest.skip("grading as a non-root user runs kernels as that user: no student uid is leased")
    assert LEASED, "the run leased no uid"
    others = processes_of(set(sandbox.STUDENT_UIDS))
    print(f"this run leased uids {sorted(set(LEASED))}; processes of other grading runs in the student uid "
          f"range now: {len(others)}")
    assert not leftovers(LEASED)


def test_no_network_and_limits_hold(hostile):
    course, report, _, _ = hostile
    out = outputs(course, "network")
    assert "NET OPEN" not in out and out.count("no network:") == 3
    # the fork bomb runs into its process limit; the kernel it shares that limit with may go down
    # with it, which costs only what had not run yet (its test points are checked above)
    assert any("points from the tests that had already run are kept" in n or "stopped after" in n
               for n in report["forkbomb"]["notes"]) or "stopped after" in outputs(course, "forkbomb")


def test_feedback_pages_are_capped(hostile):
    course, _, _, _ = hostile
    page = course / "feedback" / "bigout" / ASSIGNMENT / "02_reward.html"
    assert page.exists() and page.stat().st_size < 3_000_000
    # the graded copy keeps 2 MiB of the 25 MB line (outputs.py), and the page says what it left out
    assert re.search(r"\[output truncated: 2\d\.\d MB of output not shown\]", page.read_text())


def test_delegating_to_the_package_is_explained(hostile):
    _, report, _, _ = hostile
    for s in ("delegate", "delegate2"):
        msg = report[s]["verdicts"]["reward_impl_tests"][2]
        assert "write it yourself" in msg or "must compute the result itself" in msg


@pytest.mark.parametrize("student", ["receiptprint", "receiptedit", "alreadylocked", "pipelinefirst"])
def test_forged_receipts_earn_no_completion_point(hostile, student):
    course, report, _, _ = hostile
    assert scores(course, student, "04_imagination_gap")["ex1_order"] == 0
    assert not report[student]["completion"]["ex1"][0]


def test_the_planner_run_before_the_lock_costs_exercise_4s_completion_point_only(hostile):
    course, report, _, _ = hostile
    got = scores(course, "plannerfirst", "07_planning")
    assert got["ex4_order"] == 0 and got["cem_update_impl_tests"] == 4, got
    ok, why = report["plannerfirst"]["completion"]["ex4"]
    assert not ok and "ran directly" in why, why


def test_the_kernel_dying_keeps_the_points_already_earned_with_a_note(hostile):
    _, report, _, _ = hostile
    assert any("points from the tests that had already run are kept" in n for n in report["diesafter"]["notes"])


def test_unusual_uploads_and_ids(hostile):
    course, report, _, tmp = hostile
    assert any("(1)" in n for n in report["reupload"]["notes"])
    chloe = [s for s in report if unicodedata.normalize("NFC", s) == unicodedata.normalize("NFC", "Chloé")]
    assert len(chloe) == 1 and scores(course, chloe[0], "03_imagination_actor")["lambda_return_impl_tests"] == 4
    assert not {"..", "/", "escape", "rooted", "mallory"} & set(report) or not scores(course, "mallory", "02_reward")
    assert not list(tmp.glob("escape*")) and not Path("/abs").exists()
    rejected = (course / "report.csv").read_text()
    assert "escape_02_reward" in rejected and "mallory" in rejected
    assert "perfect" in report and scores(course, "perfect", "02_reward")["reward_impl_tests"] == 4


def test_results_a_kernel_forges_or_rebinds_earn_nothing(hostile):
    # the verdicts come from the probe process (autograde/probe.py): what a kernel writes is not read
    _, report, _, _ = hostile
    for s in ("forgeresults", "stackref", "probekill"):
        assert report[s]["verdicts"]["reward_impl_tests"][0] == 0, report[s]["verdicts"]
    assert "ReferenceRefused" in report["stackref"]["verdicts"]["reward_impl_tests"][2]


def test_a_copy_of_the_answer_key_keeps_its_points_and_is_flagged(hostile):
    _, report, _, _ = hostile
    assert any("answer key, for the instructor" in n and "pusht.reward.reward_from_obs" in n
               for n in report["answerkey"]["notes"]), report["answerkey"]["notes"]
    assert report["answerkey"]["verdicts"]["reward_impl_tests"][0] == 4


def test_no_file_outside_a_sandbox_changes_and_the_course_holds_only_what_the_grader_wrote(hostile):
    import os
    import stat

    course, report, token, tmp = hostile
    assert (course / "instructor_only.txt").read_text() == f"CANARY {token}\n"
    assert "LINKFARM made" in outputs(course, "linkfarm")
    # the kernel's sockets folder is root's before its first cell runs (sandbox.lock_sockets)
    assert "SOCKETS LOCKED" in outputs(course, "linkfarm") and "SOCKETS WRITABLE" not in outputs(course, "linkfarm")
    for root, dirs, files in os.walk(course):
        for name in dirs + files:
            st = os.lstat(os.path.join(root, name))
            assert stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode), os.path.join(root, name)
    for student in ("linkfarm", "diskfill", "forgeresults"):
        left = {p.name for p in (course / "autograded" / student / ASSIGNMENT).iterdir()}
        assert left <= {"02_reward.ipynb", "timestamp.txt"}, (student, left)
    assert (course / "feedback" / "linkfarm" / ASSIGNMENT / "02_reward.html").is_file()


def test_one_poisoned_student_leaves_every_other_students_outputs_intact(hostile):
    course, report, _, _ = hostile
    for name in ("grades.csv", "report.csv", "gradebook.db"):
        assert (course / name).is_file()
    for s in report:
        graded = course / "autograded" / s / ASSIGNMENT
        for nb in graded.glob("*.ipynb") if graded.is_dir() else []:
            # a page for every graded notebook, huge outputs cut (outputs.py); only a page that took too
            # long to make is skipped, with a note
            assert (course / "feedback" / s / ASSIGNMENT / f"{nb.stem}.html").is_file() or \
                any("no feedback pages" in n for n in report[s]["notes"]), (s, nb.name)


def test_disk_and_tmpfs_use_is_capped(hostile):
    import re

    course, _, _, _ = hostile
    out = outputs(course, "diskfill")
    full = {w: int(mb) for w, mb in re.findall(r"FULL (\S+) (\d+) MB", out)}
    assert set(full) == {".", "/tmp"}, out[-500:]
    assert full["."] <= sandbox.DEFAULT_LIMITS["work_bytes"] >> 20
    assert full["/tmp"] <= sandbox.DEFAULT_LIMITS["tmp_bytes"] >> 20


def test_the_graders_memory_stays_bounded_whatever_a_kernel_prints(hostile):
    import resource

    course, report, _, _ = hostile
    # the flood ran into the worker's memory cap or the cell timeout; either way only its own notebook
    # is touched, and its reward test keeps the points its function earns
    assert report["flood"]["verdicts"]["reward_impl_tests"][0] == 4
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss << 10          # bytes (Linux reports KiB)
    assert peak < 3 << 30, peak


def test_feedback_pages_hold_no_script(hostile):
    from html.parser import HTMLParser

    course, _, _, _ = hostile
    found = []

    class Scan(HTMLParser):
        def handle_starttag(self, tag, attrs):
            if tag in ("script", "iframe", "object", "embed", "base"):
                found.append(tag)
            found.extend(f"{tag}[{k}]" for k, v in attrs if k.startswith("on") or "javascript:" in (v or "").lower())

    page = (course / "feedback" / "xss" / ASSIGNMENT / "02_reward.html").read_text()
    Scan().feed(page)
    assert not found, found
    assert "Content-Security-Policy" in page


def test_without_a_sandbox_grading_runs_and_warns(tmp_path, monkeypatch):
    import zipfile

    monkeypatch.setattr(sandbox, "available", lambda: (False, "bubblewrap is not installed"))
    course = tmp_path / "course"
    course.mkdir()
    with zipfile.ZipFile(tmp_path / "class.zip", "w") as zf:   # one student, whose one file runs nothing
        zf.writestr("s1_02_reward.ipynb", "not notebook JSON")
    lines = []
    with pytest.warns(UserWarning, match="NOT confined"):
        grade.grade_class(tmp_path / "class.zip", course, log=lines.append)
    assert any("NOT confined" in line and "bubblewrap is not installed" in line for line in lines)
    # and its guarantees, first, say that none held (autograde/guarantees.py)
    assert any(line.startswith("guarantees of this run: 5 of 5 NOT held") for line in lines)
    run = [r["notes"] for r in csv.DictReader(open(course / "report.csv", newline="")) if r["student_id"] == "(this run)"]
    assert len(run) == 5 and all(": NOT HELD: " in n for n in run) and "hidden tests" in run[0]
