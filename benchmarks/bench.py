"""Speed figures for the chapter, printed and written to benchmarks/wallclock.csv.

    python -m benchmarks.bench [--repeats 3]

* env: real-sim steps per second under uniformly random actions;
* pipeline cold: ``python -m pusht.dreamer`` at the default config, seed 0, in a fresh process
  with no expert-data cache (process wall-clock, torch import included);
* pipeline warm: the same with the expert data already cached on disk;
* the per-phase split (from the run's timing.json) and the peak memory (max RSS) of the process;
* start-up: a process that only imports the package (Python, torch, pymunk) and exits, the floor
  under every process-wall figure above;
* two yardsticks of the host itself, so figures from different machines can be told apart from
  changes in the code: single-thread matrix-multiply throughput (``host_sgemm_gflops``) and the
  cost of one small ``nn.Linear`` call (``host_small_linear_us``), the per-operation overhead that
  bounds this chapter's tiny models.

Speed is measured here, never asserted in a test: this machine has 2 cores and is noisy, so each
figure is the median of ``--repeats`` runs. Each run APPENDS its rows to the CSV with the time, the
host (CPU model and family) and the git commit, so the file keeps the history: the same code can
be twice as fast on a newer CPU, and the yardsticks show when that is what happened.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def env_steps_per_second(n_episodes: int = 20) -> float:
    from pusht.env import PushTEnv

    env, rng, n = PushTEnv(), np.random.default_rng(0), 0
    actions = rng.uniform(-1, 1, (n_episodes, 300, 2))
    t = time.perf_counter()
    for ep in range(n_episodes):
        env.reset(ep)
        for a in actions[ep]:
            n += 1
            if env.step(a)[2]:
                break
    return n / (time.perf_counter() - t)


def pipeline(out: Path, cache: Path | None) -> dict:
    """One fresh process of the default pipeline: wall-clock, peak RSS, phase split."""
    cmd = [sys.executable, "-m", "pusht.dreamer", "--seed", "0", "--out", str(out), "--quiet"]
    cmd += ["--cache", str(cache)] if cache else ["--no-cache"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
                   env={**os.environ, "PYTHONPATH": str(ROOT)})
    wall = time.perf_counter() - t
    peak_mb = max(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, before) / 1024
    return {"wall_s": wall, "peak_mb": peak_mb, **json.loads((out / "timing.json").read_text())}


def startup_seconds() -> float:
    """Process wall-clock of importing the package and exiting, as the CLI does (no work)."""
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import gc, pusht.dreamer; gc.freeze()"], check=True,
                   cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    return time.perf_counter() - t


def host_yardsticks(repeats: int) -> tuple[float, float]:
    """(single-thread sgemm GFLOP/s on 1024x1024 matrices, microseconds per Linear(80->64) call on a
    batch of 64): the host's arithmetic speed and its per-operation overhead."""
    import torch

    torch.set_num_threads(1)
    a, b = torch.randn(1024, 1024), torch.randn(1024, 1024)
    layer, x = torch.nn.Linear(80, 64), torch.randn(64, 80)
    gflops, us = [], []
    with torch.no_grad():
        for _ in range(repeats):
            a @ b
            t = time.perf_counter()
            for _ in range(20):
                a @ b
            gflops.append(20 * 2 * 1024 ** 3 / (time.perf_counter() - t) / 1e9)
            for _ in range(500):
                layer(x)
            t = time.perf_counter()
            for _ in range(5000):
                layer(x)
            us.append((time.perf_counter() - t) / 5000 * 1e6)
    return float(np.median(gflops)), float(np.median(us))


def host_description() -> str:
    """The run's platform fingerprint (as meta.yaml records it) plus the CPU model and family, from
    /proc/cpuinfo where there is one."""
    from pusht.fingerprint import platform_fingerprint

    from pusht.host import cpu_model

    fp, cpu = platform_fingerprint(), cpu_model(family=True)
    return f"{fp['machine']} {cpu}, {os.cpu_count()} cores, torch {fp['torch']} ({fp['cpu_capability']})"


def git_commit() -> str:
    """Short commit of the code measured, with '+dirty' if tracked files other than the CSV differ
    from it."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":!benchmarks/wallclock.csv"], cwd=ROOT, capture_output=True,
                               text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


HEADER = ["measured_at", "tier", "machine", "figure", "value", "unit", "notes", "commit"]


def append_rows(path: Path, rows: list[list]) -> None:
    """Append ``rows`` under HEADER; rows of an older file without the commit column get ''."""
    old = []
    if path.exists():
        with open(path, newline="") as f:
            old = list(csv.reader(f))
        if old and old[0] != HEADER:
            if old[0] != HEADER[:-1]:
                raise SystemExit(f"{path} has unexpected columns {old[0]}; move it aside and re-run")
            old = [HEADER] + [r + [""] for r in old[1:]]
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows((old or [HEADER]) + rows)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--csv", type=Path, default=ROOT / "benchmarks" / "wallclock.csv")
    args = p.parse_args(argv)

    rows = []
    gflops, op_us = host_yardsticks(args.repeats)
    rows.append(("host_sgemm_gflops", gflops, "GFLOP/s", "1024x1024 float32 matmul, one thread"))
    rows.append(("host_small_linear_us", op_us, "us", "one nn.Linear(80, 64) call on a batch of 64"))
    print(f"host: {gflops:.0f} GFLOP/s sgemm (one thread), {op_us:.1f} us per small Linear call")
    sps = float(np.median([env_steps_per_second() for _ in range(args.repeats)]))
    rows.append(("env_steps_per_s", sps, "steps/s", "random actions, 10 substeps each"))
    print(f"env: {sps:,.0f} steps/s")
    start = float(np.median([startup_seconds() for _ in range(args.repeats)]))
    rows.append(("startup", start, "s", "import the package and exit, fresh process"))
    print(f"start-up (import python, torch, pymunk; exit): {start:.2f} s")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cold = [pipeline(tmp / f"cold{i}", None) for i in range(args.repeats)]
        pipeline(tmp / "fill", tmp / "cache")                   # fill the cache once
        warm = [pipeline(tmp / f"warm{i}", tmp / "cache") for i in range(args.repeats)]
    for name, runs in (("cold", cold), ("warm", warm)):
        med = {k: float(np.median([r[k] for r in runs])) for k in runs[0]}
        print(f"pipeline {name}: {med['wall_s']:.2f} s wall (process), peak {med['peak_mb']:.0f} MB; "
              f"data {med['data_s']:.2f} s, world model {med['world_model_s']:.2f} s, "
              f"imagination {med['imagination_s']:.2f} s, eval {med['eval_s']:.2f} s")
        print(f"  fastest of {len(runs)}: {min(r['wall_s'] for r in runs):.2f} s wall; in-process "
              f"(timing.json total) {med['total_s']:.2f} s")
        rows.append((f"pipeline_{name}_wall", med["wall_s"], "s", "default config, seed 0, fresh process"))
        rows.append((f"pipeline_{name}_wall_fastest", min(r["wall_s"] for r in runs), "s",
                     "fastest single run, same command"))
        rows.append((f"pipeline_{name}_in_process", med["total_s"], "s",
                     "timing.json total_s: from run() start to its end, no start-up"))
        for k in ("data_s", "world_model_s", "imagination_s", "eval_s"):
            rows.append((f"pipeline_{name}_{k[:-2]}", med[k], "s", "in-script phase"))
        rows.append((f"pipeline_{name}_peak_rss", med["peak_mb"], "MB", "max resident set size"))

    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    machine, commit = host_description(), git_commit()
    append_rows(args.csv, [[stamp, "cpu", machine, name, f"{value:.3f}", unit,
                            (f"{note}; {'fastest' if name.endswith('fastest') else 'median'} of "
                             f"{args.repeats}"), commit] for name, value, unit, note in rows])
    print(f"appended {len(rows)} rows to {args.csv} ({machine}; commit {commit})")


if __name__ == "__main__":
    main()
