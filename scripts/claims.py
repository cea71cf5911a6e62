"""``make claims``: run notebooks 03-07 on seeds 0-9 and record every claim they evaluated.

    python -m scripts.claims [--seeds 0 1 2 3 4 5 6 7 8 9] [--out runs/claims] [--smoke] [--record]

Each notebook runs headless (papermill, as ``make chapter`` runs it) with ``SEED`` set, all seeds
sharing one model cache under ``--out``; notebook 04 compares its ``SEED`` with the two seeds after
it, notebook 05 sweeps its actor seeds on the world model of ``SEED``. Every claim a notebook
evaluates (``pusht.nb.claims``) is appended to a log per notebook and seed, through the environment
variable ``PUSHT_CLAIMS_LOG`` that the kernel inherits. At the end the logs become one table:

* ``<out>/claims.json``: every evaluation, with the numbers its predicate read;
* ``<out>/claims.md``: claim x seed, each cell "true", "FALSE" (a fixed claim that failed) or
  "alt" (a guarded claim that took its alternative), with counts where a notebook evaluates a claim
  more than once, and for each causal claim the control it is judged against; below it, any pair of
  evaluations in one notebook run that judged one number with two different tests
  (``pusht.nb.claims.conflicts``: there should be none);

and with ``--record`` both are copied to ``benchmarks/`` with the host, the commit and the time,
where ``tests/test_claims.py`` checks them against the registry.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from scripts.chapter import ROOT, execute

from pusht.host import cpu_model
from pusht.nb.claims import LOG_ENV, conflicts, load_all

NOTEBOOKS = ("03_imagination_actor", "04_imagination_gap", "05_horizon", "06_closing_the_gap", "07_planning")


def host() -> str:
    import torch

    return (f"{platform.machine()} {cpu_model()}, {os.cpu_count()} cores, "
            f"python {platform.python_version()}, torch {torch.__version__}")


def commit() -> str:
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def collect(logs: Path) -> list[dict]:
    rows = []
    for path in sorted(logs.glob("*.jsonl")):
        nb, seed = path.stem.rsplit("_seed", 1)
        for line in path.read_text().splitlines():
            rec = json.loads(line)
            rows.append({"notebook": nb, "seed": int(seed), **rec})
    return rows


def matrix(rows: list[dict], seeds: list[int]) -> str:
    registry = load_all()
    names = sorted({r["claim"] for r in rows} | set(registry))
    lines = ["| claim | kind | control | " + " | ".join(f"seed {s}" for s in seeds) + " |",
             "|---|---|---|" + "---|" * len(seeds)]
    for name in names:
        fixed = registry[name].fixed if name in registry else None
        cells = []
        for s in seeds:
            got = [r["holds"] for r in rows if r["claim"] == name and r["seed"] == s]
            if not got:
                cells.append("-")
                continue
            bad = "FALSE" if fixed else "alt"
            n_true = sum(got)
            cells.append("true" if n_true == len(got) else (bad if n_true == 0 else f"{n_true}/{len(got)} true"))
        kind = "fixed" if fixed else ("guarded" if fixed is False else "unregistered")
        control = (registry[name].control or "") if name in registry else ""
        lines.append(f"| `{name}` | {kind} | {control} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


LETTERS = {"Exercise 1 (04)": "04.ex1_letter_decided", "Exercise 2 (05)": "05.ex2_letter_decided",
           "Exercise 3 (06)": "06.ex3_letter_decided"}


def letters_decided(rows: list[dict]) -> dict[str, dict[int, bool]]:
    """For each exercise, seed -> whether its letter was decided beyond the noise on that seed's run (every
    evaluation of the exercise's ``*_letter_decided`` claim held)."""
    out: dict[str, dict[int, bool]] = {}
    for ex, name in LETTERS.items():
        for r in rows:
            if r["claim"] == name:
                out.setdefault(ex, {})[r["seed"]] = out.get(ex, {}).get(r["seed"], True) and r["holds"]
    return out


def letters_section(rows: list[dict]) -> str:
    """How many seeds decided each exercise's letter beyond the noise."""
    got = letters_decided(rows)
    lines = ["## Exercise letters decided beyond the noise", "",
             "A letter is decided when the test behind it is more than 10% away from its threshold (`|t|` against "
             "`k`) and, for Exercise 2, the change is not 'unresolved' (claims `*.ex*_letter_decided`).", ""]
    for ex in LETTERS:
        seeds = got.get(ex, {})
        undecided = sorted(s for s, ok in seeds.items() if not ok)
        lines.append(f"* {ex}: {sum(seeds.values())} of {len(seeds)} seeds"
                     + (f" (not decided on seed {', '.join(map(str, undecided))})" if undecided else ""))
    return "\n".join(lines)


def one_test_section(rows: list[dict]) -> str:
    """The one-test-per-quantity check of the recorded evaluations, for the table's reader."""
    bad = conflicts(rows)
    head = ("## One test per quantity\n\nPairs of evaluations in one notebook run that judged the same number "
            "with different standard errors, k or minimum effects (`pusht.nb.claims.conflicts`): ")
    return head + ("none." if not bad else f"{len(bad)}:\n\n" + "\n".join(f"* {b}" for b in bad))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(10)))
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "claims")
    p.add_argument("--smoke", action="store_true", help="the tiny config (a check of the machinery)")
    p.add_argument("--record", action="store_true", help="copy the table to benchmarks/")
    p.add_argument("--notebooks", nargs="+", default=list(NOTEBOOKS))
    args = p.parse_args(argv)
    out = args.out.resolve()
    logs, executed = out / "logs", out / "executed"
    for d in (logs, executed):
        d.mkdir(parents=True, exist_ok=True)
    seconds = {}
    for seed in args.seeds:
        for name in args.notebooks:
            log = logs / f"{name}_seed{seed}.jsonl"
            log.unlink(missing_ok=True)
            os.environ[LOG_ENV] = str(log)
            t = time.perf_counter()
            print(f"seed {seed}: {name} ...", flush=True)
            execute(ROOT / "solutions" / f"{name}.ipynb", out, args.smoke, parameters={"SEED": seed},
                    saved=executed / f"{name}_seed{seed}.ipynb")
            seconds[f"{name}_seed{seed}"] = round(time.perf_counter() - t, 1)
            print(f"  {seconds[f'{name}_seed{seed}']:.0f} s", flush=True)
    os.environ.pop(LOG_ENV, None)
    rows = collect(logs)
    seeds = sorted({r["seed"] for r in rows})      # the kept logs' seeds too: a table of every run in it
    # A run of some notebooks keeps the other notebooks' logs (and their times) from the run before:
    # the table says which were run this time.
    before = json.loads((out / "claims.json").read_text()) if (out / "claims.json").is_file() else {}
    kept = {k: v for k, v in (before.get("seconds") or {}).items()
            if k not in seconds and (logs / f"{k}.jsonl").is_file()}
    table = {"written_by": "scripts/claims.py (make claims)", "host": host(), "commit": commit(),
             "measured_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             "config": "smoke" if args.smoke else "default", "seeds": seeds, "seeds_run_this_time": args.seeds,
             "notebooks": sorted({r["notebook"] for r in rows}), "run_this_time": args.notebooks,
             "kept_from": ({"commit": before.get("commit"), "measured_at": before.get("measured_at"), "runs": sorted(kept)}
                           if kept else None),
             "seconds": {**kept, **seconds},
             "total_seconds": round(sum({**kept, **seconds}.values()), 1), "records": rows}
    (out / "claims.json").write_text(json.dumps(table, indent=1) + "\n")
    md = (f"# Claims x seeds\n\nWritten by `make claims` (scripts/claims.py), {table['measured_at']}, commit "
          f"{table['commit']}, on {table['host']}; {table['config']} config, notebooks "
          f"{', '.join(table['notebooks'])}, {table['total_seconds']:.0f} s in all"
          + (f" (run this time: {', '.join(args.notebooks)}; the others' evaluations are kept from the run of "
             f"{table['kept_from']['measured_at']}, commit {table['kept_from']['commit']})" if kept else "")
          + ".\n\n"
          "`true`: held on every evaluation for that seed. `alt`: a guarded claim that did not hold, so "
          "the notebook printed its alternative. `FALSE`: a fixed claim that did not hold (CI fails on "
          "it). `k/n true`: evaluated n times for that seed (per seed compared, horizon, round or fix), "
          "held k times. `-`: not evaluated for that seed. The control: for a causal claim, the run that differs "
          "from the claimed cause's run only in that cause (`pusht.nb.claims.CONTROLS`).\n\n"
          + matrix(rows, seeds) + "\n\n" + letters_section(rows) + "\n\n" + one_test_section(rows) + "\n")
    (out / "claims.md").write_text(md)
    print(md)
    if args.record:
        for f in ("claims.json", "claims.md"):
            shutil.copy(out / f, ROOT / "benchmarks" / f)
        print("recorded in benchmarks/claims.json and benchmarks/claims.md")
    bad = [r for r in rows if r["fixed"] and not r["holds"]]
    if bad:
        print(f"{len(bad)} fixed claim evaluation(s) FALSE: "
              + ", ".join(sorted({f"{r['claim']} (seed {r['seed']})" for r in bad})), file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
