"""The LMS import files (autograde/lms_export.py): Canvas's gradebook CSV and Moodle's grading worksheet
or gradebook CSV, in the layouts those LMSs document, written from a real nbgrader sqlite gradebook.

The gradebook is made with nbgrader's own API in the shape of this course (a test cell, a
one-sentence answer graded by hand, a completion task cell), and every score goes in through
``autograde.gradebook.record``, the function grading uses, manual_grades.csv included. Nothing
here runs a notebook: the module takes a few seconds, most of it nbgrader creating the database once.
"""

import csv
import io
import re
import shutil
from datetime import datetime, timezone

import pytest

from autograde import gradebook, lms_export
from autograde.course import ASSIGNMENT, COURSE_ID, tool_env
from autograde.lms_export import CANVAS_FILE, MOODLE_FILE, NOTES_FILE, write_lms_exports

NOW = datetime(2026, 5, 4, 12, 30, tzinfo=timezone.utc)
TOTAL = 9                                              # 4 + 3 + 1 + 1, see the template below
CANVAS = {"canvas": {"assignment_id": 4711, "assignment_name": "World models 3.2"}}
NAMES = {"ann": "Ann Lee", "bob": "O'Brien, Bob \"Bobby\"", "zoe": "Zoë Ångström", "eve": "=HYPERLINK(\"x\")"}


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """An empty gradebook of this course's assignment in miniature: 02_reward (a 4-point test cell)
    and 04_imagination_gap (a 3-point test cell, ex1_sentence graded by hand, ex1_order a task)."""
    from nbgrader.api import Gradebook

    path = tmp_path_factory.mktemp("template") / "gradebook.db"
    with pytest.MonkeyPatch.context() as mp:      # a new gradebook runs the venv's `alembic`
        mp.setenv("PATH", tool_env()["PATH"])
        make_template(Gradebook, path)
    return path


def make_template(Gradebook, path):
    with Gradebook(f"sqlite:///{path}", course_id=COURSE_ID) as gb:
        gb.add_assignment(ASSIGNMENT)
        gb.add_notebook("02_reward", ASSIGNMENT)
        gb.add_solution_cell("reward_impl", "02_reward", ASSIGNMENT)
        gb.add_grade_cell("reward_impl_tests", "02_reward", ASSIGNMENT, max_score=4, cell_type="code")
        gb.add_notebook("04_imagination_gap", ASSIGNMENT)
        gb.add_solution_cell("dream_impl", "04_imagination_gap", ASSIGNMENT)
        gb.add_grade_cell("dream_impl_tests", "04_imagination_gap", ASSIGNMENT, max_score=3, cell_type="code")
        gb.add_grade_cell("ex1_sentence", "04_imagination_gap", ASSIGNMENT, max_score=1, cell_type="markdown")
        gb.add_solution_cell("ex1_sentence", "04_imagination_gap", ASSIGNMENT)
        gb.add_task_cell("ex1_order", "04_imagination_gap", ASSIGNMENT, max_score=1, cell_type="markdown")


@pytest.fixture
def course(template, tmp_path):
    (tmp_path / "course").mkdir()
    shutil.copy(template, tmp_path / "course" / "gradebook.db")
    return tmp_path / "course"


def canvas_id(uid, name):
    return {"system": "canvas", "name": name, "ids": {"user_id": uid, "attachment_id": "9" + str(uid)},
            "late": False, "submitted_at": "2026-05-01T10:00:00Z", "attempt": 1}


def moodle_id(pid, name):
    return {"system": "moodle", "name": name, "ids": {"participant_id": pid}, "late": None,
            "submitted_at": None, "attempt": None}


def grade(course, students: dict, manual: dict = None) -> dict:
    """Record hand-ins the way grade_class does. ``students``: {id: (lms identity or None, sentence)}
    where sentence is "answered" (waits for a person), "blank" (left as released: nbgrader's 0),
    "missing" (04_imagination_gap not handed in) or "crashed" (nbgrader could not finish it). ``manual``: {id: score} written to manual_grades.csv."""
    if manual:
        with open(course / "manual_grades.csv", "w", newline="") as f:
            w = csv.DictWriter(f, ["student_id", "notebook", "grade_id", "score", "comment"])
            w.writeheader()
            for s, score in manual.items():
                w.writerow({"student_id": s, "notebook": "04_imagination_gap", "grade_id": "ex1_sentence",
                            "score": score, "comment": "Clear."})
    report, results = {}, {}
    passed = {"passed": True, "message": "all cases agree"}
    for s, (lms, sentence) in students.items():
        report[s] = {"notes": [], "completion": {}, "verdicts": {}, "failed": {}, "delegated": {}, "lms": lms}
        results[s] = {"02_reward.ipynb": {"ok": True, "scores": {"reward_impl_tests": 4.0},
                                          "verdicts": {"reward_impl_tests": passed}}}
        if sentence == "crashed":           # nbgrader could not finish 04: no scores, no verdict came back
            report[s]["completion"]["ex1"] = (True, "prediction locked before the experiment")
            results[s]["04_imagination_gap.ipynb"] = {"ok": False, "error": "the kernel died", "scores": {},
                                                      "verdicts": {}}
        elif sentence != "missing":
            report[s]["completion"]["ex1"] = (True, "prediction locked before the experiment")
            results[s]["04_imagination_gap.ipynb"] = {
                "ok": True, "verdicts": {"dream_impl_tests": passed},
                "scores": {"dream_impl_tests": 3.0, "ex1_order": None,
                           "ex1_sentence": None if sentence == "answered" else 0.0}}
    gradebook.clear_submissions(course, report)          # as grade_class does
    gradebook.record(course, report, results)
    return report


def read_csv(path):
    """(raw bytes, rows as the LMS's CSV reader sees them)."""
    raw = path.read_bytes()
    return raw, list(csv.reader(io.StringIO(raw.decode("utf-8-sig"), newline="")))


def assert_lms_encoding(raw: bytes):
    assert raw.startswith(b"\xef\xbb\xbf") and not raw.startswith(b'\xef\xbb\xbf"')   # BOM, first cell unquoted
    assert raw.endswith(b"\r\n") and raw.count(b"\n") == raw.count(b"\r\n")           # CRLF only


def test_canvas_file_is_the_gradebook_import_layout(course):
    report = grade(course, {s: (canvas_id(100 + i, NAMES[s]), "answered") for i, s in enumerate(NAMES)},
                   manual={"ann": 1, "bob": 0.5, "zoe": 0, "eve": 1})
    paths = write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    assert [p.name for p in paths] == [CANVAS_FILE, NOTES_FILE] and all(p.is_file() for p in paths)
    assert not (course / MOODLE_FILE).exists()          # a Canvas class gets no Moodle file
    raw, rows = read_csv(course / CANVAS_FILE)
    assert_lms_encoding(raw)
    assert raw.startswith("\ufeffStudent,ID,SIS User ID,SIS Login ID,Section,World models 3.2 (4711)\r\n"
                          "    Points Possible,,,,,9\r\n".encode())
    assert rows[2:] == [                                    # in student-id order; the name only informs
        ["Ann Lee", "100", "", "", "", "9"],
        ["O'Brien, Bob \"Bobby\"", "101", "", "", "", "8.5"],
        ["'=HYPERLINK(\"x\")", "103", "", "", "", "9"],     # no spreadsheet formula
        ["Zoë Ångström", "102", "", "", "", "8"],
    ]
    assert '"O\'Brien, Bob ""Bobby"""' in raw.decode("utf-8-sig")          # RFC 4180 quoting
    assert all(len(r) == 6 for r in rows)
    # what Canvas's importer (lib/gradebook_importer.rb) checks before it reads a row
    header = rows[0]
    assert "Student" in header[0] and "ID" in header[1] and header[2:4] == ["SIS User ID", "SIS Login ID"]
    assert "Section" in header[4]                          # the last student column
    assert re.fullmatch(r"(.*)\s\((\d+)\)", header[5]).groups() == ("World models 3.2", "4711")
    assert "Points Possible" in rows[1][0]
    notes = (course / NOTES_FILE).read_text()
    assert "canvas_import.csv: 4 students" in notes and "Not exported yet" not in notes.split("== moodle")[0]


def test_scores_are_scaled_to_the_lms_points_with_two_decimals(course):
    report = grade(course, {"ann": (canvas_id(7, "Ann"), "blank")})       # 8 of 9: the blank answer is nbgrader's 0
    write_lms_exports(course, report, settings={**CANVAS, "points_possible": 100}, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert rows[1] == ["    Points Possible", "", "", "", "", "100"]
    assert rows[2] == ["Ann", "7", "", "", "", "88.89"]
    assert "written out of 100" in (course / NOTES_FILE).read_text()


def test_pending_hand_graded_answer_keeps_the_student_out_until_it_is_graded(course):
    students = {"ann": (canvas_id(1, "Ann Lee"), "answered"), "bob": (canvas_id(2, "Bob"), "blank")}
    report = grade(course, students)
    lines = []
    write_lms_exports(course, report, settings=CANVAS, log=lines.append, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert [r[1] for r in rows[2:]] == ["2"]               # ann waits; bob's unanswered sentence is a real 0
    assert rows[2][-1] == "8"
    notes = (course / NOTES_FILE).read_text()
    canvas_part = notes.split("== moodle_import.csv")[0]
    assert "Not exported yet, hand-graded answers to grade (1):" in canvas_part
    assert "ann (Ann Lee): not graded yet: 04_imagination_gap ex1_sentence (1 point). " \
           "So far 8 of 9 points, 1 still to grade" in canvas_part
    assert "canvas_import.csv: 1 student; 1 not in it, 1 of them waiting for hand-graded answers: see " \
           "lms_export_notes.txt" in lines
    assert ",0\r\n" not in (course / CANVAS_FILE).read_bytes().decode()        # never a 0 for a pending answer

    report = grade(course, students, manual={"ann": 1})        # the instructor grades it; grading again re-applies it
    write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert {r[1]: r[-1] for r in rows[2:]} == {"1": "9", "2": "8"}
    assert "Not exported yet" not in (course / NOTES_FILE).read_text()


def test_moodle_worksheet_is_keyed_by_participant_number(course):
    report = grade(course, {"ann": (moodle_id("48213", "Ann Lee"), "blank"),
                            "zoe": (moodle_id(48214, "Zoë, Å"), "answered"),
                            "cat": (canvas_id(3, "Cat"), "blank")}, manual={"zoe": 1})
    write_lms_exports(course, report, settings={}, log=lambda _: None, now=NOW)
    raw, rows = read_csv(course / MOODLE_FILE)
    assert_lms_encoding(raw)
    assert rows[0] == ["Identifier", "Full name", "Grade", "Maximum grade", "Last modified (grade)"]
    assert rows[1:] == [["Participant 48213", "Ann Lee", "8", "9", "2026-05-04T12:30:00+00:00"],
                        ["Participant 48214", "Zoë, Å", "9", "9", "2026-05-04T12:30:00+00:00"]]
    moodle_part = (course / NOTES_FILE).read_text().split("== moodle_import.csv")[1]
    assert "no Moodle participant number: the hand-in came from Canvas (1): cat" in moodle_part


def test_moodle_gradebook_layout_never_maps_a_participant_number_to_a_user(course):
    report = grade(course, {"jdoe": (None, "blank"), "mia": (moodle_id("777", "Mia"), "blank")})
    settings = {"moodle": {"identifier": "username", "grade_item": "Chapter 3.2 notebooks",
                           "student_ids_are": "username"}}
    write_lms_exports(course, report, settings=settings, log=lambda _: None, now=NOW)
    raw, rows = read_csv(course / MOODLE_FILE)
    assert_lms_encoding(raw)
    assert rows == [["Username", "Full name", "Chapter 3.2 notebooks"], ["jdoe", "jdoe", "8"]]
    notes = (course / NOTES_FILE).read_text()
    assert "mia" in notes and "participant number, which the gradebook import cannot match" in notes


def test_students_without_the_identifier_are_listed_not_dropped(course):
    report = grade(course, {"s042": (None, "blank"), "bb": ({"system": "blackboard", "name": "B B",
                                                             "ids": {"username": "bb1"}}, "blank"),
                            "odd": (canvas_id("12a", "Odd"), "blank"), "none": (canvas_id(None, "No Id"), "blank"),
                            "anon": ({**canvas_id("anon_Xy12", None), "name": None}, "blank"),
                            "ok": (canvas_id(5, "Ok"), "blank")})
    write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert [r[1] for r in rows[2:]] == ["5"]
    canvas_part = (course / NOTES_FILE).read_text().split("== moodle_import.csv")[0]
    assert "Not exported, no identifier this file can use (5):" in canvas_part
    assert "anonymous grading: Canvas's download names the student only by an anonymous id" in canvas_part
    assert "no Canvas identifier: the file name carried only a student id" in canvas_part and "s042" in canvas_part
    assert "the hand-in came from Blackboard (1): bb" in canvas_part
    assert "its Canvas user id '12a' is not a number (1): odd" in canvas_part
    assert "the Canvas download gave no Canvas user id (1): none" in canvas_part

    # declared in course.yaml: generic ids are Canvas SIS login ids -> exported under that column
    write_lms_exports(course, report, settings={"canvas": {"student_ids_are": "sis_login_id"}},
                      log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert rows[0][-1] == ASSIGNMENT                        # no assignment id set: the title alone
    assert ["s042", "", "", "s042", "", "8"] in rows


def test_one_identifier_claimed_twice_exports_neither(course):
    report = grade(course, {"ann": (canvas_id(9, "Ann"), "blank"), "ann2": (canvas_id(9, "Ann"), "blank")})
    write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert len(rows) == 2
    notes = (course / NOTES_FILE).read_text()
    assert "Not exported, one identifier claimed twice (2):" in notes
    assert "ann, ann2: all claim ID '9'; none is exported" in notes


def test_a_notebook_not_handed_in_scores_0_with_a_note(course):
    report = grade(course, {"ann": (canvas_id(1, "Ann"), "missing")})
    write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert rows[2][-1] == "4"                               # the sentence of a notebook never handed in is no pending answer
    assert "04_imagination_gap was not graded (not handed in, or not readable): 0 of its 5 points" in \
        (course / NOTES_FILE).read_text()


def test_a_notebook_that_crashed_keeps_its_answer_pending_and_its_tests_at_0(course):
    report = grade(course, {"ann": (canvas_id(1, "Ann"), "crashed")})
    assert "04_imagination_gap.ipynb" in report["ann"]["failed"]
    write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    _, rows = read_csv(course / CANVAS_FILE)
    assert len(rows) == 2                                    # ex1_sentence can still be graded by hand
    notes = (course / NOTES_FILE).read_text()
    assert "So far 5 of 9 points, 1 still to grade; also: 04_imagination_gap dream_impl_tests: no result" in notes


def test_import_files_only_for_the_lms_they_serve(course, tmp_path):
    """No student of any LMS and no course.yaml mapping: no import file, and the notes say why; a
    mapping of generic ids to Canvas SIS ids: Canvas's file, even for zero students; an earlier run's
    file for another LMS is removed, not left to be uploaded with another class's scores."""
    (course / MOODLE_FILE).write_text("an earlier run's scores")
    paths = write_lms_exports(course, {}, settings=CANVAS, log=lambda _: None, now=NOW)
    assert [p.name for p in paths] == [NOTES_FILE] and not (course / CANVAS_FILE).exists()
    notes = paths[0].read_text()
    assert "no import file written" in notes and f"removed {MOODLE_FILE}" in notes
    assert not (course / MOODLE_FILE).exists()
    sis = {"canvas": {**CANVAS["canvas"], "student_ids_are": "sis_user_id"}}
    paths = write_lms_exports(course, {}, settings=sis, log=lambda _: None, now=NOW)
    assert (course / CANVAS_FILE).read_bytes() == ("\ufeffStudent,ID,SIS User ID,SIS Login ID,Section,"
                                                   "World models 3.2 (4711)\r\n    Points Possible,,,,,9\r\n").encode()
    assert not (course / MOODLE_FILE).exists() and "0 students" in paths[-1].read_text()
    empty = tmp_path / "no_gradebook"                       # not even a gradebook: still the headers, and why
    empty.mkdir()
    write_lms_exports(empty, {}, settings={"canvas": {"student_ids_are": "sis_user_id"}}, log=lambda _: None, now=NOW)
    assert read_csv(empty / CANVAS_FILE)[1][1] == ["    Points Possible", "", "", "", "", ""]
    assert "no gradebook" in (empty / NOTES_FILE).read_text() and not (empty / "gradebook.db").exists()


def test_a_notebook_without_graded_cells_is_never_called_ungraded(course):
    """01_world_model has no graded cell: the notes never say it 'was not graded'."""
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        gb.update_or_create_notebook("01_world_model", ASSIGNMENT)
    report = grade(course, {"ann": (canvas_id(100, NAMES["ann"]), "answered")}, manual={"ann": 1})
    paths = write_lms_exports(course, report, settings=CANVAS, log=lambda _: None, now=NOW)
    assert "01_world_model" not in paths[-1].read_text()


def test_course_yaml_lms_section_is_read_and_bad_values_are_named():
    settings, warnings = lms_export.lms_settings()          # course.yaml's placeholders
    assert warnings == [] and settings["moodle"]["identifier"] == "participant"
    assert settings["canvas"] == {"assignment_id": None, "assignment_name": None, "student_ids_are": None}
    _, warnings = lms_export.lms_settings({"points_possible": "lots", "canvas": {"assignment_id": "abc"},
                                           "moodle": {"identifier": "email"}})
    assert len(warnings) == 3 and "participant is used" in warnings[2]
