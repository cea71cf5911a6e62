"""Every graded notebook gets a feedback page (issue 37, item 5): huge outputs are cut in the graded copy
with a note on the page, the scores stay those of the full run, and where there is no graded copy to
make the page from (over the size read back, or nbgrader could not finish the notebook) the notebook as
handed in stands in, with a note. Never no page.

The cutting and the stand-in are tested directly (fast); then one grading run of three small hand-ins
(about 20 s): an honest one, a 40 MB line, a kernel that dies after the tests, and a hand-in whose own cells are over
the size read back (made small here so the hand-in stays small)."""

import csv
import json
import re

import nbformat
import pytest
from nbformat import v4

from autograde import grade, outputs, task
from autograde.course import ASSIGNMENT, COURSE_ID
from autograde.outputs import NOTEBOOK_OUTPUT_BYTES, OUTPUT_BYTES, autograde_steps, cap_cell, stand_in

from handins import reward_handin, write_class

NOTE = re.compile(r"\[output truncated: (\d+\.\d) MB of output not shown\]")


def code(*outs):
    return v4.new_code_cell("x", outputs=list(outs))


def stream(text, name="stdout"):
    return v4.new_output("stream", name=name, text=text)


def notes(cell):
    return [o["data"]["text/plain"] for o in cell.outputs if o.get("output_type") == "display_data"
            and NOTE.fullmatch(o["data"].get("text/plain", ""))]


def test_small_outputs_are_left_alone():
    png = v4.new_output("display_data", data={"image/png": "iVBOR" * 20_000, "text/plain": "<Figure>"})
    err = v4.new_output("error", ename="ValueError", evalue="bad", traceback=["line"] * 5)
    cell = code(stream("hello\n"), png, err)
    before = json.dumps(cell)
    left = cap_cell(cell, NOTEBOOK_OUTPUT_BYTES)
    assert json.dumps(cell) == before and left < NOTEBOOK_OUTPUT_BYTES


def test_a_huge_line_keeps_its_beginning_and_says_how_much_is_not_shown():
    cell = code(stream("x" * 40_000_000 + "\n"), stream("after\n", "stderr"))
    cap_cell(cell, NOTEBOOK_OUTPUT_BYTES)
    assert len(cell.outputs[0]["text"]) == OUTPUT_BYTES and cell.outputs[0]["text"].startswith("xxx")
    assert cell.outputs[1]["text"] == "after\n"                  # the next output is still there
    assert notes(cell) == [f"[output truncated: {(40_000_001 - OUTPUT_BYTES) / 1e6:.1f} MB of output not shown]"]


def test_past_the_notebooks_budget_outputs_are_left_out_but_errors_stay():
    cells = [code(stream("y" * OUTPUT_BYTES)) for _ in range(NOTEBOOK_OUTPUT_BYTES // OUTPUT_BYTES)]
    late = code(v4.new_output("display_data", data={"text/html": "<b>big</b>" * 10}),
                v4.new_output("error", ename="KeyError", evalue="k" * 50_000, traceback=["t" * 50_000] * 300))
    left = NOTEBOOK_OUTPUT_BYTES
    for c in cells + [late]:
        left = cap_cell(c, left)
    assert all(not notes(c) for c in cells) and left == 0
    kinds = [o["output_type"] for o in late.outputs]
    assert kinds == ["error", "display_data"] and notes(late)           # the HTML left out, said so
    err = late.outputs[0]
    assert err["ename"] == "KeyError" and len(err["evalue"]) == outputs.ERROR_LINE_CHARS
    assert err["traceback"] == ["[traceback truncated]"]


def test_the_cut_runs_after_the_scores_are_saved():
    names = [s.__name__ for s in autograde_steps()]
    assert names[-1] == "CapOutput" and names.index("SaveAutoGrades") < names.index("CapOutput")
    assert names.index("Execute") == 0


def test_a_stand_in_is_the_notebook_as_handed_in_without_outputs():
    nb = reward_handin(source_padding="# " + "p" * 100_000 + "\n")
    nb["cells"][3]["outputs"] = [{"output_type": "stream", "name": "stdout", "text": "z" * 1000}]
    made = nbformat.reads(stand_in(json.dumps(nb), 123_400_000), as_version=4)
    assert made.cells[0].cell_type == "markdown" and "123.4 MB" in made.cells[0].source
    assert all(not c.get("outputs") for c in made.cells if c.cell_type == "code")
    graded = [c for c in made.cells if c.metadata.get("nbgrader", {}).get("grade_id") == "reward_impl"]
    assert len(graded) == 1 and len(graded[0].source) < 21_000 and "cut" in graded[0].source
    assert len(made.cells) == len(nb["cells"]) + 1
    nothing = nbformat.reads(stand_in("not json", None), as_version=4)
    assert len(nothing.cells) == 1 and "could not finish" in nothing.cells[0].source


@pytest.fixture(scope="module")
def graded(tmp_path_factory, request):
    mp = pytest.MonkeyPatch()
    request.addfinalizer(mp.undo)
    # read back at most 6 MB here, so that a hand-in of 8 MB is over it (the real bound is 32 MB)
    mp.setattr(task, "MAX_NOTEBOOK_BYTES", 6 << 20)
    tmp = tmp_path_factory.mktemp("feedback-always")
    subs = write_class(tmp / "class", {
        "alice": reward_handin(),
        "bigout": reward_handin(["print('x' * 40_000_000)\n"]),
        "dies": reward_handin(["import os, signal\nos.kill(os.getpid(), signal.SIGKILL)\n"]),
        "bigsrc": reward_handin(markdown="notes " * ((8 << 20) // 6)),      # code cells are capped in prepare
    })
    course = tmp / "course"
    course.mkdir()
    report = grade.grade_class(subs, course, timeout=60, log=print, progress=False)
    return course, report


def page(course, student):
    path = course / "feedback" / student / ASSIGNMENT / "02_reward.html"
    assert path.is_file(), f"no feedback page for {student}"
    return path.read_text()


def scores(course, student):
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        return {g.name: (g.auto_score, g.score) for g in gb.find_submission_notebook("02_reward", ASSIGNMENT, student).grades}


@pytest.mark.slow      # the one grading run (`graded`: nbgrader executes the hand-ins)
@pytest.mark.parametrize("student", ["bigout", "dies", "bigsrc"])
def test_every_graded_notebook_has_a_page_with_its_scores(graded, student):
    course, report = graded
    text = page(course, student)
    assert "Score: 4.0 / 4.0" in text                      # the hidden test's points, on the page too
    assert report[student]["verdicts"]["reward_impl_tests"][:2] == (4.0, 4.0)
    rows = {r["student_id"]: r for r in csv.DictReader(open(course / "report.csv", newline=""))}
    assert float(rows[student]["score"]) == 4.0


@pytest.mark.slow
def test_a_huge_output_is_cut_on_the_page_with_a_note_and_the_scores_of_the_full_run(graded):
    course, report = graded
    text = page(course, "bigout")
    found = NOTE.search(text)
    assert found and float(found.group(1)) >= 37.0, "the note says how much was not shown"
    assert len(text) < 3_000_000
    graded_copy = course / "autograded" / "bigout" / ASSIGNMENT / "02_reward.ipynb"
    assert graded_copy.stat().st_size < 6 << 20
    assert scores(course, "bigout") == scores(course, "alice")       # what was cut was scored as it ran


@pytest.mark.slow
def test_no_graded_copy_gives_the_notebook_as_handed_in_with_a_note(graded):
    course, report = graded
    dies, bigsrc = page(course, "dies"), page(course, "bigsrc")
    assert "The grader could not finish running this notebook" in dies
    assert "too large to make a feedback page from" in bigsrc and "as you handed it in" in bigsrc
    assert any("nbgrader made no graded copy" in n for n in report["dies"]["notes"])
    assert any("over the 6 MB read back" in n for n in report["bigsrc"]["notes"])
