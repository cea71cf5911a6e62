"""The planner (``pusht.plan``) on several seeds, one after the other, each row appended to a CSV.

    python -m benchmarks.bench_plan --seeds 0 1 [--serial 5] [--horizon 16 --samples 256 ...]
        [--hidden_dim 128 --wm_predicts delta --data_pause_episodes 100 ...] [--csv benchmarks/plan_seeds.csv]

Per seed: the recipe's world model (``pusht.plan.RECIPE``, any config field overridable), its gate
and the chapter's default model's gate, at the planner's horizon and the evaluation's; the planner
on ``--starts`` held-out starts beside zero actions and the scripted expert (success k/n with its
Wilson 95% interval, reward per step with standard errors, final distance and yaw error); the wall
time of every stage; with ``--serial N``, batched planning against one start at a time on the
first N starts, side by side. One CSV row per seed (the host, the commit and the machine's load
recorded with it) and the whole result, per start included, as JSON beside the CSV
(``<csv stem>/seed<N>_<settings>_m<model_tag>.json``). Rows are appended, never rewritten. Torch runs on one thread.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import hashlib
import json
import os
import time
from datetime import datetime, timezone
from pathlib import Path

from benchmarks.bench import git_commit, host_description

from pusht.config import make_config
from pusht.data import default_cache_dir
from pusht.plan import RECIPE, PlanSettings, run

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CSV = ROOT / "benchmarks" / "plan_seeds.csv"
MODEL_FIELDS = ("wm_predicts", "hidden_dim", "latent_dim", "data_noisy_episodes", "data_pause_episodes",
                "data_random_episodes", "data_poke_episodes", "data_noise", "n_episodes", "wm_epochs")


def row(res: dict, host: str, commit: str, load: float) -> dict:
    """One CSV row of a seed's result."""
    m, cfg, t, s = res["summary"], res["config"], res["timing"], res["settings"]
    out = {"measured_at": datetime.now(timezone.utc).isoformat(timespec="seconds"), "host": host,
           "load_1min_at_start": round(load, 2), "commit": commit, "seed": cfg["seed"],
           "settings": " ".join(f"{k}={v}" for k, v in s.items()),
           "model": " ".join(f"{k}={cfg[k]}" for k in MODEL_FIELDS), "eval_horizon": cfg["eval_horizon"],
           "starts": m["n_starts"], "successes": m["plan_successes"],
           "success_low": round(m["plan_success_low"], 4), "success_high": round(m["plan_success_high"], 4)}
    for name in ("plan", "zero", "expert"):
        out[f"{name}_reward_per_step"] = round(m[f"{name}_reward_per_step"], 4)
        out[f"{name}_reward_per_step_se"] = round(m[f"{name}_reward_per_step_se"], 4)
    out.update({"plan_minus_zero": round(m["plan_minus_zero"], 4), "plan_minus_zero_se": round(m["plan_minus_zero_se"], 4),
                "plan_beats_zero": m["plan_beats_zero"], "zero_successes": m["zero_successes"],
                "expert_successes": m["expert_successes"]})
    for name in ("plan", "zero", "expert"):
        out[f"{name}_final_dist_cm"] = round(100 * m[f"{name}_final_dist"], 2)
        out[f"{name}_final_yaw_deg"] = round(m[f"{name}_final_yaw_err_deg"], 1)
    for name, g in res["gate"].items():
        out[f"gate_{name}_dream"] = round(g["expert_signal_dream"], 4)
        out[f"gate_{name}_dream_se"] = round(g["expert_signal_dream_se"], 4)
        out[f"gate_{name}_real"] = round(g["expert_signal_real"], 4)
        out[f"gate_{name}_passed"] = g["passed"]
    out.update({k: round(v, 1) for k, v in t.items()})
    if "speedup" in res:
        sp = res["speedup"]
        out.update({"serial_starts": sp["starts"], "serial_steps": sp["steps"], "batched_s": round(sp["batched_s"], 2),
                    "one_at_a_time_s": round(sp["serial_s"], 2), "speedup": round(sp["speedup"], 2),
                    "max_action_diff": f"{sp['max_action_diff']:.1e}"})
    return out


def model_tag(model: str) -> str:
    """Eight hex digits naming a row's model fields (its "model" column), for the JSON's file name."""
    return hashlib.sha256(model.encode()).hexdigest()[:8]


def append(path: Path, rec: dict) -> None:
    """Append ``rec``; a file whose header differs is kept and a new file beside it is started."""
    if path.exists():
        with open(path, newline="") as f:
            header = next(csv.reader(f), None)
        if header != list(rec):             # other columns (speed-up or not): a file of their own
            return append(path.with_name(f"{path.stem}_{len(rec)}cols{path.suffix}"), rec)
    path.parent.mkdir(parents=True, exist_ok=True)
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rec))
        if new:
            w.writeheader()
        w.writerow(rec)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--serial", type=int, default=0, help="also plan this many starts one at a time (the speed-up)")
    p.add_argument("--serial_steps", type=int, default=10)
    p.add_argument("--csv", type=Path, default=DEFAULT_CSV)
    p.add_argument("--model_cache", type=Path, default=None)
    for name, default in dataclasses.asdict(PlanSettings()).items():
        if not isinstance(default, bool):
            p.add_argument(f"--{name}", type=type(default), default=None)
    p.add_argument("--no_warm", action="store_true")
    for name in MODEL_FIELDS + ("eval_horizon",):
        kind = type(getattr(make_config(), name))
        p.add_argument(f"--{name}", type=kind, default=None)
    args = p.parse_args(argv)
    s = PlanSettings(**{f.name: getattr(args, f.name) for f in dataclasses.fields(PlanSettings)
                        if getattr(args, f.name, None) is not None and f.name != "warm"}, warm=not args.no_warm)
    s.validate()
    overrides = {**RECIPE, **{k: getattr(args, k) for k in MODEL_FIELDS + ("eval_horizon",)
                              if getattr(args, k) is not None}}
    host, commit = host_description(), git_commit()
    print(f"host: {host}; commit {commit}; settings {dataclasses.asdict(s)}; model {overrides}", flush=True)
    for seed in args.seeds:
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        res = run(make_config(seed=seed, **overrides), s, default_cache_dir(), args.model_cache, log=None,
                  serial=args.serial, serial_steps=args.serial_steps, chapter_gate=True)
        rec = row(res, host, commit, load)
        append(args.csv, rec)
        tag = f"h{s.horizon}k{s.knots}n{s.samples}i{s.iters}e{s.elites}" + ("" if s.warm else "-cold") + \
            (f"w{s.window}" if s.window else "") + f"_m{model_tag(rec['model'])}"
        js = args.csv.parent / args.csv.stem / f"seed{seed}_{tag}.json"
        js.parent.mkdir(parents=True, exist_ok=True)
        js.write_text(json.dumps({"host": host, "commit": commit, **res}, indent=1, default=str) + "\n")
        print(f"seed {seed}: {rec['successes']}/{rec['starts']} solved ({100 * rec['success_low']:.0f}-"
              f"{100 * rec['success_high']:.0f}%), reward/step {rec['plan_reward_per_step']:+.3f} ± "
              f"{rec['plan_reward_per_step_se']:.3f} vs zero {rec['zero_reward_per_step']:+.3f}, expert "
              f"{rec['expert_reward_per_step']:+.3f}; gate {rec['gate_eval_horizon_dream']:+.3f} "
              f"({'pass' if rec['gate_eval_horizon_passed'] else 'fail'}), chapter's "
              f"{rec['gate_chapter_eval_horizon_dream']:+.3f}; {time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
