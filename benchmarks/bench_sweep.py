"""A sweep's runs one after the other in this process, against run_many's worker processes.

    python -m benchmarks.bench_sweep [--horizons 5 30] [--actor-seeds 1 2] [--workers N] [--seed 0]

The sweep is notebook 05's kind: actors of several (horizon, actor seed) pairs on one frozen world
model of ``--seed`` at the default config. The world model is trained once first, and each mode
starts from its own copy of that cache (the model in it, no agent), so both train exactly the
same actors. Prints both wall-clocks, their ratio, the peak resident memory of the largest worker
(``pusht.sweep.WORKER_BYTES`` is sized from it) and whether every run's metrics and curves are
bit-identical between the two modes (they must be).
"""

from __future__ import annotations

import argparse
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.bench import host_description

from pusht.config import make_config
from pusht.dreamer import run, world_model_stage
from pusht.sweep import WORKER_BYTES, default_workers, run_many

ROOT = Path(__file__).resolve().parents[1]


def same(a, b) -> bool:
    return a.metrics == b.metrics and all(np.array_equal(a.history[k], b.history[k]) for k in a.history)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--horizons", type=int, nargs="+", default=[5, 30])
    p.add_argument("--actor-seeds", type=int, nargs="+", default=[1, 2])
    p.add_argument("--workers", type=int, default=None, help="default: pusht.sweep.default_workers")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    cfg = make_config(seed=args.seed)
    cfgs = [cfg.replace(imag_horizon=h, actor_seed=a) for h in args.horizons for a in args.actor_seeds]
    workers = args.workers or default_workers(cfgs)
    print(f"host: {host_description()}; {len(cfgs)} runs (horizons {args.horizons} x actor seeds "
          f"{args.actor_seeds}) on the world model of seed {args.seed}, default config")
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        world_model_stage(cfg, base, base, log=None)
        caches = {m: Path(tmp) / m for m in ("here", "pool")}
        for c in caches.values():
            shutil.copytree(base, c)
        t = time.perf_counter()
        here = [run(c, cache_dir=caches["here"], model_cache=caches["here"], log=None) for c in cfgs]
        t_here = time.perf_counter() - t
        t = time.perf_counter()
        pool = run_many(cfgs, cache_dir=caches["pool"], model_cache=caches["pool"], workers=workers)
        t_pool = time.perf_counter() - t
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024     # Linux: kB; the workers
    identical = all(same(a, b) for a, b in zip(here, pool))
    print(f"  one after the other in this process: {t_here:.1f} s")
    print(f"  run_many, {workers} workers: {t_pool:.1f} s  ({t_here / t_pool:.2f}x faster)")
    print(f"  largest worker's peak resident memory: {peak / 2**20:.0f} MiB "
          f"(pusht.sweep.WORKER_BYTES budgets {WORKER_BYTES / 2**20:.0f} MiB)")
    print(f"  every run's metrics and curves bit-identical between the two: {identical}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
