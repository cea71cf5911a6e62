"""Hand grading in one pass, timed: a class's one-sentence answers applied from to_grade.csv.

    python -m benchmarks.bench_manual_csv [--students 30] [--executed DIR] [--jobs N]
                                          [--no-feedback] [--csv benchmarks/wallclock.csv]

Issue 39's target: 30 students x 3 sentences (ex1-ex3_sentence, notebooks 04-06) applied in under
30 s on a quiet host. Builds a course of ``--students`` students graded with nothing run: the real
assignment (``prepare_course``: nbgrader's generate_assignment on solutions/, the real gradebook of
six notebooks), each student's autograded notebooks (``--executed``: executed solution notebooks,
whose outputs make pages of a real size; default: the release notebooks, no outputs, so the pages
are smaller than a real class's), every sentence answered, scores recorded through
``gradebook.record`` as grading does and the feedback sources sanitised as grading does. None of
that is timed. Then it writes ``to_grade.csv`` (``write_to_grade``, timed on its own), fills every
score, and applies it with ``python -m autograde.manual_grade --from-csv``'s function
(``manual_grade.apply_sheet``), timing two parts apart:

* gradebook + CSV: reading and checking the sheet, manual_grades.csv, the gradebook, grades.csv;
* feedback pages: the one ``generate_feedback`` call for every student touched (``--jobs``, default
  one per core), skipped with ``--no-feedback``; then grades.csv, the import file and the feedback
  packages made again from the report grading saved (``manual_grade.refresh_returns``), timed with it.

Prints the figures; ``--csv`` also appends them to that file (bench.py's columns). The figures
belong to this host and to how busy it is.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# The feedback processes it starts import this tree's autograde too (python -m from the root gives it
# to this process; the editable install may point at another checkout).
os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])

SENTENCES = {"04_imagination_gap": "ex1_sentence", "05_horizon": "ex2_sentence", "06_closing_the_gap": "ex3_sentence"}


def build_course(course: Path, students: int, executed: Path | None) -> dict:
    """A graded class in ``course``, made without running a notebook; returns grade_class's report."""
    import nbformat
    from nbgrader.api import Gradebook

    from autograde import gradebook
    from autograde.cellcode import gid
    from autograde.course import ASSIGNMENT, COURSE_ID, NOTEBOOKS, prepare_course
    from autograde.feedback import sanitize_feedback_sources

    course.mkdir(parents=True, exist_ok=True)
    prepare_course(course)
    source = executed or course / "release" / ASSIGNMENT
    ids = [f"canvas_{48200 + i}" for i in range(students)]
    report, results = {}, {}
    for n, s in enumerate(ids):
        report[s] = {"notes": [], "completion": {}, "verdicts": {}, "failed": {}, "delegated": {},
                     "lms": {"system": "canvas", "name": f"Student {n:02d}", "ids": {"user_id": str(48200 + n)},
                             "late": False, "submitted_at": None, "attempt": 1}}
        results[s] = {}
        folder = course / "autograded" / s / ASSIGNMENT
        folder.mkdir(parents=True)
        for name in NOTEBOOKS:
            nb = nbformat.read(source / name, as_version=4)
            scores = {}
            for cell in nb.cells:
                g = gid(cell)
                if g is None:
                    continue
                if g == SENTENCES.get(name[:-len(".ipynb")]):
                    cell.source = (f"Student {n:02d}: the actor learned to please the dream, whose block moves "
                                   f"without contact, so the real block stays where it was.")
                    scores[g] = None                      # answered: waits for a person
                elif (cell.get("metadata", {}).get("nbgrader") or {}).get("grade"):
                    scores[g] = 0.0
            nbformat.write(nb, folder / name)
            results[s][name] = {"ok": True, "scores": scores, "verdicts": {}}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for s in ids:
            gb.update_or_create_student(s)
        gb.db.commit()
    gradebook.record(course, report, results)
    sanitize_feedback_sources(course, report)
    from autograde.lms_feedback import write_feedback_return
    write_feedback_return(course, report, log=lambda _: None)   # as grading leaves it: applying remakes it
    return report


def fill(path: Path) -> int:
    """Every sentence row of the sheet given a score and a comment; returns how many."""
    from autograde.to_grade import COLUMNS

    raw = path.read_bytes().decode("utf-8-sig")
    rows = list(csv.DictReader(io.StringIO(raw, newline="")))
    n = 0
    for i, r in enumerate(rows):
        if r["grade_id"] in SENTENCES.values():
            r["score"], r["comment"] = ("1" if i % 3 else "0.5"), "Names both halves."
            n += 1
    with open(path, "w", newline="", encoding="utf-8-sig") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        w.writerows(rows)
    return n


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--students", type=int, default=30)
    p.add_argument("--executed", type=Path, help="executed solution notebooks, used as the autograded ones")
    p.add_argument("--jobs", type=int, default=None, help="feedback processes (default: one per core)")
    p.add_argument("--no-feedback", action="store_true", help="time the gradebook + CSV part only")
    p.add_argument("--csv", type=Path, help="append the figures to this file (bench.py's columns)")
    args = p.parse_args(argv)

    from autograde import manual_grade
    from autograde.schedule import default_jobs
    from autograde.to_grade import write_to_grade

    jobs = args.jobs or default_jobs()
    tmp = Path(tempfile.mkdtemp(prefix="bench-manual-csv-"))
    try:
        course = tmp / "course"
        t = time.perf_counter()
        report = build_course(course, args.students, args.executed)
        print(f"class of {args.students} built (not timed): {time.perf_counter() - t:.1f} s", flush=True)

        t = time.perf_counter()
        sheet = write_to_grade(course, report)
        t_sheet = time.perf_counter() - t
        filled = fill(sheet)

        feedback = {"seconds": 0.0, "calls": 0, "students": 0}
        real = manual_grade.generate_feedback

        def timed_feedback(course_, students, jobs, log=print, **kw):
            feedback["calls"] += 1
            feedback["students"] += len(students)
            if args.no_feedback:
                return {}
            t0 = time.perf_counter()
            try:
                return real(course_, students, jobs, log=log, **kw)
            finally:
                feedback["seconds"] += time.perf_counter() - t0

        manual_grade.generate_feedback = timed_feedback
        try:
            t = time.perf_counter()
            out = manual_grade.apply_sheet(sheet, course, jobs=jobs, log=lambda line: print(line, file=sys.stderr))
            total = time.perf_counter() - t
        finally:
            manual_grade.generate_feedback = real
        assert len(out["applied"]) == filled, (len(out["applied"]), filled)
        assert feedback["calls"] == 1 and feedback["students"] == args.students, feedback
        pages = len(list((course / "feedback").rglob("*.html"))) if (course / "feedback").is_dir() else 0
        part = total - feedback["seconds"]
        print(f"to_grade.csv written: {t_sheet:.2f} s ({filled} sentences of {args.students} students)")
        print(f"applied {filled} grades for {len(out['students'])} students:")
        print(f"  gradebook + CSV (check, manual_grades.csv, gradebook, grades.csv, import file, packages): {part:.2f} s")
        if args.no_feedback:
            print("  feedback pages: not made (--no-feedback)")
        else:
            print(f"  feedback pages ({jobs} processes, one call, {pages} pages): {feedback['seconds']:.2f} s")
            print(f"  total: {total:.2f} s (target: under 30 s for 30 students x 3 sentences, quiet host)")
            if out["feedback_errors"]:
                print(f"  feedback errors: {out['feedback_errors']}")
        if args.csv:
            from benchmarks.bench import HEADER, append_rows, git_commit, host_description  # noqa: F401
            from datetime import datetime, timezone

            when, host, commit = datetime.now(timezone.utc).replace(microsecond=0).isoformat(), host_description(), git_commit()
            note = f"{args.students} students x 3 sentences via manual_grade --from-csv"
            rows = [[when, "cpu", host, "manual_csv_sheet", f"{t_sheet:.3f}", "s", "write_to_grade; " + note, commit],
                    [when, "cpu", host, "manual_csv_gradebook", f"{part:.3f}", "s", "gradebook + CSV; " + note, commit]]
            if not args.no_feedback:
                rows += [[when, "cpu", host, "manual_csv_feedback", f"{feedback['seconds']:.3f}", "s",
                          f"one generate_feedback call, {jobs} processes; " + note, commit],
                         [when, "cpu", host, "manual_csv_total", f"{total:.3f}", "s", note, commit]]
            append_rows(args.csv, rows)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
