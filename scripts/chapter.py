"""The chapter's main job: execute all five instructor notebooks at the default config, in order.

    python scripts/chapter.py [--out runs/chapter] [--smoke]

Each notebook runs headless with papermill into ``--out`` (executed notebooks, figures under
figures/, per-seed metrics under metrics/, and the model cache shared between notebooks). At the
end it prints the headline table from the metrics the notebooks wrote.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = [("imagined_return_per_step", "imagined r/step", "+.3f"),
           ("real_return_per_step", "real r/step", "+.3f"),
           ("imagination_gap", "gap", "+.3f"),
           ("imagined_final_tee_dist", "dream tee-dist m", ".3f"),
           ("real_final_tee_dist", "real tee-dist m", ".3f"),
           ("spawn_tee_dist", "spawn tee-dist m", ".3f"),
           ("real_success_rate", "real success", ".2f")]


def headline_table(metrics_dir: Path) -> str:
    rows = []
    for path in sorted(metrics_dir.glob("seed*.json")):
        m = json.loads(path.read_text())
        rows.append([path.stem] + [format(m[key], fmt) for key, _, fmt in COLUMNS])
    header = ["run"] + [title for _, title, _ in COLUMNS]
    widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in rows]
    return "\n".join(lines)


def execute(nb: Path, out: Path, smoke: bool) -> None:
    """Run one instructor notebook headless into ``out`` with papermill, parameters SMOKE and OUT.

    Raises ``papermill.PapermillExecutionError`` naming the failing cell. On Linux and macOS the
    kernel talks to papermill over Unix sockets in a private temporary folder instead of TCP ports
    on localhost: nothing here needs the network, and ipykernel would otherwise print a warning
    about unencrypted TCP at every kernel start.
    """
    import papermill as pm
    from traitlets.config import Config

    with tempfile.TemporaryDirectory(prefix="pusht-kernel-") as sockets:
        config = Config()
        if os.name == "posix":
            config.KernelManager.transport = "ipc"
            config.KernelManager.ip = os.path.join(sockets, "k")
        pm.execute_notebook(str(nb), str(out / nb.name), kernel_name="python3", cwd=str(out),
                            parameters={"SMOKE": smoke, "OUT": str(out)}, progress_bar=False,
                            config=config)


def main(argv=None) -> int:
    import papermill as pm

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "chapter")
    p.add_argument("--smoke", action="store_true", help="the tiny config (seconds per notebook)")
    args = p.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    for nb in sorted((ROOT / "solutions").glob("*.ipynb")):
        t = time.perf_counter()
        print(f"running {nb.name} ...", flush=True)
        try:
            execute(nb, out, args.smoke)
        except pm.PapermillExecutionError as e:
            print(f"FAILED: {nb.name}, cell {e.cell_index}: {e.ename}: {e.evalue}\n"
                  f"the executed notebook with the error is {out / nb.name}", file=sys.stderr)
            return 1
        print(f"  done in {time.perf_counter() - t:.0f} s -> {out / nb.name}", flush=True)
    print(f"\nall notebooks ran in {time.perf_counter() - t0:.0f} s; figures in {out / 'figures'}\n")
    if list((out / "metrics").glob("seed*.json")):
        print("The same policy, two worlds (30 held-out starts per seed unless --smoke):")
        print(headline_table(out / "metrics"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
