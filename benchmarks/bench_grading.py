"""How long one complete submission takes to grade, confined and not.

    python benchmarks/bench_grading.py [--executed DIR] [--repeats 1]

Executes the five solution notebooks in smoke mode (or reuses ``--executed``), zips them as one
student's upload, and times ``grade.grade_class`` on it in a fresh course folder, once with the
bubblewrap sandbox and once without. Prints one line per run; the figures belong to this host.
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "autograde"))
sys.path.insert(0, str(ROOT / "scripts"))

import grade  # noqa: E402
import sandbox  # noqa: E402
from synthetic_class import build  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--executed", type=Path, help="executed solution notebooks (default: run them now)")
    p.add_argument("--repeats", type=int, default=1)
    args = p.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench-grading-"))
    executed = args.executed
    if executed is None:
        from chapter import execute

        executed = tmp / "executed"
        executed.mkdir()
        for nb in sorted((ROOT / "solutions").glob("*.ipynb")):
            execute(nb, executed, smoke=True)
    subs = tmp / "one.zip"
    with zipfile.ZipFile(subs, "w") as zf:
        for name, data in build(executed).items():
            if name.startswith("perfect_"):
                zf.writestr(name, data)
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
