"""Where the default pipeline's wall-clock goes, one fresh process per repeat.

    python -m benchmarks.bench_pipeline [--repeats 3] [--seed 0]

Each repeat starts a new interpreter (cold, as ``python -m pusht.dreamer`` is) and times, in order:
``import torch``; the rest of ``import pusht.dreamer``; the first optimizer step (``pusht.optim.Adam``;
before it, the chapter used ``torch.optim.Adam``, whose first call imports ``torch._dynamo``, 1.3 s
once per process: ``--torch-optim`` times that instead);
then the pipeline's own phases from ``run()``'s ``timing`` (expert data, world model, imagination,
evaluation), with the stage cache off. Prints one row per repeat and the medians. The phases are
the same timing.json split ``bench.py`` records as medians in wallclock.csv; what this adds is the
split of what comes before ``run()`` and every repeat's row. ``bench_vs.py`` compares whole runs
against an older commit.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from benchmarks.bench import host_description  # CPU model and family, as wallclock.csv names hosts

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
import torch
t1 = time.perf_counter()
from pusht.config import make_config
from pusht.dreamer import run
t2 = time.perf_counter()
_p = torch.zeros(1, requires_grad=True)
if sys.argv[2] == "torch":
    torch.optim.Adam([_p]).zero_grad()
else:
    from pusht.optim import Adam
    _o = Adam([_p], lr=1e-3); _p.sum().backward(); _o.step()
t3 = time.perf_counter()
res = run(make_config(seed=int(sys.argv[1])), log=None)
t4 = time.perf_counter()
print(json.dumps({"import_torch_s": t1 - t0, "import_pusht_s": t2 - t1, "first_optimizer_s": t3 - t2,
                  **{k: v for k, v in res.timing.items() if k != "total_s"}, "run_s": t4 - t3,
                  "process_s": t4 - t0, "dynamo_imported": "torch._dynamo" in sys.modules}))
"""

COLUMNS = ("import_torch_s", "import_pusht_s", "first_optimizer_s", "data_s", "world_model_s",
           "imagination_s", "eval_s", "process_s")


def one(seed: int, optimizer: str = "pusht") -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", CHILD, str(seed), optimizer], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--torch-optim", action="store_true",
                   help="time a first torch.optim.Adam (imports torch._dynamo) before run()")
    args = p.parse_args(argv)
    print(f"host: {host_description()}; seed {args.seed}, default config, no stage cache, "
          f"a fresh process per repeat")
    print("  " + " ".join(f"{c[:-2]:>17}" for c in COLUMNS))
    rows = []
    for _ in range(args.repeats):
        row = one(args.seed, "torch" if args.torch_optim else "pusht")
        rows.append(row)
        print("  " + " ".join(f"{row[c]:17.2f}" for c in COLUMNS)
              + ("  (torch._dynamo imported)" if row["dynamo_imported"] else ""), flush=True)
    print("  " + " ".join(f"{statistics.median(r[c] for r in rows):17.2f}" for c in COLUMNS) + "  (median, s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
