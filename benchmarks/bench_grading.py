"""How long one complete submission takes to grade, confined and not.

    python -m benchmarks.bench_grading [--executed DIR] [--repeats 1]

Executes the solution notebooks in smoke mode (or reuses ``--executed``), zips them as one
student's upload, and times ``grade.grade_class`` on it in a fresh course folder, once with the
bubblewrap sandbox and once without. Prints one line per run, then where the confined run's time
went (the course's nbgrader steps, and each notebook's nbgrader autograde, kernel included, which
run ``--jobs`` at a time); the figures belong to this host.
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import autograde.course
from autograde import grade, sandbox, schedule
from autograde.classes.synthetic import build

ROOT = Path(__file__).resolve().parents[1]


def executed_notebooks(executed: Path | None, tmp: Path) -> Path:
    """``executed``, or (None) the solution notebooks executed now in smoke mode, under ``tmp``."""
    if executed is None:
        from scripts.chapter import execute

        executed = tmp / "executed"
        executed.mkdir()
        for nb in sorted((ROOT / "solutions").glob("*.ipynb")):
            execute(nb, executed, smoke=True)
    return executed


def command_line(doc: str, argv, repeats: int, prefix: str):
    """The grading benchmarks' two options, parsed; and a fresh folder for the run."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    p.add_argument("--executed", type=Path, help="executed solution notebooks (default: run them now, smoke mode)")
    p.add_argument("--repeats", type=int, default=repeats)
    return p.parse_args(argv), Path(tempfile.mkdtemp(prefix=prefix))


def main(argv=None) -> int:
    args, tmp = command_line(__doc__, argv, 1, "bench-grading-")
    executed = executed_notebooks(args.executed, tmp)
    subs = tmp / "one.zip"
    with zipfile.ZipFile(subs, "w") as zf:
        for name, data in build(executed).items():
            if name.startswith("perfect_"):
                zf.writestr(name, data)
    phases = {}

    def timed(name, fn):
        def wrapper(*a, **k):
            t = time.perf_counter()
            out = fn(*a, **k)
            phases[name] = phases.get(name, 0.0) + time.perf_counter() - t
            if name == "grade_task":
                for nb, entry in out["results"].items():
                    phases[f"  autograde {nb} (nbgrader, kernel included)"] = entry.get("seconds", float("nan"))
            return out
        return wrapper

    for name in ("prepare_course", "record", "sanitize_feedback_sources", "generate_feedback", "export"):
        setattr(grade, name, timed(name, getattr(grade, name)))      # as grade_class looks them up
    schedule.grade_task = timed("grade_task", schedule.grade_task)    # as run_local looks it up
    api = autograde.course.nbgrader_api
    autograde.course.nbgrader_api = lambda course: _timed_api(api(course), phases)
    modes = [True, False] if sandbox.available()[0] else [False]
    print(f"host: {platform.processor() or platform.machine()}, {sys.platform}, python {platform.python_version()}")
    for _ in range(args.repeats):
        for confine in modes:
            course = Path(tempfile.mkdtemp(prefix="course-", dir=tmp))
            t = time.perf_counter()
            report = grade.grade_class(subs, course, timeout=120, confine=confine, log=lambda *a: None,
                                       progress=False)
            seconds = time.perf_counter() - t
            score = sum(v[0] for v in report["perfect"]["verdicts"].values())
            print(f"one complete submission, {'confined' if confine else 'NOT confined'}: {seconds:.1f} s "
                  f"(test points {score:g})", flush=True)
            if confine or len(modes) == 1:
                print("  where it went (grade_task: summed over notebooks, which run in parallel):")
                for name, sec in phases.items():
                    print(f"  {sec:7.1f} s  {name}")
            phases.clear()
    return 0


def _timed_api(api, phases):
    """Wrap an NbGraderAPI so that generate_assignment / generate_feedback are timed."""
    for name in ("generate_assignment", "generate_feedback"):
        fn = getattr(api, name)

        def wrapper(*a, _fn=fn, _name=name, **k):
            t = time.perf_counter()
            out = _fn(*a, **k)
            phases[f"nbgrader {_name}"] = phases.get(f"nbgrader {_name}", 0.0) + time.perf_counter() - t
            return out
        setattr(api, name, wrapper)
    return api


if __name__ == "__main__":
    sys.exit(main())
