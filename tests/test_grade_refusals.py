"""What grading refuses before it touches anything: a download that names no student.

Fast: the refusal comes before nbgrader, a kernel or the course's gradebook is touched. The course
folder holds the outputs of an earlier grading; every one of them must be byte for byte the same
after the refused run, which exits non-zero and says why.
"""

import hashlib
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ["grades.csv", "report.csv", "canvas_import.csv", "class_report.html", "lms_export_notes.txt",
           "gradebook.db", "feedback/canvas_1/assignment/02_reward.html"]


def snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def empty_folder(tmp_path):
    (tmp_path / "empty").mkdir()
    return tmp_path / "empty"


def only_system_files(tmp_path):
    path = tmp_path / "junk.zip"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("__MACOSX/._x", b"")
        zf.writestr(".DS_Store", b"")
    return path


def an_empty_zip(tmp_path):
    path = tmp_path / "none.zip"
    zipfile.ZipFile(path, "w").close()
    return path


@pytest.mark.parametrize("make", [empty_folder, only_system_files, an_empty_zip])
def test_a_download_of_nobody_is_refused_and_changes_no_file(tmp_path, make):
    course = tmp_path / "course"
    for name in OUTPUTS:
        (course / name).parent.mkdir(parents=True, exist_ok=True)
        (course / name).write_text(f"an earlier grading's {name}\n")
    before = snapshot(course)
    run = subprocess.run([sys.executable, "-m", "autograde.grade", str(make(tmp_path)), "--course", str(course)],
                         capture_output=True, text=True, cwd=ROOT, timeout=120,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode != 0
    assert "holds no student's submission" in run.stderr and "no file was changed" in run.stderr
    assert snapshot(course) == before


def test_every_command_writes_to_the_one_course_folder_unless_told_otherwise():
    """The course folder is defined once (course.COURSE_DIR, course/ beside the package, never the
    package itself); every command's --course defaults to it and make grade passes COURSE= on."""
    import inspect

    from autograde import course, grade, lms_feedback, manual_grade

    assert course.COURSE_DIR == ROOT / "course" and course.COURSE_DIR != course.HERE
    for fn in (grade.grade_class, manual_grade.apply_sheet, manual_grade.set_manual_grade):
        assert inspect.signature(fn).parameters["course"].default == course.COURSE_DIR, fn
    for module in (grade, lms_feedback, manual_grade):
        assert "default=COURSE_DIR" in Path(module.__file__).read_text(), module
    def make(*a):
        return subprocess.run(["make", "-n", "grade", *a], cwd=ROOT, capture_output=True, text=True).stdout

    assert "--course" not in make("SUBMISSIONS=x.zip")
    assert '--course "/tmp/my course"' in make("SUBMISSIONS=x.zip", "COURSE=/tmp/my course")
    assert (ROOT / ".gitignore").read_text().splitlines().count("/course/") == 1
    assert "autograde/" not in (ROOT / ".gitignore").read_text()


def test_make_grade_passes_jobs_timeout_and_confinement_on_only_when_given():
    def make(*a):
        return " ".join(subprocess.run(["make", "-n", "grade", "SUBMISSIONS=x.zip", *a], cwd=ROOT,
                                       capture_output=True, text=True).stdout.split())

    plain = make()
    assert "autograde.grade \"x.zip\"" in plain.replace("\\", "")
    assert not any(flag in plain for flag in ("--jobs", "--timeout", "--no-confine"))
    given = make("JOBS=3", "TIMEOUT=60", "CONFINE=unconfined")
    assert "--jobs 3" in given and "--timeout 60" in given and "--no-confine" in given
    assert "--no-confine" not in make("CONFINE=yes")      # only the word that says it
