"""The course: its settings, nbgrader on it, the bundle a grading task takes, one run at a time.

Everything here is about the nbgrader course folder (``COURSE_DIR``, ``course/`` at the repository's
root by default; ``--course`` on the command lines, ``COURSE=`` to make) and the private copies of
it that grading tasks make: the assignment's name and notebooks, nbgrader's API and
command line on a folder, the zip a task receives, and the lock that keeps two grading runs off
one folder.
"""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


# The course folder: everything grading writes (nbgrader's source/, release/, submitted/,
# autograded/ and feedback/, the gradebook, graded.json, shared_stages/, grades.csv, report.csv,
# to_grade.csv, manual_grades.csv, the LMS import files, the class report, feedback_return/, the
# lock) lands in it and nowhere else: never in this package, so nothing of a class's grading is
# committed (.gitignore: /course/) or vendored into the Gradescope bundle. The one default of every
# command's --course (grade, manual_grade, lms_feedback) and of make's COURSE=.
COURSE_DIR = ROOT / "course"


COURSE = yaml.safe_load((ROOT / "course.yaml").read_text())


ASSIGNMENT = COURSE["assignment"]


# The course's public addresses, from course.yaml: the student release renders them into its badges
# and install cell (scripts/release.py), the chapter site into its links (chapter_site/).
def install_url() -> str:
    """What the Colab install cell gives pip: the package from the course's repository and ref."""
    return f"git+https://github.com/{COURSE['repository']}@{COURSE['ref']}"


def colab_url(notebook: str) -> str:
    """The student notebook ``notebook`` (a file name) opened in Colab."""
    return (f"https://colab.research.google.com/github/{COURSE['repository']}/blob/{COURSE['ref']}/"
            f"notebooks/{notebook}")


def binder_url(notebook: str) -> str:
    """The student notebook ``notebook`` opened in JupyterLab on Binder."""
    return f"https://mybinder.org/v2/gh/{COURSE['repository']}/{COURSE['ref']}?labpath=notebooks%2F{notebook}"


COURSE_ID = "zero2robot-ch3.2"      # the same as in nbgrader_config.py


# nbgrader's source of the assignment: the instructor's notebooks, solutions/. The Gradescope bundle
# holds no solutions/ but GRADING_SOURCE: the same notebooks with every solution taken out, of which
# nbgrader makes the same release and gradebook (autograde/gradescope.py, grading_source).
GRADING_SOURCE = "grading_source"
SOURCE = ROOT / "solutions" if (ROOT / "solutions").is_dir() else ROOT / GRADING_SOURCE


NOTEBOOKS = sorted(p.name for p in SOURCE.glob("*.ipynb"))


# The completion task cell of each predict-then-run exercise: "<ex>_order".
EXERCISES = {"ex1": "04_imagination_gap", "ex2": "05_horizon", "ex3": "06_closing_the_gap",
             "ex4": "07_planning"}


def tool_env() -> dict:
    """nbgrader shells out to `alembic`: make this interpreter's scripts folder visible."""
    here, path = str(Path(sys.executable).parent), os.environ.get("PATH", "")
    return {**os.environ, "PATH": path if here in path.split(os.pathsep) else f"{here}{os.pathsep}{path}"}


def nbgrader(course: Path, *args: str, timeout: int | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "nbgrader", *args, f"--CourseDirectory.root={course}",
           f"--CourseDirectory.db_url=sqlite:///{course / 'gradebook.db'}"]
    if timeout:
        cmd.append(f"--Execute.timeout={timeout}")
    return subprocess.run(cmd, cwd=course, capture_output=True, text=True, env=tool_env())


def prepare_course(course: Path) -> None:
    """Copy the assignment's source (solutions/, ``SOURCE``) into the course's source folder and
    (re)generate the assignment."""
    src = course / "source" / ASSIGNMENT
    src.mkdir(parents=True, exist_ok=True)
    for path in SOURCE.glob("*.ipynb"):
        shutil.copy(path, src / path.name)
    if course.resolve() != HERE:
        shutil.copy(HERE / "nbgrader_config.py", course / "nbgrader_config.py")
    res = nbgrader_api(course).generate_assignment(ASSIGNMENT, force=True)
    if not res.get("success"):
        sys.exit(f"nbgrader generate_assignment failed:\n{(res.get('error') or res.get('log') or '')[-3000:]}")


def nbgrader_api(course: Path):
    """nbgrader's own Python API (``NbGraderAPI``) on ``course``, in this process.

    The same steps as the ``nbgrader`` command, without a new interpreter each: one import of
    nbgrader serves the whole batch (an import cost 2.5 s on the recording host; see
    benchmarks/grading_wallclock.txt).
    """
    from .feedback_html import FeedbackHTMLExporter
    from nbgrader.apps import NbGraderAPI
    from nbgrader.coursedir import CourseDirectory
    from traitlets.config import PyFileConfigLoader

    os.environ["PATH"] = tool_env()["PATH"]     # a new gradebook runs the venv's `alembic`
    config = PyFileConfigLoader("nbgrader_config.py", path=str(course)).load_config()
    config.CourseDirectory.root = str(course)
    config.CourseDirectory.db_url = f"sqlite:///{course / 'gradebook.db'}"
    # nbconvert's HTMLExporter, less the BeautifulSoup round trip that was half of each student's
    # feedback time, and made safe: no script survives, a Content-Security-Policy forbids any
    # (feedback_html.py); otherwise the pages are nbconvert's documents
    config.GenerateFeedback.exporter_class = FeedbackHTMLExporter
    return NbGraderAPI(coursedir=CourseDirectory(config=config), config=config)


def course_bundle(course: Path) -> bytes:
    """What a grading task needs of the course, as one zip: nbgrader's config, the assignment's
    source and release versions and an empty gradebook (no other student, no manual grades). It
    is built once per batch; a Dask worker on another machine receives it once."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.write(course / "nbgrader_config.py", "nbgrader_config.py")
        for sub in ("source", "release"):
            for p in sorted((course / sub).rglob("*")):
                if p.is_file():
                    zf.write(p, p.relative_to(course).as_posix())
        zf.write(course / "gradebook.template.db", "gradebook.db")
    return buf.getvalue()


def private_course(bundle: bytes, student: str, notebooks: dict, work: Path) -> Path:
    """A copy of the course with only this student in it; the kernel sees none of it but its folder."""
    priv = work / "course"
    priv.mkdir(parents=True)
    with zipfile.ZipFile(io.BytesIO(bundle)) as zf:
        zf.extractall(priv)           # our own zip: names were written by course_bundle above
    dest = priv / "submitted" / student / ASSIGNMENT
    dest.mkdir(parents=True)
    for name, nb in notebooks.items():
        (dest / name).write_text(nb, encoding="utf-8")          # notebook JSON text
    (dest / "timestamp.txt").write_text("2026-01-01 00:00:00.000000 UTC")   # fixed: regrades match
    return priv


def _last_error(text: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip() and "NbGraderException" not in line]
    for line in reversed(lines):
        if "Error" in line or "error" in line:
            return line.strip()[:300]
    return (lines[-1] if lines else "nbgrader failed")[:300]


COURSE_LOCK = ".grading.lock"        # in the course folder while a grading run holds it


def _lock_holder(fd: int) -> str:
    """What the holder of a course lock wrote of itself (it writes just after it locks)."""
    for _ in range(20):
        text = os.pread(fd, 200, 0).decode(errors="replace").strip()
        if text:
            return text
        time.sleep(0.05)
    return "a process that has not said its pid yet"


class course_lock:
    """Hold the course folder ``course`` for one grading run: ``with course_lock(course, log): ...``

    Everything a run writes lives there (gradebook.db, graded.json, feedback/, shared_stages/), so
    two runs on one folder at once (a regrade started while a batch runs) would corrupt each other.
    The lock is an ``flock`` on ``course/.grading.lock``, which says who holds it (pid, host, since
    when); a second run logs that and waits. The kernel drops the lock of a holder that dies; the
    holder removes the file when it is done, still holding it (a waiter that then gets a removed
    file sees so and locks the new one)."""

    def __init__(self, course: Path, log=print):
        self.path, self.log, self.fd = Path(course) / COURSE_LOCK, log, None

    def __enter__(self) -> Path:
        import fcntl
        import socket

        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    self.log(f"waiting for another grading run of this course to finish: {_lock_holder(fd)} "
                             f"holds {self.path}")
                    fcntl.flock(fd, fcntl.LOCK_EX)
                try:
                    current = os.stat(self.path, follow_symlinks=False)
                except FileNotFoundError:
                    current = None
                mine = os.fstat(fd)
                if current is not None and (current.st_dev, current.st_ino) == (mine.st_dev, mine.st_ino):
                    break
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)             # the run before removed this file on its way out: lock the new one
        self.fd = fd
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}, grading since "
                      f"{time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode(), 0)
        return self.path

    def __exit__(self, *exc) -> None:
        self.path.unlink(missing_ok=True)      # before the lock goes: see the class's doc
        os.close(self.fd)
        self.fd = None


def _one_run_per_course(fn):
    """``fn`` (grade_class) runs holding its ``course`` argument's folder (``course_lock``)."""
    import functools
    import inspect

    signature = inspect.signature(fn)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        with course_lock(Path(bound.arguments["course"]).resolve(), bound.arguments["log"]):
            return fn(*args, **kwargs)
    return run
