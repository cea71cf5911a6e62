"""Hand grading in one pass (issue 39, item 3): ``to_grade.csv`` written from a real nbgrader gradebook
and the autograded notebooks (autograde/to_grade.py), filled as an instructor fills it, and applied
with ``python -m autograde.manual_grade --from-csv`` (autograde/manual_grade.py).

The gradebook is made with nbgrader's own API in this course's shape (notebooks 04-07, each with a
one-sentence answer graded by hand; 04 also a test cell and a completion task cell), and scores go in
through ``autograde.gradebook.record``, the function grading uses, as in tests/test_lms_export.py. The
autograded notebooks are small ones written with nbformat, carrying nbgrader's cell metadata. Nothing
runs a notebook. Only the feedback pages are replaced, by a stand-in that counts its calls: the
gradebook, manual_grades.csv and grades.csv are the real ones.
"""

import csv
import io

import nbformat
import pytest
from test_lms_export import course  # noqa: F401 (the fixture: a copy of this module's template)

from autograde import gradebook, manual_grade
from autograde.course import ASSIGNMENT, COURSE_ID, tool_env
from autograde.to_grade import COLUMNS, TO_GRADE_FILE, mark_scheme, write_to_grade

SENTENCES = {"04_imagination_gap": "ex1_sentence", "05_horizon": "ex2_sentence", "06_closing_the_gap": "ex3_sentence",
             "07_planning": "ex4_sentence"}


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """An empty gradebook of the assignment in miniature: 04 (a 3-point test cell, ex1_sentence by
    hand, ex1_order a completion task), 05 (ex2_sentence), 06 (ex3_sentence), 07 (ex4_sentence)."""
    from nbgrader.api import Gradebook

    path = tmp_path_factory.mktemp("template") / "gradebook.db"
    with pytest.MonkeyPatch.context() as mp:      # a new gradebook runs the venv's `alembic`
        mp.setenv("PATH", tool_env()["PATH"])
        with Gradebook(f"sqlite:///{path}", course_id=COURSE_ID) as gb:
            gb.add_assignment(ASSIGNMENT)
            for nb, sentence in SENTENCES.items():
                gb.add_notebook(nb, ASSIGNMENT)
                if nb == "04_imagination_gap":
                    gb.add_solution_cell("dream_impl", nb, ASSIGNMENT)
                    gb.add_grade_cell("dream_impl_tests", nb, ASSIGNMENT, max_score=3, cell_type="code")
                    gb.add_task_cell("ex1_order", nb, ASSIGNMENT, max_score=1, cell_type="markdown")
                gb.add_grade_cell(sentence, nb, ASSIGNMENT, max_score=1, cell_type="markdown")
                gb.add_solution_cell(sentence, nb, ASSIGNMENT)
    return path




@pytest.fixture
def feedback_calls(monkeypatch):
    """The feedback pages' one entry point, replaced by a stand-in that only counts its calls."""
    calls = []
    monkeypatch.setattr(manual_grade, "generate_feedback",
                        lambda course, students, jobs, log=print, **kw: calls.append((list(students), jobs)) or {})
    return calls


def canvas(uid, name):
    return {"system": "canvas", "name": name, "ids": {"user_id": uid, "attachment_id": "9" + str(uid)},
            "late": False, "submitted_at": None, "attempt": 1}


def autograded(course, student, notebook, answer):
    """The autograded notebook nbgrader would leave: the answer cell with its nbgrader metadata."""
    sentence = SENTENCES[notebook]
    cells = [nbformat.v4.new_markdown_cell("# A notebook"),
             nbformat.v4.new_markdown_cell(answer, metadata={"nbgrader": {
                 "grade": True, "grade_id": sentence, "locked": False, "points": 1, "schema_version": 3,
                 "solution": True, "cell_type": "markdown"}})]
    folder = course / "autograded" / student / ASSIGNMENT
    folder.mkdir(parents=True, exist_ok=True)
    nbformat.write(nbformat.v4.new_notebook(cells=cells), folder / f"{notebook}.ipynb")


def grade(course, students: dict) -> dict:
    """Record hand-ins as grade_class does. ``students``: {id: (lms identity or None, {notebook:
    answer})}: an answer None is left as released (nbgrader's 0, "no response"); a notebook absent
    was not handed in."""
    report, results = {}, {}
    for s, (lms, answers) in students.items():
        report[s] = {"notes": [], "completion": {}, "verdicts": {}, "failed": {}, "delegated": {}, "lms": lms}
        results[s] = {}
        for nb, answer in answers.items():
            scores = {SENTENCES[nb]: None if answer is not None else 0.0}
            verdicts = {}
            if nb == "04_imagination_gap":
                report[s]["completion"]["ex1"] = (True, "prediction locked before the experiment")
                scores.update({"dream_impl_tests": 3.0, "ex1_order": None})
                verdicts = {"dream_impl_tests": {"passed": True, "message": "all cases agree"}}
            results[s][f"{nb}.ipynb"] = {"ok": True, "scores": scores, "verdicts": verdicts}
            autograded(course, s, nb, answer if answer is not None else "YOUR ANSWER HERE")
    gradebook.clear_submissions(course, report)          # as grade_class does
    gradebook.record(course, report, results)
    return report


def class_of_three(course):
    every = {nb: f"{nb}: the dream is not the world." for nb in SENTENCES}
    return grade(course, {
        "canvas_101": (canvas(101, "Ann Lee"), every),
        "canvas_102": (canvas(102, "Zoë Ångström"), {**every, "06_closing_the_gap": None}),   # 06 left blank
        "s003": (None, {nb: a for nb, a in every.items() if nb != "05_horizon"}),             # 05 not handed in
    })


def read_sheet_rows(path):
    raw = path.read_bytes()
    return raw, list(csv.DictReader(io.StringIO(raw.decode("utf-8-sig"), newline="")))


def fill(path, scores: dict, comment="Good.") -> None:
    """Fill the sheet as a spreadsheet would save it: ``scores`` {(student, notebook): score}."""
    _, rows = read_sheet_rows(path)
    for r in rows:
        if (r["student_id"], r["notebook"]) in scores:
            r["score"], r["comment"] = scores[(r["student_id"], r["notebook"])], comment
    with open(path, "w", newline="", encoding="utf-8-sig") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        w.writerows(rows)


def cell_score(course, student, notebook, grade_id):
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        g = gb.find_grade(grade_id, notebook, ASSIGNMENT, student)
        c = gb.find_comment(grade_id, notebook, ASSIGNMENT, student)
        return g.manual_score, c.manual_comment


def manual_rows(course):
    with open(course / "manual_grades.csv", newline="") as f:
        return {(r["student_id"], r["notebook"], r["grade_id"]): (float(r["score"]), r["comment"])
                for r in csv.DictReader(f)}


def test_the_sheet_lists_every_answer_to_grade_with_name_answer_and_mark_scheme(course):
    report = class_of_three(course)
    path = write_to_grade(course, report)
    assert path == course / TO_GRADE_FILE
    raw, rows = read_sheet_rows(path)
    assert raw.startswith(b"\xef\xbb\xbfstudent_name,") and raw.count(b"\n") == raw.count(b"\r\n")
    assert list(rows[0]) == COLUMNS
    got = [(r["notebook"], r["grade_id"], r["student_id"], r["status"]) for r in rows]
    assert got == [                                        # by question, then by student; no task cell
        ("04_imagination_gap", "ex1_sentence", "canvas_101", "to grade"),
        ("04_imagination_gap", "ex1_sentence", "canvas_102", "to grade"),
        ("04_imagination_gap", "ex1_sentence", "s003", "to grade"),
        ("05_horizon", "ex2_sentence", "canvas_101", "to grade"),
        ("05_horizon", "ex2_sentence", "canvas_102", "to grade"),      # s003 handed no 05 in: no row
        ("06_closing_the_gap", "ex3_sentence", "canvas_101", "to grade"),
        ("06_closing_the_gap", "ex3_sentence", "canvas_102", "no answer (0)"),
        ("06_closing_the_gap", "ex3_sentence", "s003", "to grade"),
        ("07_planning", "ex4_sentence", "canvas_101", "to grade"),
        ("07_planning", "ex4_sentence", "canvas_102", "to grade"),
        ("07_planning", "ex4_sentence", "s003", "to grade"),
    ]
    by = {(r["student_id"], r["notebook"]): r for r in rows}
    first = by[("canvas_102", "05_horizon")]
    assert first["student_name"] == "Zoë Ångström" and by[("s003", "06_closing_the_gap")]["student_name"] == "s003"
    assert first["answer"] == "05_horizon: the dream is not the world."
    assert first["mark_scheme"] == mark_scheme()["ex2_sentence"] and first["mark_scheme"].startswith("1 point")
    assert (first["max_score"], first["current_score"], first["score"], first["comment"]) == ("1", "", "", "")
    assert by[("canvas_102", "06_closing_the_gap")]["current_score"] == "0"
    assert by[("s003", "07_planning")]["mark_scheme"] == mark_scheme()["ex4_sentence"]


def test_a_filled_sheet_is_applied_at_once_with_one_feedback_run(course, feedback_calls):
    report = class_of_three(course)
    path = write_to_grade(course, report)
    fill(path, {("canvas_101", "04_imagination_gap"): "1", ("canvas_102", "04_imagination_gap"): "0.5",
                ("s003", "06_closing_the_gap"): "0", ("canvas_101", "05_horizon"): "1"})
    assert manual_grade.main(["--from-csv", str(path), "--course", str(course), "--jobs", "2"]) == 0
    assert feedback_calls == [(["canvas_101", "canvas_102", "s003"], 2)]     # one call, every student touched
    assert manual_rows(course) == {
        ("canvas_101", "04_imagination_gap", "ex1_sentence"): (1.0, "Good."),
        ("canvas_101", "05_horizon", "ex2_sentence"): (1.0, "Good."),
        ("canvas_102", "04_imagination_gap", "ex1_sentence"): (0.5, "Good."),
        ("s003", "06_closing_the_gap", "ex3_sentence"): (0.0, "Good."),
    }
    score, comment = cell_score(course, "canvas_102", "04_imagination_gap", "ex1_sentence")
    assert score == 0.5 and comment.startswith("Good.\n\nMark scheme: 1 point")
    assert cell_score(course, "canvas_102", "05_horizon", "ex2_sentence")[0] is None      # blank: skipped
    grades = {r["student_id"]: float(r["score"]) for r in csv.DictReader(open(course / "grades.csv"))}
    assert grades == {"canvas_101": 3 + 1 + 1 + 1, "canvas_102": 3 + 1 + 0.5, "s003": 3 + 1 + 0}
    # a regrade re-applies them (gradebook.record, from manual_grades.csv), and the sheet shows them
    class_of_three(course)
    assert cell_score(course, "canvas_102", "04_imagination_gap", "ex1_sentence")[0] == 0.5
    _, rows = read_sheet_rows(write_to_grade(course, report))
    by = {(r["student_id"], r["notebook"]): r for r in rows}
    assert (by[("canvas_102", "04_imagination_gap")]["status"], by[("canvas_102", "04_imagination_gap")]["current_score"],
            by[("canvas_102", "04_imagination_gap")]["current_comment"]) == ("graded", "0.5", "Good.")
    assert by[("canvas_102", "04_imagination_gap")]["score"] == ""


def test_applying_the_same_sheet_again_changes_nothing(course, feedback_calls):
    path = write_to_grade(course, class_of_three(course))
    fill(path, {("canvas_101", "04_imagination_gap"): "1", ("s003", "04_imagination_gap"): "0"})
    first = manual_grade.apply_sheet(path, course, jobs=1, log=lambda _: None)
    assert len(first["applied"]) == 2 and first["students"] == ["canvas_101", "s003"]
    before = ((course / "manual_grades.csv").read_bytes(), (course / "grades.csv").read_bytes(),
              cell_score(course, "canvas_101", "04_imagination_gap", "ex1_sentence"))
    again = manual_grade.apply_sheet(path, course, jobs=1, log=lambda _: None)
    assert again["applied"] == [] and len(again["unchanged"]) == 2 and again["students"] == []
    assert len(feedback_calls) == 1                                    # nothing changed: no pages made again
    assert ((course / "manual_grades.csv").read_bytes(), (course / "grades.csv").read_bytes(),
            cell_score(course, "canvas_101", "04_imagination_gap", "ex1_sentence")) == before
    # one changed score: only its student's pages are made again
    fill(path, {("canvas_101", "04_imagination_gap"): "1", ("s003", "04_imagination_gap"): "1"})
    third = manual_grade.apply_sheet(path, course, jobs=1, log=lambda _: None)
    assert [e.student for e in third["applied"]] == ["s003"] and feedback_calls[-1] == (["s003"], 1)
    assert manual_rows(course)[("s003", "04_imagination_gap", "ex1_sentence")] == (1.0, "Good.")


def test_a_bad_row_applies_nothing_and_names_every_line_and_the_nearest_ids(course, feedback_calls, capsys):
    path = write_to_grade(course, class_of_three(course))
    _, rows = read_sheet_rows(path)
    rows = [dict(r) for r in rows[:6]]
    rows[0]["score"] = "1"                                              # line 2: fine
    rows[1].update(student_id="canvas_1O2", score="1")                 # line 3: O for 0
    rows[2].update(notebook="04_imagination", score="1")               # line 4
    rows[3].update(grade_id="ex2_sentance", score="1")                 # line 5
    rows[4]["score"] = "2"                                             # line 6: 1 point at most
    rows[5]["score"] = "good"                                          # line 7
    with open(path, "w", newline="", encoding="utf-8-sig") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        w.writerows(rows)
    with pytest.raises(ValueError) as err:
        manual_grade.apply_sheet(path, course, jobs=1, log=lambda _: None)
    text = str(err.value)
    assert "nothing applied, 5 problems" in text and "line 2" not in text
    lines = text.splitlines()[1:]
    assert [line.split(":")[0] for line in lines] == ["line 3", "line 4", "line 5", "line 6", "line 7"]
    assert "no student 'canvas_1O2': did you mean canvas_102?" in lines[0] or \
        ("canvas_102" in lines[0] and "nearest" in lines[0])
    assert "no notebook '04_imagination'" in lines[1] and "04_imagination_gap" in lines[1]
    assert "no graded cell 'ex2_sentance' in 05_horizon: did you mean ex2_sentence?" in lines[2]
    assert "outside 0..1" in lines[3] and "'good' is not a number" in lines[4]
    assert not (course / "manual_grades.csv").exists() and feedback_calls == []
    assert cell_score(course, "canvas_101", "04_imagination_gap", "ex1_sentence")[0] is None    # line 2 not applied
    # the command line says the same and exits non-zero
    assert manual_grade.main(["--from-csv", str(path), "--course", str(course)]) == 2
    assert "line 3: no student 'canvas_1O2'" in capsys.readouterr().err
    assert not (course / "manual_grades.csv").exists()


def test_the_one_grade_command_names_the_nearest_ids(course, feedback_calls, capsys):
    class_of_three(course)
    with pytest.raises(SystemExit) as ex:
        manual_grade.main(["canvas_1011", "04_imagination_gap", "ex1_sentence", "1", "--course", str(course)])
    assert ex.value.code == 2 and "no student 'canvas_1011': the nearest ids are canvas_101," in capsys.readouterr().err
    with pytest.raises(SystemExit):
        manual_grade.main(["canvas_101", "04_imagination_gap", "ex1_sentense", "1", "--course", str(course)])
    assert "did you mean ex1_sentence?" in capsys.readouterr().err
    assert manual_grade.main(["canvas_101", "04_imagination_gap.ipynb", "ex1_sentence", "1", "--comment",
                              "Clear.", "--course", str(course)]) == 0
    assert feedback_calls == [(["canvas_101"], 1)]
    assert manual_rows(course) == {("canvas_101", "04_imagination_gap", "ex1_sentence"): (1.0, "Clear.")}
    assert cell_score(course, "canvas_101", "04_imagination_gap", "ex1_sentence")[0] == 1.0


def test_an_answer_or_name_written_as_a_formula_is_shown_as_text(course):
    report = grade(course, {
        "canvas_7": (canvas(7, "=HYPERLINK(\"http://x\",\"y\")"), {"04_imagination_gap": "=1+1 cmd|' /C calc'!A0",
                                                                   "05_horizon": "+SUM(A1:A9)",
                                                                   "06_closing_the_gap": "@foo\n-2"}),
    })
    raw, rows = read_sheet_rows(write_to_grade(course, report))
    for r in rows:
        for column in COLUMNS:
            assert not r[column].startswith(("=", "+", "-", "@")), (column, r[column])
    assert [r["answer"] for r in rows] == ["'=1+1 cmd|' /C calc'!A0", "'+SUM(A1:A9)", "'@foo -2"]
    assert rows[0]["student_name"] == "'=HYPERLINK(\"http://x\",\"y\")"
    assert b"\r\n=" not in raw and b",=" not in raw and b',"=' not in raw


def test_a_sheet_saved_by_a_spreadsheet_in_another_locale_is_read(course, feedback_calls):
    """Excel's 'CSV' in a European locale: ';' between cells, a decimal comma, Windows-1252, no BOM."""
    path = write_to_grade(course, class_of_three(course))
    _, rows = read_sheet_rows(path)
    rows[0].update(score="0,5", comment="Très bien")
    with open(path, "w", newline="", encoding="cp1252") as f:
        w = csv.DictWriter(f, COLUMNS, delimiter=";")
        w.writeheader()
        w.writerows({k: v.encode("cp1252", "replace").decode("cp1252") for k, v in r.items()} for r in rows)
    out = manual_grade.apply_sheet(path, course, jobs=1, log=lambda _: None)
    assert [(e.student, e.score, e.comment) for e in out["applied"]] == [("canvas_101", 0.5, "Très bien")]
    assert len(out["skipped"]) == len(rows) - 1


def test_long_answers_are_cut_and_missing_notebooks_said(course):
    report = class_of_three(course)
    autograded(course, "canvas_101", "05_horizon", "word " * 5000)
    (course / "autograded" / "s003" / ASSIGNMENT / "04_imagination_gap.ipynb").unlink()
    _, rows = read_sheet_rows(write_to_grade(course, report))
    by = {(r["student_id"], r["notebook"]): r for r in rows}
    assert len(by[("canvas_101", "05_horizon")]["answer"]) < 3_200 and "cut at" in by[("canvas_101", "05_horizon")]["answer"]
    assert by[("s003", "04_imagination_gap")]["answer"] == "(no autograded notebook)"


def test_a_tripwire_left_to_a_human_is_on_the_sheet_and_decided_from_it(course, feedback_calls):
    """A test cell whose verdict the tripwire left undecided (autograde/tripwire.py) is a row too."""
    report = class_of_three(course)
    report["s003"]["undecided"] = [("04_imagination_gap", "dream_impl_tests", 3.0)]
    report["s003"]["tripwires"] = ["04_imagination_gap dream_impl_tests: the grader could not run it again"]
    path = write_to_grade(course, report)
    _, rows = read_sheet_rows(path)
    wire = [r for r in rows if r["grade_id"] == "dream_impl_tests"]
    assert [(r["student_id"], r["status"], r["max_score"]) for r in wire] == [("s003", "NEEDS A HUMAN", "3")]
    assert "could not run it again" in wire[0]["mark_scheme"]
    with open(path, "w", newline="", encoding="utf-8-sig") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        w.writerows({**r, "score": "3" if r is wire[0] else "", "comment": "noted" if r is rows[1] else ""}
                    for r in rows)
    lines = []
    out = manual_grade.apply_sheet(path, course, jobs=1, log=lines.append)
    assert [(e.student, e.grade_id, e.score) for e in out["applied"]] == [("s003", "dream_impl_tests", 3.0)]
    assert cell_score_only(course, "s003", "04_imagination_gap", "dream_impl_tests") == 3.0
    assert lines[0] == "line 3: a comment without a score is not applied (give a score to apply it)"
    assert lines[1:] == [line for line in lines[1:] if "report.json does not exist" in line]   # no grading saved one here
    # decided: the next sheet shows it graded, not waiting
    del report["s003"]["undecided"]
    _, rows = read_sheet_rows(write_to_grade(course, report))
    assert [(r["status"], r["current_score"]) for r in rows if r["grade_id"] == "dream_impl_tests"] == [("graded", "3")]


def cell_score_only(course, student, notebook, grade_id):
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        return gb.find_grade(grade_id, notebook, ASSIGNMENT, student).manual_score


def test_a_sheet_saved_as_unicode_text_or_in_an_unknown_code_page(tmp_path):
    """Excel's "Unicode Text" (UTF-16 with tabs) is read; a file in neither UTF-8 nor Windows-1252
    (MacRoman's bytes 0x81 and 0x8d are unassigned there) is refused with what to do, not garbled."""
    from autograde.to_grade import read_sheet

    rows = "\t".join(COLUMNS) + "\r\n" + "\t".join("s001" if c == "student_id" else "Zoë" if c == "comment"
                                                  else "" for c in COLUMNS) + "\r\n"
    (tmp_path / "u16.txt").write_bytes(rows.encode("utf-16"))
    got, problems = read_sheet(tmp_path / "u16.txt")
    assert problems == [] and got[0][1]["student_id"] == "s001" and got[0][1]["comment"] == "Zoë"
    (tmp_path / "mac.csv").write_bytes((",".join(COLUMNS) + "\n").encode() + b"s001" + b"," * (len(COLUMNS) - 2) + b"\x81\x8d\n")
    got, problems = read_sheet(tmp_path / "mac.csv")
    assert got == [] and "CSV UTF-8" in problems[0]


def test_grading_again_never_overwrites_a_sheet_holding_scores_not_yet_applied(course, tmp_path):
    """An instructor fills to_grade.csv in place, then a late hand-in makes them grade again: the
    filled sheet is kept aside, said, and can still be applied; a sheet with nothing waiting is
    simply rewritten."""
    report = class_of_three(course)
    path = write_to_grade(course, report)
    with open(path, newline="", encoding="utf-8-sig") as f:
        rows = list(csv.DictReader(f))
    rows[0]["score"] = "1"
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = []
    write_to_grade(course, report, log=lines.append)
    [aside] = list(course.glob("to_grade.unapplied-*.csv"))
    assert "not yet applied" in lines[0] and str(aside) in lines[0]
    out = manual_grade.apply_sheet(aside, course, jobs=1, log=lambda _: None)
    assert len(out["applied"]) == 1
    write_to_grade(course, report, log=lines.append)                 # now applied: nothing waits
    assert len(list(course.glob("to_grade.unapplied-*.csv"))) == 1 and len(lines) == 1
