"""Grading a class: every kind of bad submission gets the score and feedback it deserves, nothing
stops the batch, and grading again gives the same grades.

This is the instructor's one command (python -m autograde.grade) on a synthetic class
(autograde/classes/synthetic.py), with real nbgrader and its sqlite gradebook.
"""

import csv
import time
import zipfile
from pathlib import Path

import nbformat
import pytest

from autograde import feedback, grade
from autograde.course import ASSIGNMENT, COURSE_ID, NOTEBOOKS, nbgrader_api
from autograde.manual_grade import set_manual_grade
from autograde.classes.synthetic import write_zip

ROOT = Path(__file__).resolve().parents[1]


STUDENTS = ["badpred", "colab", "garbage", "loops", "order", "perfect", "raises", "tamper", "wrong"]
TIMEOUT = 30   # seconds per cell: enough for every smoke-mode cell, short for the infinite loop


@pytest.fixture(scope="module")
def graded(executed_solutions, tmp_path_factory):
    executed = executed_solutions
    tmp = tmp_path_factory.mktemp("grading")
    course = tmp / "course"
    course.mkdir()
    subs = write_zip(tmp / "class.zip", executed)
    t = time.perf_counter()
    report = grade.grade_class(subs, course, timeout=TIMEOUT, log=print)
    seconds = time.perf_counter() - t
    print(f"graded {len(report)} synthetic students in {seconds:.0f} s")
    return course, report, subs


def cell_scores(course, student, notebook):
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        try:
            sub = gb.find_submission_notebook(notebook, ASSIGNMENT, student)
        except MissingEntry:
            return None
        return {g.name: g.score for g in sub.grades}


def grades_csv(course):
    with open(course / "grades.csv", newline="") as f:
        return {row["student_id"]: float(row["raw_score"]) for row in csv.DictReader(f)}


def test_every_student_is_in_the_gradebook_and_the_csv(graded):
    course, report, _ = graded
    assert sorted(report) == STUDENTS
    assert sorted(grades_csv(course)) == STUDENTS


def test_perfect_student_gets_every_automatic_point(graded):
    course, _, _ = graded
    for nb in ("02_reward", "03_imagination_actor", "04_imagination_gap", "06_closing_the_gap", "07_planning"):
        scores = cell_scores(course, "perfect", nb)
        tests = {k: v for k, v in scores.items() if k.endswith("_tests")}
        assert tests and all(v > 0 for v in tests.values()), (nb, scores)
    assert cell_scores(course, "perfect", "04_imagination_gap")["ex1_order"] == 1
    assert cell_scores(course, "perfect", "05_horizon")["ex2_order"] == 1
    assert cell_scores(course, "perfect", "06_closing_the_gap")["ex3_order"] == 1
    assert cell_scores(course, "perfect", "07_planning")["ex4_order"] == 1


def test_experiment_before_prediction_loses_the_completion_point_only(graded):
    course, report, _ = graded
    scores = cell_scores(course, "order", "04_imagination_gap")
    assert scores["ex1_order"] == 0 and scores["dream_impl_tests"] > 0
    ok, why = report["order"]["completion"]["ex1"]
    assert not ok and "before the prediction was locked" in why


def test_invalid_prediction_loses_the_completion_point_only(graded):
    course, report, _ = graded
    scores = cell_scores(course, "badpred", "04_imagination_gap")
    assert scores["ex1_order"] == 0 and scores["dream_impl_tests"] > 0
    assert not report["badpred"]["completion"]["ex1"][0]


def test_wrong_implementation_fails_its_tests_with_feedback(graded):
    course, _, _ = graded
    assert cell_scores(course, "wrong", "02_reward")["reward_impl_tests"] == 0
    feedback = (course / "feedback" / "wrong" / ASSIGNMENT / "02_reward.html").read_text()
    assert "[grader] reward_impl_tests: 0 of 4 points" in feedback and "first failure" in feedback
    # the verdict and its hint reach the student; the hidden tests' source does not
    assert "BEGIN HIDDEN TESTS" not in feedback and "grading.submit" not in feedback


def test_a_notebook_that_raises_is_graded_not_fatal(graded):
    # its set-up cell raises, so the kernel's later cells fail; the hidden tests judge the functions
    # its cells define (autograde/probe.py), and this one is right: the points its code earns
    course, _, _ = graded
    assert cell_scores(course, "raises", "03_imagination_actor")["lambda_return_impl_tests"] == 4
    nb = nbformat.read(course / "autograded" / "raises" / ASSIGNMENT / "03_imagination_actor.ipynb", as_version=4)
    assert any(o.get("ename") == "RuntimeError" for c in nb.cells for o in c.get("outputs", []))


def test_an_infinite_loop_is_interrupted_by_the_cell_timeout(graded):
    course, _, _ = graded
    assert cell_scores(course, "loops", "02_reward")["reward_impl_tests"] == 0


def test_edited_or_deleted_locked_tests_are_restored(graded):
    course, report, _ = graded
    assert cell_scores(course, "tamper", "03_imagination_actor")["lambda_return_impl_tests"] == 4
    assert cell_scores(course, "tamper", "02_reward")["reward_impl_tests"] == 4
    assert any("reward_impl_tests' was missing and was put back" in n for n in report["tamper"]["notes"])


def test_a_file_that_is_not_a_notebook_scores_zero_with_a_note(graded):
    course, report, _ = graded
    assert cell_scores(course, "garbage", "04_imagination_gap") is None
    assert grades_csv(course)["garbage"] == 0
    assert any("not a notebook" in n and "Download .ipynb" in n for n in report["garbage"]["notes"])
    assert "not a notebook" in (course / "report.csv").read_text()


def test_a_colab_download_grades_like_any_other(graded):
    course, report, _ = graded
    assert cell_scores(course, "colab", "02_reward")["reward_impl_tests"] == 4
    assert any("Colab" in n for n in report["colab"]["notes"])


def test_feedback_pages_are_the_documents_nbgraders_own_exporter_makes(graded, tmp_path, monkeypatch):
    """The pages come from autograde/feedback_html.py's exporter, which skips nbconvert's
    BeautifulSoup round trip and makes the page safe (no script, a Content-Security-Policy);
    nbgrader's default exporter, on a copy of the course, makes the same documents, less what the
    exporter removes to make them safe (tests/test_feedback_html.py says exactly what). Math is
    compared as nbconvert leaves it (``$...$``): ours draws it as MathML (tests/test_feedback_math.py),
    so our pages are made again here with nbconvert's math renderer."""
    import shutil

    from nbconvert.exporters import HTMLExporter
    from nbconvert.filters.markdown_mistune import IPythonRenderer
    from test_feedback_html import same_document_made_safe

    from autograde.feedback_html import _MathMLRenderer

    course, _, _ = graded
    for name in ("block_math", "inline_math", "latex_environment"):
        monkeypatch.setattr(_MathMLRenderer, name, getattr(IPythonRenderer, name))
    copies = {}
    for which, exporter in (("ours", None), ("theirs", HTMLExporter)):
        copies[which] = tmp_path / which
        shutil.copytree(course, copies[which], ignore=shutil.ignore_patterns("feedback"))
        api = nbgrader_api(copies[which])
        if exporter is not None:
            api.config.GenerateFeedback.exporter_class = exporter
        for student in ("perfect", "wrong"):
            assert api.generate_feedback(ASSIGNMENT, student_id=student, force=True)["success"]
    for student, n in (("perfect", len(NOTEBOOKS)), ("wrong", 1)):     # every notebook; a failed test's output
        pages = sorted((course / "feedback" / student / ASSIGNMENT).glob("*.html"))
        assert len(pages) == n
        for page in pages:
            ours, theirs = ((copies[w] / "feedback" / student / ASSIGNMENT / page.name).read_text()
                            for w in ("ours", "theirs"))
            assert same_document_made_safe(ours, theirs), page


def test_a_student_whose_feedback_never_finishes_loses_only_their_pages(graded, tmp_path):
    """A page that takes too long (here: a notebook of 5 million characters of nbconvert's slowest
    markdown, some 35 s to render, with the size caps bypassed) is given up after ``timeout``; the
    students after it, in the same process before, get theirs from a new one."""
    import shutil

    import nbformat

    course, _, _ = graded
    copy = tmp_path / "course"
    shutil.copytree(course, copy, ignore=shutil.ignore_patterns("feedback"))
    slow = copy / "autograded" / "perfect" / ASSIGNMENT / "02_reward.ipynb"
    nb = nbformat.read(slow, as_version=4)
    nb.cells.append(nbformat.v4.new_markdown_cell("\n- [" * 1_250_000))
    nbformat.write(nb, slow)
    lines = []
    t = time.perf_counter()
    errors = feedback.generate_feedback(copy, ["wrong", "perfect", "colab"], jobs=1, log=lines.append, timeout=20)
    assert time.perf_counter() - t < 60
    assert list(errors) == ["perfect"] and "took more than 20 s" in errors["perfect"], errors
    assert not (copy / "feedback" / "perfect").joinpath(ASSIGNMENT).exists(), "no half-made pages"
    for student in ("colab", "wrong"):      # before and after the slow one, in sorted order
        assert sorted((copy / "feedback" / student / ASSIGNMENT).glob("*.html")), student
    assert any("perfect" in line and "took more than" in line for line in lines)


def test_feedback_pages_are_capped_in_text_too():
    import nbformat

    cap, budget = feedback.FEEDBACK_SOURCE_CHARS, feedback.FEEDBACK_NOTEBOOK_CHARS
    small = nbformat.v4.new_markdown_cell("A short answer.")
    assert feedback._cap_source(small, budget) == budget - len("A short answer.")
    assert small.source == "A short answer."
    big = nbformat.v4.new_markdown_cell("x" * (cap + 1))
    left = feedback._cap_source(big, budget)
    assert big.source.startswith("x" * cap) and f"cut at {cap} characters" in big.source
    assert left == budget - cap
    code = nbformat.v4.new_code_cell("y = 1\n" * cap)
    feedback._cap_source(code, budget)
    assert code.source.splitlines()[-1].startswith("# [... this cell's text is cut")     # still Python
    late = nbformat.v4.new_markdown_cell("q" * 100)       # more than the notebook has left: left out
    assert feedback._cap_source(late, 50) == 50 and "q" not in late.source and "left out" in late.source
    assert feedback._cap_source(nbformat.v4.new_markdown_cell("w" * 40), 50) == 10   # a smaller one still fits


def test_mark_scheme_reaches_students_through_feedback_only(graded):
    course, _, _ = graded
    feedback = (course / "feedback" / "perfect" / ASSIGNMENT / "04_imagination_gap.html").read_text()
    assert "Mark scheme" in feedback
    release = "".join(p.read_text() for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert "Mark scheme" not in release and "pleasing the dream" not in release


def test_regrading_an_unchanged_class_reuses_its_results_and_keeps_manual_grades(graded):
    course, _, subs = graded
    set_manual_grade("perfect", "04_imagination_gap", "ex1_sentence", 1.0, "Clear and complete.",
                     course=course)
    before = grades_csv(course)
    with open(course / "manual_grades.csv", "a", newline="") as f:       # a hand edit out of range
        csv.writer(f).writerow(["perfect", "05_horizon", "ex2_sentence", "7", "too generous"])
    lines = []
    report = grade.grade_class(subs, course, timeout=TIMEOUT, log=lines.append)
    graded_ones = len(STUDENTS) - 1          # "garbage" hands in nothing that can be graded
    assert f"{graded_ones} of {graded_ones} students unchanged" in "\n".join(lines)
    after = grades_csv(course)
    assert after == before
    assert cell_scores(course, "perfect", "04_imagination_gap")["ex1_sentence"] == 1.0
    assert cell_scores(course, "perfect", "05_horizon")["ex2_sentence"] in (None, 0)
    assert any("refused" in n and "ex2_sentence" in n for n in report["perfect"]["notes"])


def test_a_changed_submission_is_graded_again_and_only_it(graded, tmp_path):
    """The student 'wrong' hands in a corrected reward notebook: only they are graded again."""
    course, _, subs = graded
    before = grades_csv(course)
    fixed = tmp_path / "resubmitted.zip"
    with zipfile.ZipFile(subs) as src, zipfile.ZipFile(fixed, "w") as dst:
        for name in src.namelist():
            data = src.read(name)
            if name == "wrong_02_reward.ipynb":
                data = src.read("perfect_02_reward.ipynb")
            dst.writestr(name, data)
    lines = []
    grade.grade_class(fixed, course, timeout=TIMEOUT, log=lines.append)
    graded_ones = len(STUDENTS) - 1
    assert f"{graded_ones - 1} of {graded_ones} students unchanged" in "\n".join(lines)
    after = grades_csv(course)
    assert after["wrong"] > before["wrong"]
    assert cell_scores(course, "wrong", "02_reward")["reward_impl_tests"] > 0
    assert {s: v for s, v in after.items() if s != "wrong"} == {s: v for s, v in before.items() if s != "wrong"}


def test_a_students_line_sharing_a_message_with_a_grading_line_stays_in_the_feedback():
    """The kernel cuts printed text into messages on a clock, so a student's print and the test
    cell's '[graded outside this kernel]' line can arrive as one message: only the grading line
    (and any line posing as a verdict) goes, whatever the cut."""
    import nbformat

    stream = lambda text: nbformat.v4.new_output("stream", name="stdout", text=text)  # noqa: E731
    one = [stream("visible tests passed\n[graded outside this kernel] t: 9 checks recorded\n")]
    two = [stream("visible tests passed\n"), stream("[graded outside this kernel] t: 9 checks recorded\n")]
    forged = [stream("[grader] t: 4 of 4 points: all passed\nvisible tests passed\n")]
    for outputs in (one, two, forged):
        assert [o["text"] for o in feedback._without_grader_lines(outputs)] == ["visible tests passed\n"]
    assert feedback._without_grader_lines([stream("[graded outside this kernel] t\n")]) == []
