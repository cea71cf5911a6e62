"""Grade a whole class in one command: LMS download -> scores, feedback HTML and a grades CSV.

    python -m autograde.grade SUBMISSIONS [--course course] [--timeout 120] [--jobs N]

SUBMISSIONS is a .zip as the LMS hands it over, or a folder: each student's downloaded notebooks
(Jupyter or Colab), named ``<student_id>_<notebook>.ipynb`` or placed in ``<student_id>/``
folders (``intake`` says exactly what is accepted and what is refused).

This module is the front: ``grade_class`` and the command line. Student code is untrusted
(docs/grader.md, "Student code is treated as hostile"); each step is a module of this package:

1. ``intake``: the download read in memory (hostile names refused, nothing written outside the
   course), LMS ids normalised, the newest of several uploads picked, look-alike ids noted;
2. ``prepare``: each notebook repaired (``repair``), its receipts read (``receipts``), each graded
   function followed through it (``delegation``) and compared with the package's answer
   (``answer_key``); nothing runs;
3. ``schedule`` runs grading tasks (``task``), here or on a Dask cluster, after ``stages`` has
   computed the stages no student can change, once. A task runs the student's notebooks through
   nbgrader in confined kernels (``worker``, ``sandbox``) for the outputs and receipts, and has
   each hidden test probed in a sandbox of its own where the package's answers do not exist
   (``probe``, ``stripped``) and judged (``checks``). A failure in one notebook costs only that
   notebook; one student's failure, nobody else's;
4. only this process writes the course's gradebook (``gradebook``): every student's scores,
   completion points and manual grades (``manual_grades.csv``); then the feedback pages
   (``feedback``: hidden tests removed, outputs capped, no script), ``grades.csv`` (nbgrader's
   export of that gradebook) and ``report.csv``.

Grading again gives the same grades: manual grades live in ``manual_grades.csv`` and are
re-applied after every run.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
import warnings
from pathlib import Path

import nbformat

from . import guarantees, intake, sandbox
from .class_report import write_class_report
from .course import ASSIGNMENT, COURSE_DIR, HERE, NOTEBOOKS, _one_run_per_course, course_bundle, prepare_course
from .feedback import generate_feedback, sanitize_feedback_sources
from .gradebook import clear_submissions, export, record
from .lms_export import write_lms_exports
from .lms_feedback import write_feedback_return
from .prepare import prepare_student
from .schedule import _split, default_jobs, run_tasks
from .stages import SHARE_FROM, grader_fingerprint, shared_stages, submission_fingerprint
from .text import spreadsheet_text
from .to_grade import write_to_grade


STATE_FILE = "graded.json"           # per student: what was graded (fingerprint) and its results


@_one_run_per_course
def grade_class(submissions: Path, course: Path = COURSE_DIR, timeout: int = 120, jobs: int | None = None,
                log=print, confine: bool | None = None, limits: dict | None = None,
                progress: bool = True, scheduler=None, share: bool | None = None,
                regrade: bool = False) -> dict:
    """Grade every submission in ``submissions``; returns the per-student report.

    ``scheduler``: a Dask scheduler address (or ``distributed.Client``) to grade on its workers;
    None grades here, ``jobs`` tasks at once (default: one per core). ``share``: compute the
    stages that depend on no student (expert data, the world models and actors the notebooks
    train from the package's own code at the grading config) once, by grading the instructor's
    solutions first, and let every student's kernel read them (None: when there are at least
    SHARE_FROM students to grade). ``regrade``: grade again students whose submission, and
    everything else that decides their results, did not change since the last run in ``course``
    (by default their recorded results are reused).

    The whole run holds the course folder (``course_lock``): a second run on the same folder
    waits for this one, and says whose run it waits for. It first says which of the sandbox's
    guarantees hold here (``guarantees.of_run``: logged, then the first rows of ``report.csv`` and
    the first section of the class report).
    """
    from tqdm.auto import tqdm

    course = course.resolve()
    _refuse_empty(submissions)           # before anything in the course folder is touched
    limits = {**sandbox.DEFAULT_LIMITS, **(limits or {})}
    ok, why = sandbox.available()
    if confine is None:
        confine = ok
    if confine and not ok:
        raise RuntimeError(f"confined grading was asked for, but {why}")
    if not confine:
        msg = (f"WARNING: submissions are NOT confined ({why or 'confinement switched off'}): "
               f"student code runs as you, with your files in reach. Install bubblewrap to confine it.")
        log(msg)
        warnings.warn(msg, stacklevel=2)
    held = guarantees.of_run(confine, why, limits, scheduler)   # which protections hold here, said first
    for line in guarantees.lines(held):
        log(line)
    if course != HERE and (HERE / "gradebook.db").exists():      # the course folder of earlier versions
        log(f"NOTE: autograde/ still holds a gradebook.db and the other outputs of grading from before they "
            f"moved to the course folder; git no longer ignores them there: move them to {course} or delete them")
    prepare_course(course)
    shutil.copy(course / "gradebook.db", course / "gradebook.template.db")
    release = {name: nbformat.read(course / "release" / ASSIGNMENT / name, as_version=4) for name in NOTEBOOKS}
    got = intake.collect(submissions, NOTEBOOKS, release=release)     # each file known by its content
    for line in got.rejected:
        log(f"skipped {line}")
    for line in got.warnings:            # e.g. look-alike ids not checked: PyICU is missing
        log(f"WARNING: {line}")
        warnings.warn(line, stacklevel=2)
    report = {s: {"notes": list(got.notes.get(s, [])), "completion": {}, "verdicts": {}, "failed": {},
                  "lms": got.lms.get(s),          # the LMS's own identity, for its import file
                  "name": student_name(got, s),   # shown beside the id, never a key
                  "human": [h for h in got.human if h["student"] == s],   # files their names did not place
                  "submitted_at": submitted_at(got, s)}                  # for grades.csv's timestamp
              for s in got.students}
    prepared = {}
    for s, uploads in got.students.items():
        nbs, notes, completion, delegated = prepare_student(uploads, release)
        report[s]["notes"] += notes
        report[s]["completion"] = completion
        report[s]["delegated"] = delegated
        prepared[s] = nbs
    jobs = jobs or default_jobs()
    students = sorted(s for s in prepared if prepared[s])

    # Unchanged since the last run (same notebooks, same grader): reuse the recorded results.
    grader = grader_fingerprint(timeout, confine, limits)
    state_path = course / STATE_FILE
    state = json.loads(state_path.read_text()) if state_path.exists() else {}
    prints = {s: submission_fingerprint(prepared[s], grader) for s in students}
    results = {}
    for s in students:
        old = state.get(s, {})
        folder = course / "autograded" / s / ASSIGNMENT
        # a notebook nbgrader could not finish has a stand-in page (outputs.stand_in), not a graded
        # copy: it is graded again, as before there was a page for it
        if not regrade and old.get("fingerprint") == prints[s] and \
                all((folder / n).is_file() and (not isinstance(r, dict) or r.get("ok", True))
                    for n, r in old.get("results", {}).items()):
            results[s] = old["results"]
    if results:
        log(f"{len(results)} of {len(students)} students unchanged since the last grading: their results "
            f"are reused (regrade to grade them again)")
    todo = [s for s in students if s not in results]
    for s in todo:
        shutil.rmtree(course / "autograded" / s / ASSIGNMENT, ignore_errors=True)

    bundle = course_bundle(course)
    settings = dict(timeout=timeout, confine=confine, limits=limits)
    shared = None
    if share is None:
        share = len(todo) >= SHARE_FROM
    if share and todo:
        shared = shared_stages(bundle, course, jobs, scheduler, log=log, **settings)

    def submit_args(task):
        s, names = task
        return (bundle, s, {n: nbformat.writes(prepared[s][n]) for n in names}, timeout, confine, limits, shared)

    left = {}
    tasks = _split(todo, prepared, jobs if scheduler is None else 1)
    for s, _ in tasks:
        left[s] = left.get(s, 0) + 1
    where = f"on Dask at {getattr(scheduler, 'scheduler', None) and scheduler.scheduler.address or scheduler}" \
        if scheduler is not None else f"{jobs} at a time"
    with tqdm(total=len(todo), desc=f"grading ({where})", unit="student", disable=not progress) as bar:
        def on_done(task, out):
            s, _ = task
            results.setdefault(s, {}).update(out["results"])
            dest = course / "autograded" / s / ASSIGNMENT
            dest.mkdir(parents=True, exist_ok=True)
            for name, text in out["autograded"].items():
                (dest / name).write_text(text, encoding="utf-8")
            left[s] -= 1
            if not left[s]:                  # the bar counts students: all their tasks done
                name = report[s].get("name")
                bar.set_postfix_str(spreadsheet_text(f"{name} ({s})" if name else s)[:40])
                bar.update()
        run_tasks(tasks, jobs, scheduler, submit_args, on_done, log)
    state = {s: {"fingerprint": prints[s], "results": results[s]} for s in students if s in results}
    state_path.write_text(json.dumps(state, indent=1, sort_keys=True))
    clear_submissions(course, report)
    phases = {}
    t = time.perf_counter()
    record(course, report, results)
    sanitize_feedback_sources(course, report)
    phases["gradebook"], t = time.perf_counter() - t, time.perf_counter()
    for student, error in generate_feedback(course, [s for s in report if results.get(s)], jobs, log).items():
        report[student]["notes"].append(f"no feedback pages: {error}")
    phases["feedback pages"], t = time.perf_counter() - t, time.perf_counter()
    for s in report:                   # nbgrader's autograde of this student's notebooks, kernels included
        times = [r["seconds"] for r in results.get(s, {}).values() if isinstance(r, dict) and "seconds" in r]
        report[s]["seconds"] = round(sum(times), 2) if times else None
    export(course, report, got.rejected, held)
    write_to_grade(course, report, log=log)   # the answers a person grades, one row each (manual_grade --from-csv)
    phases["grades.csv, report.csv, to_grade.csv"], t = time.perf_counter() - t, time.perf_counter()
    write_lms_exports(course, report, log=log)
    phases["LMS import files"], t = time.perf_counter() - t, time.perf_counter()
    try:
        write_class_report(course, report, submitted=prepared, guarantees=held)
    except Exception as e:  # noqa: BLE001 - the report must never cost the grades
        log(f"WARNING: no class report ({type(e).__name__}: {e})")
    phases["class report"], t = time.perf_counter() - t, time.perf_counter()
    try:                                  # the feedback each LMS takes back (lms_feedback)
        write_feedback_return(course, report, log=log)
    except Exception as e:  # noqa: BLE001 - the packages must never cost the grades
        log(f"WARNING: no feedback packages ({type(e).__name__}: {e}); python -m autograde.lms_feedback "
            f"makes them again")
    phases["feedback packages"] = time.perf_counter() - t
    log("after grading: " + ", ".join(f"{name} {sec:.1f} s" for name, sec in phases.items()))
    return report


def _refuse_empty(submissions: Path) -> None:
    """A download that names no student (an empty folder, the wrong zip, a zip of only system
    files) is refused with ``intake.LayoutError`` before any output of an earlier grading is
    rewritten: grading it would overwrite grades.csv, the import files and the class report with
    a class of nobody."""
    got = intake.collect(submissions, NOTEBOOKS)
    if got.students:
        return
    seen = "; ".join(got.rejected[:5]) + (f"; and {len(got.rejected) - 5} more" if len(got.rejected) > 5 else "")
    raise intake.LayoutError(
        f"{submissions} holds no student's submission, so nothing was graded and no file was changed"
        + (f" (what it holds: {seen})" if seen else " (it is empty)")
        + ". Expected the LMS's download of the assignment, or <student>_<notebook>.ipynb or "
          "<student>/<notebook>.ipynb files")


def submitted_at(got: intake.Intake, student: str) -> str | None:
    """When the student handed in, as the download says: the LMS's own time where its names carry
    one (Blackboard's attempt), else the newest graded file's time in the download (a zip entry's
    date, or the file's modification time), local time without a zone; None with no file."""
    lms = got.lms.get(student) or {}
    if lms.get("submitted_at"):
        return str(lms["submitted_at"]).replace("T", " ")
    times = [u.mtime for u in (got.students.get(student) or {}).values()]
    return f"{max(times):%Y-%m-%d %H:%M:%S}" if times else None


def student_name(got: intake.Intake, student: str) -> str | None:
    """The student's name as the download wrote it: the LMS's (Moodle's full name, Blackboard's
    receipt name, Canvas's file-name form of it), else the id as written where it differs from the
    folder-safe one (``Ann Lee`` for ``Ann_Lee``); None where there is none."""
    lms = got.lms.get(student) or {}
    if lms.get("name"):
        return str(lms["name"])
    written = got.display_names.get(student)
    return written if written and written != student else None


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("submissions", type=Path, help="a .zip from the LMS, or a folder of notebooks")
    p.add_argument("--course", type=Path, default=COURSE_DIR,
                   help="the course folder, where everything grading writes goes (default: course/)")
    p.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    p.add_argument("--jobs", type=int, default=None, help="grading tasks at once (default: one per core); fewer students than that split their notebooks")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="grade on a Dask cluster, e.g. tcp://10.0.0.5:8786 (docs/scale.md: 'Beyond one machine: Dask')")
    p.add_argument("--regrade", action="store_true",
                   help="grade again students whose submissions did not change since the last run")
    p.add_argument("--share", choices=("auto", "yes", "no"), default="auto",
                   help=f"compute the stages no student can change once, from the solutions (auto: from {SHARE_FROM} students)")
    p.add_argument("--no-confine", action="store_true",
                   help="run student code unconfined (only for trusted notebooks; prints a warning)")
    args = p.parse_args(argv)
    if not args.submissions.exists():
        p.error(f"{args.submissions} does not exist")
    try:
        report = grade_class(args.submissions, args.course, args.timeout, args.jobs,
                             confine=False if args.no_confine else None, scheduler=args.scheduler,
                             share={"auto": None, "yes": True, "no": False}[args.share], regrade=args.regrade)
    except intake.LayoutError as e:      # e.g. a download that mixes two LMSs' layouts
        p.error(str(e))
    print(f"graded {len(report)} students: scores in {args.course / 'grades.csv'}, per-file notes in "
          f"{args.course / 'report.csv'}, feedback in {args.course / 'feedback'}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
