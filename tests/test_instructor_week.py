"""The instructor's week, end to end, once per LMS: download -> grade -> hand grades -> feedback back.

For Canvas, Moodle and Blackboard, a download in that LMS's own layout (``autograde/classes/lms.py``)
of three students who hand in as students do:

* A renamed notebook 02 (``02_reward_final.ipynb``), added a stray notebook (``scratch.ipynb``,
  none of the assignment's) and handed in notebook 04 (whose one-sentence answer a person grades);
* B handed in Colab's copy of 02 (``Copy of 02_reward (1).ipynb``);
* C handed in 02 twice under two names: a wrong ``02_reward.ipynb``, then a right ``02_reward_final.ipynb``.

Graded with the grader's one command (real nbgrader, confined kernels where the host allows), then:
every renamed notebook is graded (the reward tests' 4 points each, which C's wrong file would not
earn); the stray file is in the class report's "Needs a human" and on A's own summary page; the
feedback package is written in the LMS's format and read back with parsers written from the LMS's
importer (tests/test_lms_feedback.py); A's sentence, graded from ``to_grade.csv`` in one pass,
reaches the gradebook, grades.csv, A's notebook page, A's summary and the import file.

Only notebooks 02 and 04 are graded (the cheapest, and the first with a sentence to grade): about a
minute per LMS on 2 cores.
"""

import csv
import io
import time
import zipfile

import pytest
from test_lms_feedback import canvas_infer, moodle_import

from autograde.classes import lms

TIMEOUT = 120        # seconds per cell, as the other grading tests: a loaded machine must not time out a correct cell
SYSTEMS = {          # which of the generator's students plays A, B and C (C: one upload per file)
    "canvas": {"A": ("_1003_", "canvas_1003"), "B": ("_1002_", "canvas_1002"), "C": ("_1001_", "canvas_1001")},
    "moodle": {"A": ("Seán OBrien_5301279_", "moodle_5301279"), "B": ("Zoë Müller_5301277_", "moodle_5301277"),
               "C": ("Ann Lee_5301278_", "moodle_5301278")},
    "blackboard": {"A": ("_jdoe_", "blackboard_jdoe"), "B": ("_asmith_", "blackboard_asmith"),
                   "C": ("_o_brien_", "blackboard_o_brien")},
}
SCRATCH = b'{"cells": [{"cell_type": "markdown", "metadata": {}, "source": "my scratch work, not the assignment"}], ' \
          b'"metadata": {}, "nbformat": 4, "nbformat_minor": 5}'
COMMENT = "Clear and causal: the dream moves the block without contact."


def download(system: str, files: dict, tmp_path):
    right, wrong, nb04 = files["perfect_02_reward.ipynb"], files["wrong_02_reward.ipynb"], \
        files["perfect_04_imagination_gap.ipynb"]
    plan = {"A": {"02_reward_final.ipynb": right, "scratch.ipynb": SCRATCH, "04_imagination_gap.ipynb": nb04},
            "B": {"Copy of 02_reward (1).ipynb": right},
            "C": {"02_reward.ipynb": wrong, "02_reward_final.ipynb": right}}
    members = {}
    for who, (mark, _) in SYSTEMS[system].items():
        made = getattr(lms, system)(plan[who], plan[who])
        members.update({name: data for name, data in made.items() if mark in name})
    return lms.write_zip(tmp_path / f"{system}.zip", members)


def package(course, system: str) -> dict[str, bytes]:
    """The feedback package of ``system``: {member: bytes}."""
    name = {"canvas": "canvas_feedback_upload.zip", "moodle": "moodle_feedback_files.zip",
            "blackboard": "blackboard_feedback.zip"}[system]
    with zipfile.ZipFile(course / "feedback_return" / name) as z:
        return {i.filename: z.read(i) for i in z.infolist() if not i.is_dir()}


def addressed(system: str, member: str, sids: dict) -> str | None:
    """The student a member reaches, read as the LMS's importer reads it."""
    if system == "canvas":
        uid, aid = canvas_infer(member)
        return f"canvas_{uid}" if uid and aid else None
    if system == "moodle":
        got = moodle_import(member, {s.split("_", 1)[1] for s in sids.values()})
        return f"moodle_{got[0]}" if got else None
    return next((s for s in sids.values() if member.rsplit("/", 1)[-1].startswith(s.split("_", 1)[1] + "_")), None)


@pytest.mark.parametrize("system", list(SYSTEMS))
def test_the_week_end_to_end(executed_solutions, tmp_path, system):
    from nbgrader.api import Gradebook

    from autograde import grade, manual_grade
    from autograde.classes.synthetic import build
    from autograde.course import ASSIGNMENT, COURSE_ID

    ids = {who: sid for who, (_, sid) in SYSTEMS[system].items()}
    path = download(system, build(executed_solutions), tmp_path)
    course = tmp_path / "course"
    course.mkdir()
    t = time.perf_counter()
    report = grade.grade_class(path, course, timeout=TIMEOUT, jobs=2, share=False, progress=False, log=print)
    seconds = time.perf_counter() - t
    assert sorted(report) == sorted(ids.values())

    # every renamed, copied and duplicated 02 is graded, the newest of C's two (the right one)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for sid in ids.values():
            sub = gb.find_submission_notebook("02_reward", ASSIGNMENT, sid)
            assert {g.name: g.score for g in sub.grades}["reward_impl_tests"] == 4, (sid, report[sid]["notes"])
        dream = {g.name: g for g in gb.find_submission_notebook("04_imagination_gap", ASSIGNMENT, ids["A"]).grades}
        assert dream["dream_impl_tests"].score == dream["dream_impl_tests"].max_score > 0
    a, c = report[ids["A"]], report[ids["C"]]
    stem = {"canvas": "-1.ipynb", "moodle": " (1).ipynb"}.get(system)     # A uploaded twice there: the newest counts
    assert {(h["file"].replace(stem, ".ipynb") if stem else h["file"], h["graded"]) for h in a["human"]} == {
        ("02_reward_final.ipynb", "02_reward.ipynb"), ("scratch.ipynb", None)}
    assert report[ids["B"]]["human"] == []
    [two] = c["human"]
    assert two["graded"] == "02_reward.ipynb" and "02_reward_final.ipynb" in two["why"]

    # the class report: the stray file under "Needs a human", with A's name beside the id
    page = (course / "class_report.html").read_text(encoding="utf-8")
    flags = page[page.index('id="flags"'):]
    assert "scratch.ipynb" in flags and ids["A"] in flags and "file not graded" in flags
    assert report[ids["A"]]["name"] and report[ids["A"]]["name"].split()[0] in flags

    # the feedback package, read back as the LMS reads it: every student reached, A's summary says it all
    got = package(course, system)
    reached = {}
    for member, data in got.items():
        sid = addressed(system, member, ids)
        assert sid in ids.values(), (system, member)
        reached.setdefault(sid, []).append((member, data))
    assert set(reached) == set(ids.values())
    summary = next(d for m, d in reached[ids["A"]] if m.endswith("summary.html")).decode()
    assert "scratch" in summary and "not graded" in summary and "02_reward_final" in summary

    # hand grading in one pass: A's sentence from to_grade.csv reaches every output
    with open(course / "to_grade.csv", newline="", encoding="utf-8-sig") as f:
        rows = list(csv.DictReader(f))
    mine = [r for r in rows if r["student_id"] == ids["A"] and r["grade_id"] == "ex1_sentence"]
    assert len(mine) == 1 and mine[0]["answer"].strip() and mine[0]["mark_scheme"].strip()
    assert not [r for r in rows if r["student_id"] != ids["A"]]        # B and C handed in no sentence
    before = grades_csv(course)[ids["A"]]
    key = {"canvas": ids["A"].split("_", 1)[1], "moodle": f"Participant {ids['A'].split('_', 1)[1]}"}.get(system)
    if key:        # A waits for the sentence's grade: not in the import file yet (a blank would erase the LMS's grade)
        assert key not in (course / f"{system}_import.csv").read_text(encoding="utf-8-sig")
    mine[0].update(score=mine[0]["max_score"], comment=COMMENT)
    sheet = tmp_path / "graded.csv"
    with open(sheet, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    out = manual_grade.apply_sheet(sheet, course, jobs=2, log=print)
    assert [e.student for e in out["applied"]] == [ids["A"]]
    assert grades_csv(course)[ids["A"]] == pytest.approx(before + float(mine[0]["max_score"]))
    html = (course / "feedback" / ids["A"] / ASSIGNMENT / "04_imagination_gap.html").read_text(encoding="utf-8")
    assert COMMENT in html
    summary = next(d for m, d in package(course, system).items()
                   if addressed(system, m, ids) == ids["A"] and m.endswith("summary.html")).decode()
    assert COMMENT in summary
    if system in ("canvas", "moodle"):     # Blackboard: no import file (grades.csv)
        assert key in (course / f"{system}_import.csv").read_text(encoding="utf-8-sig")
    # what each LMS's own names said, kept: Canvas's late marker, Blackboard's attempt time; and in
    # grades.csv, each student's name and when they handed in, as the download says
    rows = grades_rows(course)
    for sid in ids.values():
        assert rows[sid]["last_name"] == report[sid]["name"] and rows[sid]["timestamp"] == report[sid]["submitted_at"]
    if system == "canvas":
        assert any("marked this submission late" in n for n in report[ids["B"]]["notes"])
        with open(course / "canvas_import.csv", newline="", encoding="utf-8-sig") as f:
            assert sorted(r[1] for r in list(csv.reader(f))[2:]) == ["1001", "1002", "1003"]
    elif system == "moodle":
        with open(course / "moodle_import.csv", newline="", encoding="utf-8-sig") as f:
            assert sorted(r[0] for r in list(csv.reader(f))[1:]) == [
                f"Participant {sid.split('_', 1)[1]}" for sid in sorted(ids.values())]
    else:       # jdoe's second attempt is graded, and its time is the hand-in's
        assert report[ids["A"]]["lms"]["ids"] == {"username": "jdoe"}
        assert report[ids["A"]]["lms"]["submitted_at"].startswith("2026-03-02T09:30")
        assert rows[ids["A"]]["timestamp"] == "2026-03-02 09:30:15"
    print(f"{system}: graded 3 students (02 x 3, 04 x 1) in {seconds:.0f} s")


def grades_rows(course) -> dict[str, dict]:
    with open(course / "grades.csv", newline="", encoding="utf-8") as f:
        return {r["student_id"]: r for r in csv.DictReader(io.StringIO(f.read()))}


def grades_csv(course) -> dict[str, float]:
    return {s: float(r["raw_score"] or 0) for s, r in grades_rows(course).items()}
