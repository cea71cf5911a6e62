"""Grade a whole class in one command: LMS download -> scores, feedback HTML and a grades CSV.

    python autograde/grade.py SUBMISSIONS [--course autograde] [--timeout 120]

SUBMISSIONS is a .zip as the LMS hands it over, or a folder. Each file is a student's downloaded
notebook (from Jupyter or Colab), named ``<student_id>_<notebook>.ipynb`` (for example
``s042_04_imagination_gap.ipynb``), or it lives at ``<student_id>/<notebook>.ipynb``.

What happens, per student, and why no submission can stop the batch:

1. the file is read as a notebook; if it is not one, the student scores 0 for it and the report
   says what to re-upload (the rest of their work, and everyone else's, is graded as usual);
2. Colab's extra metadata is removed; a locked test cell the student deleted is put back (nbgrader
   already restores edited ones), so tests always run on the instructor's version;
3. the prediction receipts printed in the student's own outputs are checked: the completion points
   of Exercises 1 and 2 need the prediction locked BEFORE the experiment ran;
4. ``nbgrader autograde`` executes everything in a fresh kernel (reduced config, a per-cell
   timeout, errors recorded and execution continued), then the completion grades, the manual
   grades from ``manual_grades.csv`` and the mark scheme are written into the gradebook;
5. ``nbgrader generate_feedback`` writes one HTML page per notebook, and ``grades.csv`` plus
   ``report.csv`` (what was wrong with each file) land in the course folder.

Grading again gives the same grades: manual grades live in the course folder's
``manual_grades.csv`` (edit it or use ``python autograde/manual_grade.py``) and are re-applied
after every run.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from datetime import datetime
from pathlib import Path

import nbformat
import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
COURSE = yaml.safe_load((ROOT / "course.yaml").read_text())
ASSIGNMENT = COURSE["assignment"]
COURSE_ID = "zero2robot-ch3.2"      # the same as in nbgrader_config.py
NOTEBOOKS = sorted(p.name for p in (ROOT / "solutions").glob("*.ipynb"))
NAME_RE = re.compile(r"^(?P<student>[A-Za-z0-9.-]+)_(?P<notebook>\d\d_[A-Za-z0-9_]+?)(?:[ (-]*\d*\)?)?\.ipynb$")
LOCK_RE = re.compile(r"\[prediction locked\] (?P<ex>ex\d): \((?P<choice>[abc])\) at (?P<at>\S+)")
RUN_RE = re.compile(r"\[experiment started\] (?P<ex>ex\d) at (?P<at>\S+) \(prediction locked at (?P<locked>\S+)\)")
COLAB_KEYS = ("executionInfo", "colab", "outputId", "id")   # cell metadata Colab adds
# The completion task cell of each predict-then-run exercise: "<ex>_order".
EXERCISES = {"ex1": "04_imagination_gap", "ex2": "05_horizon"}


def tool_env() -> dict:
    """nbgrader shells out to `alembic`: make this interpreter's scripts folder visible."""
    return {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}


def nbgrader(course: Path, *args: str, timeout: int | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "nbgrader", *args, f"--CourseDirectory.root={course}",
           f"--CourseDirectory.db_url=sqlite:///{course / 'gradebook.db'}"]
    if timeout:
        cmd.append(f"--Execute.timeout={timeout}")
    return subprocess.run(cmd, cwd=course, capture_output=True, text=True, env=tool_env())


# --- 1. collect -----------------------------------------------------------------------------------
def collect(submissions: Path) -> tuple[dict[str, dict[str, bytes]], list[str]]:
    """{student: {notebook file name: raw bytes}} and a list of files that could not be placed."""
    files: dict[str, bytes] = {}
    if submissions.suffix == ".zip":
        with zipfile.ZipFile(submissions) as zf:
            for info in zf.infolist():
                if not info.is_dir():
                    files[info.filename] = zf.read(info)
    else:
        for path in sorted(submissions.rglob("*")):
            if path.is_file():
                files[str(path.relative_to(submissions))] = path.read_bytes()
    by_student: dict[str, dict[str, bytes]] = {}
    unplaced = []
    for name, data in sorted(files.items()):
        parts = Path(name).parts
        if len(parts) >= 2 and f"{Path(name).stem[:2]}".isdigit():
            student, base = parts[-2], parts[-1]
            notebook = Path(base).stem
        else:
            m = NAME_RE.match(Path(name).name)
            if not m:
                unplaced.append(f"{name}: name does not look like <student_id>_<notebook>.ipynb")
                continue
            student, notebook = m["student"], m["notebook"]
        match = [nb for nb in NOTEBOOKS if nb.startswith(notebook[:2] + "_")]
        if not match:
            unplaced.append(f"{name}: no notebook {notebook!r} in this assignment")
            continue
        by_student.setdefault(student, {})[match[0]] = data
    return by_student, unplaced


# --- 2. clean and repair ---------------------------------------------------------------------------
def read_notebook(data: bytes):
    """The notebook, or raise ValueError saying why it is not one."""
    try:
        nb = nbformat.reads(data.decode("utf-8"), as_version=4)
    except Exception as e:   # JSON, encoding or schema problems all mean "not a notebook"
        raise ValueError(f"not a valid notebook file ({type(e).__name__}: {str(e)[:120]})") from None
    return nb


def clean_colab(nb) -> bool:
    """Drop the metadata Colab adds; True if there was any."""
    found = False
    for key in ("colab", "accelerator", "gpuClass"):
        found |= nb.metadata.pop(key, None) is not None
    nb.metadata.setdefault("kernelspec", {"display_name": "Python 3", "language": "python", "name": "python3"})
    for cell in nb.cells:
        for key in COLAB_KEYS[:3]:
            found |= cell.metadata.pop(key, None) is not None
    return found


def restore_locked_cells(nb, release) -> list[str]:
    """Put back locked graded cells the student deleted, after the cell that precedes them in the
    release. Returns the grade ids restored."""
    def gid(cell):
        return cell.metadata.get("nbgrader", {}).get("grade_id")

    present = {gid(c) for c in nb.cells if gid(c)}
    restored = []
    for i, cell in enumerate(release.cells):
        meta = cell.metadata.get("nbgrader", {})
        if meta.get("locked") and meta.get("grade") and gid(cell) not in present:
            prev = {gid(c) or c.get("id") for c in release.cells[:i]}
            pos = max([j + 1 for j, c in enumerate(nb.cells) if (gid(c) or c.get("id")) in prev], default=len(nb.cells))
            nb.cells.insert(pos, nbformat.from_dict(json.loads(json.dumps(cell))))
            present.add(gid(cell))
            restored.append(gid(cell))
    return restored


# --- 3. receipts -----------------------------------------------------------------------------------
def receipt_verdict(nb, exercise: str) -> tuple[bool, str]:
    """Did the student's own outputs show the prediction locked before the experiment ran?"""
    text = "\n".join(o.get("text", "") if isinstance(o.get("text"), str) else "".join(o.get("text", []))
                     for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    locks = [m for m in LOCK_RE.finditer(text) if m["ex"] == exercise]
    runs = [m for m in RUN_RE.finditer(text) if m["ex"] == exercise]
    if not runs:
        return False, f"{exercise}: no experiment receipt in your notebook (run the experiment cell)"
    if not locks and "already locked" not in text:
        return False, f"{exercise}: no prediction receipt in your notebook (run the lock cell)"
    run = runs[0]
    try:
        started, locked = datetime.fromisoformat(run["at"]), datetime.fromisoformat(run["locked"])
    except ValueError:
        return False, f"{exercise}: the receipts are unreadable (were they edited?)"
    lock_times = {m["at"] for m in locks}
    if locks and run["locked"] not in lock_times and "already locked" not in text:
        return False, f"{exercise}: the experiment used a prediction that this notebook never locked"
    if f"[warning] {exercise}: the experiment already ran" in text or locked >= started:
        return False, f"{exercise}: the experiment ran before the prediction was locked"
    return True, f"{exercise}: prediction locked at {run['locked']}, experiment ran at {run['at']}: in order"


# --- the whole batch -------------------------------------------------------------------------------
def prepare_course(course: Path) -> None:
    """Copy solutions/ into the course's source folder and (re)generate the assignment."""
    src = course / "source" / ASSIGNMENT
    src.mkdir(parents=True, exist_ok=True)
    for path in (ROOT / "solutions").glob("*.ipynb"):
        shutil.copy(path, src / path.name)
    if course.resolve() != HERE:
        shutil.copy(HERE / "nbgrader_config.py", course / "nbgrader_config.py")
    proc = nbgrader(course, "generate_assignment", ASSIGNMENT, "--force")
    if proc.returncode != 0:
        sys.exit(f"nbgrader generate_assignment failed:\n{proc.stderr[-3000:]}")


def autograde(course: Path, students: list[str], timeout: int, jobs: int, log=print) -> None:
    """``nbgrader autograde`` each student, ``jobs`` at a time (one process per student).

    A student whose run fails (for example when both processes write the gradebook at once) is
    retried alone, so a failure can only cost time, never a grade.
    """
    from concurrent.futures import ThreadPoolExecutor

    def one(student):
        return student, nbgrader(course, "autograde", ASSIGNMENT, "--force", f"--student={student}",
                                 timeout=timeout)

    with ThreadPoolExecutor(max(1, jobs)) as pool:
        failed = [s for s, proc in pool.map(one, students) if proc.returncode != 0]
    for student in failed:
        _, proc = one(student)
        if proc.returncode != 0:
            log(f"nbgrader autograde failed for {student} (the others are graded):\n{proc.stderr[-1500:]}")


def grade_class(submissions: Path, course: Path = HERE, timeout: int = 120, jobs: int = 2,
                log=print) -> dict:
    """Grade every submission in ``submissions``; returns the per-student report."""
    course = course.resolve()
    prepare_course(course)
    by_student, unplaced = collect(submissions)
    for line in unplaced:
        log(f"skipped {line}")
    release = {name: nbformat.read(course / "release" / ASSIGNMENT / name, as_version=4)
               for name in NOTEBOOKS}
    report = {s: {"notes": [], "completion": {}} for s in by_student}

    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for student in by_student:
            gb.update_or_create_student(student)
    for student, notebooks in by_student.items():
        dest = course / "submitted" / student / ASSIGNMENT
        shutil.rmtree(dest, ignore_errors=True)
        dest.mkdir(parents=True)
        for name, data in notebooks.items():
            try:
                nb = read_notebook(data)
            except ValueError as e:
                report[student]["notes"].append(f"{name}: {e}; it scores 0. Re-upload it "
                                                f"(Jupyter/Colab: File > Download > .ipynb).")
                continue
            if clean_colab(nb):
                report[student]["notes"].append(f"{name}: saved by Colab; its extra metadata was removed")
            for gid in restore_locked_cells(nb, release[name]):
                report[student]["notes"].append(f"{name}: the locked test cell '{gid}' was missing and "
                                                f"was put back; never delete test cells")
            for ex, nb_stem in EXERCISES.items():
                if name.startswith(nb_stem):
                    report[student]["completion"][ex] = receipt_verdict(nb, ex)
            nbformat.write(nb, dest / name)
        (dest / "timestamp.txt").write_text("2026-01-01 00:00:00.000000 UTC")   # fixed: regrades match

    autograde(course, [s for s in by_student if any((course / "submitted" / s / ASSIGNMENT).glob("*.ipynb"))],
              timeout, jobs, log)
    apply_grades(course, report)
    nbgrader(course, "generate_feedback", ASSIGNMENT, "--force")
    export(course, report)
    return report


def apply_grades(course: Path, report: dict) -> None:
    """Completion grades from the receipts, then manual grades and the mark scheme."""
    from nbgrader.api import Gradebook, MissingEntry

    scheme = yaml.safe_load((HERE / "mark_scheme.yaml").read_text()) if (HERE / "mark_scheme.yaml").exists() else {}
    manual = {}
    if (course / "manual_grades.csv").exists():
        with open(course / "manual_grades.csv", newline="") as f:
            for row in csv.DictReader(f):
                manual[(row["student_id"], row["notebook"], row["grade_id"])] = row
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for student, rep in report.items():
            for name in NOTEBOOKS:
                nb_id = name[:-len(".ipynb")]
                try:
                    sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                except MissingEntry:
                    continue
                for grade in sub.grades:
                    gid, comment_text = grade.name, None
                    ex = gid[:-len("_order")] if gid.endswith("_order") else None
                    if ex in rep["completion"]:
                        ok, why = rep["completion"][ex]
                        grade.manual_score = grade.max_score if ok else 0.0
                        comment_text = why
                    elif gid in scheme:
                        comment_text = f"Mark scheme: {scheme[gid]}"
                    row = manual.get((student, nb_id, gid))
                    if row:
                        grade.manual_score = float(row["score"])
                        comment_text = (row.get("comment") or "") + (f"\n\n{comment_text}" if comment_text else "")
                    if comment_text is not None:
                        try:
                            c = gb.find_comment(gid, nb_id, ASSIGNMENT, student)
                            c.manual_comment = comment_text
                        except MissingEntry:
                            pass
            gb.db.commit()


def export(course: Path, report: dict) -> None:
    """grades.csv (nbgrader's export) and report.csv (what happened to each file)."""
    nbgrader(course, "export", f"--CsvExportPlugin.filename={course / 'grades.csv'}")
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb, \
            open(course / "report.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["student_id", "score", "max_score", "notes"])
        for student in sorted(report):
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
                score, max_score = sub.score, sub.max_score
            except MissingEntry:
                score, max_score = 0.0, gb.find_assignment(ASSIGNMENT).max_score
            notes = report[student]["notes"] + [why for _, why in report[student]["completion"].values()]
            w.writerow([student, round(score, 3), round(max_score, 3), " | ".join(notes)])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("submissions", type=Path, help="a .zip from the LMS, or a folder of notebooks")
    p.add_argument("--course", type=Path, default=HERE, help="nbgrader course folder (default: autograde/)")
    p.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    p.add_argument("--jobs", type=int, default=2, help="students graded at once (one per core)")
    args = p.parse_args(argv)
    if not args.submissions.exists():
        p.error(f"{args.submissions} does not exist")
    report = grade_class(args.submissions, args.course, args.timeout, args.jobs)
    print(f"graded {len(report)} students: scores in {args.course / 'grades.csv'}, per-file notes in "
          f"{args.course / 'report.csv'}, feedback in {args.course / 'feedback'}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
