"""Grading a whole synthetic class: seconds per student, and whether sharing changed any score.

    python -m benchmarks.bench_class [--students 40] [--kinds perfect,colab,...] [--executed DIR]
                                     [--jobs N] [--compare N|all] [--scheduler ADDRESS]

Builds a class of ``--students`` students by cycling through the synthetic hand-ins of
``autograde/classes/synthetic.py`` (correct, Colab-saved, wrong, out-of-order prediction, invalid
prediction, raising, tampered, not a notebook; ``loops``, a cell that never returns, is left out:
its cost is the per-cell timeout, which an instructor sets; ``--kinds perfect``: complete correct
hand-ins only), each under its own id and each a
complete hand-in of six notebooks (the kind's faulty ones in place of correct ones), and grades it
once as ``make grade`` would (default parallelism, stages shared, confined where bubblewrap is
here). Prints the wall time and the seconds per student, amortised. ``--compare`` then grades
that many of the students (or all) again, one at a time, each in its own batch, without shared
stages, and checks that every score is identical. The figures belong to this host.
"""

from __future__ import annotations

import argparse
import csv
import platform
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from autograde import grade, sandbox, schedule
from autograde.course import ASSIGNMENT, COURSE_ID
from autograde.classes.synthetic import build

from benchmarks.bench import host_description
from benchmarks.bench_grading import executed_notebooks

ROOT = Path(__file__).resolve().parents[1]


KINDS = ("perfect", "colab", "wrong", "order", "badpred", "raises", "tamper", "garbage")


def class_zip(executed: Path, n: int, dest: Path, kinds=KINDS) -> list[str]:
    """A zip of ``n`` students cycling through ``kinds``; returns their ids. Every student hands in all
    six notebooks: the correct ones, with the kind's own notebooks in place of those it replaces
    (the synthetic kinds other than ``perfect`` hand in only the notebooks they get wrong)."""
    members = build(executed)
    ids = []
    with zipfile.ZipFile(dest, "w") as zf:
        for i in range(n):
            kind = kinds[i % len(kinds)]
            sid = f"{kind}{i:03d}"
            ids.append(sid)
            files = {name[len("perfect_"):]: data for name, data in members.items() if name.startswith("perfect_")}
            files.update({name[len(kind) + 1:]: data for name, data in members.items() if name.startswith(f"{kind}_")})
            for name, data in sorted(files.items()):
                zf.writestr(f"{sid}_{name}", data)
    return ids


def scores(course: Path) -> dict:
    """{student: {(notebook, grade id): score}} from the course gradebook, plus the CSV's totals."""
    from nbgrader.api import Gradebook

    out = {}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for sub in gb.find_assignment(ASSIGNMENT).submissions:
            out[sub.student.id] = {(nb.name, g.name): g.score for nb in sub.notebooks for g in nb.grades}
    with open(course / "grades.csv", newline="") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["student_id"], {})[("total", "raw_score")] = float(row["raw_score"])
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--students", type=int, default=40)
    p.add_argument("--kinds", default=",".join(KINDS), help=f"synthetic kinds to cycle through (default: all of {', '.join(KINDS)})")
    p.add_argument("--executed", type=Path, help="executed solution notebooks (default: run them now, smoke mode)")
    p.add_argument("--jobs", type=int, default=None, help="default: one per core, as make grade")
    p.add_argument("--compare", default="0", help="grade this many students (or 'all') again one at a time, unshared")
    p.add_argument("--scheduler", default=None, help="grade on this Dask scheduler instead of here")
    args = p.parse_args(argv)
    kinds = tuple(k for k in args.kinds.split(",") if k)
    unknown = set(kinds) - set(KINDS)
    if unknown or not kinds:
        p.error(f"--kinds: unknown {', '.join(sorted(unknown)) or 'none given'}; choose from {', '.join(KINDS)}")
    tmp = Path(tempfile.mkdtemp(prefix="bench-class-"))
    subs = tmp / "class.zip"
    ids = class_zip(executed_notebooks(args.executed, tmp), args.students, subs, kinds)
    jobs = args.jobs or schedule.default_jobs()
    print(f"host: {host_description()}, python "
          f"{platform.python_version()}; confined: {sandbox.available()[0]}; {len(ids)} students "
          f"({', '.join(kinds)}, cycled); jobs {jobs}", flush=True)
    course = tmp / "class"
    t = time.perf_counter()
    grade.grade_class(subs, course, jobs=args.jobs, scheduler=args.scheduler, log=lambda *a: print(*a, flush=True))
    wall = time.perf_counter() - t
    print(f"class of {len(ids)}: {wall:.0f} s, {wall / len(ids):.1f} s per student amortised "
          f"(500 students: {wall / len(ids) * 500 / 3600:.1f} h)", flush=True)
    together = scores(course)
    n = len(ids) if args.compare == "all" else int(args.compare)
    if n:
        # spread the compared students over the kinds
        pick = sorted(ids, key=lambda s: (int(s[-3:]) // len(kinds), s))[:n]
        mismatched, alone_seconds = [], []
        for sid in pick:
            one = tmp / f"{sid}.zip"
            with zipfile.ZipFile(subs) as src, zipfile.ZipFile(one, "w") as zf:
                for name in src.namelist():
                    if name.startswith(f"{sid}_"):
                        zf.writestr(name, src.read(name))
            c = tmp / f"alone-{sid}"
            t = time.perf_counter()
            grade.grade_class(one, c, jobs=args.jobs, share=False, log=lambda *a: None, progress=False)
            alone_seconds.append(time.perf_counter() - t)
            alone = scores(c).get(sid, {})
            if alone != together.get(sid, {}):
                mismatched.append(sid)
        print(f"{len(pick)} students graded again one at a time without shared stages "
              f"({sum(alone_seconds) / len(pick):.1f} s each): "
              + ("every score identical" if not mismatched else f"DIFFERENT scores for {mismatched}"), flush=True)
        return 1 if mismatched else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
