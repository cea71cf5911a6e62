"""This checkout's pipeline against an older commit's, cold, interleaved, on this machine.

    python -m benchmarks.bench_vs [--old af06280] [--repeats 3] [--seed 0] [--notebooks | --sweeps]

Checks the old commit out into a temporary git worktree and runs, alternately, its
``python -m pusht.dreamer --seed 0 --no-cache`` and this checkout's (default config, a fresh
process each: torch import and expert-data collection included), ``--repeats`` times each, with the
same interpreter and packages; the old code is imported from its worktree (the current folder
comes first on ``sys.path``). Prints each run, the medians and their ratio. Interleaving puts
both under the same background load, so the ratio is fairer than two separate runs' figures.

``--notebooks`` times notebooks 01-05 instead: each run executes the tree's own solution notebooks
01 to 05 in order at the default config (papermill, as ``make chapter`` does, with that tree's
``scripts/chapter.py``) into a fresh folder, so every stage is computed (cold) and later notebooks
reuse what earlier ones cached, as in a learner's session; the kernels import the tree's package
(PYTHONPATH). Prints each notebook's seconds and the medians of the totals.

``--sweeps`` times just the sweeps of notebooks 04 (seeds 0-2) and 05 (horizons 5/15/30 x actor
seeds 0-2) with each tree's ``pusht.sweep.run_many``, at the default config, from a stage cache
that holds what the notebooks before them leave (seed 0's world model and agent, computed once
per tree): the part of those notebooks that the sweep's scheduling decides.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.bench import host_description

ROOT = Path(__file__).resolve().parents[1]


def one_run(tree: Path, seed: int, out: Path) -> float:
    cmd = [sys.executable, "-m", "pusht.dreamer", "--seed", str(seed), "--out", str(out), "--no-cache", "--quiet"]
    t = time.perf_counter()
    subprocess.run(cmd, cwd=tree, check=True, capture_output=True, text=True)
    return time.perf_counter() - t


NOTEBOOK_RUN = """
import json, sys, time
from pathlib import Path
tree, out = Path(sys.argv[1]), Path(sys.argv[2])
from scripts.chapter import execute   # the tree's: PYTHONPATH is the tree (an old tree's scripts/, with no
                                      # __init__.py, imports as a namespace package)
seconds = {}
for nb in sorted((tree / "solutions").glob("0[1-5]_*.ipynb")):
    t = time.perf_counter()
    execute(nb, out, smoke=False)
    seconds[nb.name] = time.perf_counter() - t
print(json.dumps(seconds))
"""


SWEEP_RUN = """
import json, shutil, sys, time
from pathlib import Path
from pusht.config import make_config
from pusht.dreamer import run
from pusht.sweep import run_many
prepared, out = Path(sys.argv[1]), Path(sys.argv[2])
cfg = make_config(seed=0)
if not prepared.exists():      # what notebooks 01-03 leave in the cache: seed 0's stages
    run(cfg, cache_dir=prepared, model_cache=prepared, log=None)
seconds = {}
for name, cfgs in (("04", [cfg.replace(seed=s) for s in (0, 1, 2)]),
                   ("05", [cfg.replace(imag_horizon=h, actor_seed=a) for h in (5, 15, 30) for a in (0, 1, 2)])):
    shutil.copytree(prepared, out / name)
    t = time.perf_counter()
    run_many(cfgs, cache_dir=out / name, model_cache=out / name)
    seconds[name] = time.perf_counter() - t
print(json.dumps(seconds))
"""


def child_seconds(tree: Path, script: str, *args, cwd: Path) -> dict:
    """Run ``script`` in a fresh Python that imports ``tree``'s package; the JSON it prints last."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    proc = subprocess.run([sys.executable, "-c", script, *map(str, args)], cwd=cwd, env=env,
                          check=True, capture_output=True, text=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def sweeps_run(tree: Path, prepared: Path, out: Path) -> dict:
    """Notebooks 04's and 05's sweeps with ``tree``'s package, from the stage cache ``prepared``."""
    return child_seconds(tree, SWEEP_RUN, prepared, out, cwd=tree)


def imports_old(old: Path, cwd: Path, env=None) -> None:
    """Fail unless a Python started in ``cwd`` with ``env`` imports the package from ``old``."""
    which = subprocess.run([sys.executable, "-c", "import pusht; print(pusht.__file__)"], cwd=cwd, env=env,
                           check=True, capture_output=True, text=True).stdout.strip()
    assert Path(which).resolve().is_relative_to(old.resolve()), f"the old code is not the one imported: {which}"


def notebooks_run(tree: Path, out: Path) -> dict:
    """Notebooks 01-05 of ``tree`` at the default config, in order, into ``out``: {name: seconds}."""
    out.mkdir(parents=True)
    return child_seconds(tree, NOTEBOOK_RUN, tree, out, cwd=out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--old", default="af06280")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--notebooks", action="store_true", help="time notebooks 01-05 instead of the pipeline")
    mode.add_argument("--sweeps", action="store_true", help="time notebooks 04's and 05's sweeps instead")
    args = p.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench-vs-"))
    old = tmp / "old"
    subprocess.run(["git", "worktree", "add", "--detach", str(old), args.old], cwd=ROOT, check=True,
                   capture_output=True)
    try:
        imports_old(old, cwd=old)
        if args.notebooks or args.sweeps:    # started outside the tree: PYTHONPATH must do it
            imports_old(old, cwd=tmp, env={**os.environ, "PYTHONPATH": str(old)})
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.strip()
        what = ("notebooks 01-05" if args.notebooks else "the sweeps of notebooks 04 and 05" if args.sweeps
                else f"the pipeline, seed {args.seed}")
        print(f"host: {host_description()}, python {platform.python_version()}; "
              f"{args.old} vs this checkout ({head}, with any uncommitted changes): {what}, "
              f"default config, cold", flush=True)
        times = {"old": [], "new": []}
        for r in range(args.repeats):
            for name, tree in (("old", old), ("new", ROOT)):
                if args.notebooks:
                    each = notebooks_run(tree, tmp / f"{name}{r}")
                    s = sum(each.values())
                    detail = ", ".join(f"{n[:2]} {v:.1f}" for n, v in each.items())
                    print(f"  run {r + 1} {name}: {s:.1f} s ({detail})", flush=True)
                elif args.sweeps:
                    each = sweeps_run(tree, tmp / f"{name}-prepared", tmp / f"{name}{r}")
                    s = sum(each.values())
                    print(f"  run {r + 1} {name}: {s:.1f} s (04 {each['04']:.1f}, 05 {each['05']:.1f})", flush=True)
                else:
                    s = one_run(tree, args.seed, tmp / f"{name}{r}")
                    print(f"  run {r + 1} {name}: {s:.1f} s", flush=True)
                times[name].append(s)
        mo, mn = statistics.median(times["old"]), statistics.median(times["new"])
        print(f"median {args.old}: {mo:.1f} s; median now: {mn:.1f} s; now / old = {mn / mo:.2f}")
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT, capture_output=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
