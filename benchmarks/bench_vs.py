"""This checkout's pipeline against an older commit's, cold, interleaved, on this machine.

    python benchmarks/bench_vs.py [--old af06280] [--repeats 3] [--seed 0]

Checks the old commit out into a temporary git worktree and runs, alternately, its
``python -m pusht.dreamer --seed 0 --no-cache`` and this checkout's (default config, a fresh
process each: torch import and expert-data collection included), ``--repeats`` times each, with the
same interpreter and packages; the old code is imported from its worktree (the current folder
comes first on ``sys.path``). Prints each run, the medians and their ratio. Interleaving puts
both under the same background load, so the ratio is fairer than two separate runs' figures.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def one_run(tree: Path, seed: int, out: Path) -> float:
    cmd = [sys.executable, "-m", "pusht.dreamer", "--seed", str(seed), "--out", str(out), "--no-cache", "--quiet"]
    t = time.perf_counter()
    subprocess.run(cmd, cwd=tree, check=True, capture_output=True, text=True)
    return time.perf_counter() - t


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--old", default="af06280")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench-vs-"))
    old = tmp / "old"
    subprocess.run(["git", "worktree", "add", "--detach", str(old), args.old], cwd=ROOT, check=True,
                   capture_output=True)
    try:
        which = subprocess.run([sys.executable, "-c", "import pusht; print(pusht.__file__)"], cwd=old,
                               check=True, capture_output=True, text=True).stdout.strip()
        assert Path(which).resolve().is_relative_to(old.resolve()), f"old code not imported from its worktree: {which}"
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.strip()
        print(f"host: {platform.processor() or platform.machine()}, python {platform.python_version()}; "
              f"{args.old} vs this checkout ({head}, with any uncommitted changes), seed {args.seed}, "
              f"default config, cold", flush=True)
        times = {"old": [], "new": []}
        for r in range(args.repeats):
            for name, tree in (("old", old), ("new", ROOT)):
                s = one_run(tree, args.seed, tmp / f"{name}{r}")
                times[name].append(s)
                print(f"  run {r + 1} {name}: {s:.1f} s", flush=True)
        mo, mn = statistics.median(times["old"]), statistics.median(times["new"])
        print(f"median {args.old}: {mo:.1f} s; median now: {mn:.1f} s; now / old = {mn / mo:.2f}")
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT, capture_output=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
