"""Re-measure the chapter's headline numbers and write them to meta.yaml.

    python -m scripts.record_meta            # seeds 0-2 at the default config + horizon sweep
                                             # + the tolerance bands (fresh process per code path)
    python -m scripts.record_meta --tolerance-only   # re-measure only the bands, keep the rest
    python -m scripts.record_meta --closing-only     # re-measure only notebook 06's loop and fixes
    python -m scripts.record_meta --seeds-only       # re-measure only the seeds block (same platform)

Every number in meta.yaml comes from this script's runs; the chapter page's own figures are stored
beside ours (under ``page``) so a reader can compare, never mixed into them. The determinism test
(tests/test_reproduce.py) re-runs seed 0 and checks it against the ``seeds`` block here: bit for
bit where the platform's float-deciding fingerprint (``fingerprint.FLOAT_KEYS``) matches the recorded
one, and elsewhere within the ``tolerance`` bands this script measures (see ``measure_tolerance``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from pusht.config import make_config
from pusht.dreamer import run
from pusht.fingerprint import FLOAT_KEYS, platform_fingerprint
from pusht.metric_keys import WM_ERR, WM_RATIO
from pusht.metric_keys import key as metric_key
from pusht.nb.horizon import EX2_ACTOR_SEEDS
from pusht.page import PAGE

ROOT = Path(__file__).resolve().parents[1]

HEADLINE = ["imagined_return_per_step", "real_return_per_step", "imagination_gap",
            "imagined_final_tee_dist", "real_final_tee_dist", "spawn_tee_dist", "real_success_rate",
            "real_block_displacement", "real_episodes_touching_block",
            "zero_action_dream_return_per_step", "zero_action_dream_final_tee_dist",
            "untrained_actor_dream_return_per_step", "untrained_actor_dream_final_tee_dist",
            "final_imagined_reward_per_step_train", "imagined_reward_first20_train",
            "imagined_reward_last20_train", "imagination_gap_train_horizon", "gap_drift_train_horizon",
            "gap_training_train_horizon", "gap_drift_eval_horizon", "gap_training_eval_horizon",
            "real_pusher_at_wall_share", "replay_pusher_err_train_horizon"]


def acceptance(m: dict) -> dict:
    """The chapter's lesson, as checks on one run's metrics (issues 2 and 10). The imagined reward
    must rise by more than twice its own standard error (``imagined_reward_rise_se``, measured
    from the iteration-to-iteration spread), not by a typed-in amount."""
    return {
        "gap_above_0.05": m["imagination_gap"] > 0.05,
        "real_success_zero": m["real_success_rate"] == 0,
        "real_block_within_0.03m_of_spawn": abs(m["real_final_tee_dist"] - m["spawn_tee_dist"]) <= 0.03,
        "imagined_reward_rose_beyond_2se":
            m["imagined_reward_last20_train"] - m["imagined_reward_first20_train"]
            > 2 * m["imagined_reward_rise_se"],
        "wm_beats_copy_last_on_pusher": all(m[metric_key(WM_RATIO, kind="one_step", dim=d)] < 1 for d in ("agent_x", "agent_y")),
        "wm_loses_on_a_block_dim": any(m[metric_key(WM_RATIO, kind="one_step", dim=d)] > 1 for d in
                                       ("tee_x", "tee_y", "sin(tee_yaw)", "cos(tee_yaw)")),
    }


# --- tolerance bands: how far the headline metrics move when only the float code path changes ------
# Each variant is a fresh process (both variables are read once, when torch loads). MKL_CBWR picks
# MKL's matrix-multiply code path (on a non-Intel CPU MKL honours only COMPATIBLE and falls back to
# its own choice for the others; variants that land on the same path are measured once).
# ATEN_CPU_CAPABILITY picks torch's own vectorised kernels, as on a CPU without AVX512 (or AVX2).
# One more variant runs with two threads instead of one: the same code, its sums split differently.
MKL_CBWR_VALUES = [None, "COMPATIBLE", "AVX", "AVX2", "AVX512", "AVX512_E1"]
ATEN_VALUES = [None, "avx2", "default"]
TOLERANCE_SEEDS = [0, 1, 2]
# band = SAFETY_FACTOR x the widest spread between code paths (max over the seeds). Why 4: the few
# paths one host offers sample the variation thinly; the one cross-vendor figure known (issue 9: an
# Intel Xeon, same torch and AVX512, seed-0 gap +0.2317 against +0.2352 recorded here) lies 2.6x
# this host's widest seed-0 spread away, so 4x covers it with margin, and every band stays far
# below the seed-to-seed range, so a real change of the code still fails the check.
SAFETY_FACTOR = 4
# ... but never below the resolution of the metric: metrics are rounded to 6 decimals, and a count
# of episodes can flip by one when a contact is decided by the last bits.
FLOOR, COUNT_FLOOR = 1e-6, 1
COUNTS = ("real_episodes_touching_block",)


def _env(mkl_cbwr, aten):
    env = {k: v for k, v in os.environ.items() if k not in ("MKL_CBWR", "ATEN_CPU_CAPABILITY")}
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    if mkl_cbwr:
        env["MKL_CBWR"] = mkl_cbwr
    if aten:
        env["ATEN_CPU_CAPABILITY"] = aten
    return env


def _worker(seeds, threads: int = 1) -> None:
    """Child process: print one JSON line per seed (headline metrics, the gap at full precision,
    a hash of the trained weights) after the platform line."""
    print(json.dumps(platform_fingerprint()), flush=True)
    for seed in seeds:
        res = run(make_config(seed=seed, threads=threads), log=None)
        gap = (float(res.rollouts["dream"].return_per_step.mean())
               - float(res.rollouts["real"].return_per_step.mean()))
        h = hashlib.sha256()
        for model in (res.wm, res.agent):
            for t in model.state_dict().values():
                h.update(t.detach().cpu().contiguous().numpy().tobytes())
        print(json.dumps({"seed": seed, "imagination_gap_full": repr(gap),
                          "weights_sha256": h.hexdigest()[:16],
                          **{k: res.metrics[k] for k in HEADLINE}}), flush=True)


def _child(args, mkl_cbwr=None, aten=None) -> list[str]:
    cmd = [sys.executable, "-m", "scripts.record_meta", *args]
    out = subprocess.run(cmd, env=_env(mkl_cbwr, aten), cwd=ROOT, check=True, capture_output=True,
                         text=True).stdout
    return out.strip().splitlines()


def code_path(fp: dict, threads: int = 1) -> str:
    label = f"mkl {fp['mkl_path']}, aten {fp['cpu_capability']}"
    return label + (f", {threads} threads" if threads > 1 else "")


def measure_tolerance(seeds=TOLERANCE_SEEDS, log=print, jobs: int = 2) -> dict:
    """Re-run ``seeds`` under every distinct float code path this host offers; return the
    ``tolerance`` section: per headline metric the widest spread between paths and the band.
    ``jobs`` variant processes run at once (each single-threaded; that changes no number)."""
    from concurrent.futures import ThreadPoolExecutor

    mkl_paths, aten_paths = {}, {}                  # code path -> the variable that gives it
    for mkl_cbwr in MKL_CBWR_VALUES:
        mkl_paths.setdefault(json.loads(_child(["--probe"], mkl_cbwr)[0])["mkl_path"], mkl_cbwr)
    for aten in ATEN_VALUES:
        aten_paths.setdefault(json.loads(_child(["--probe"], None, aten)[0])["cpu_capability"], aten)
    todo = [(m, a, 1) for m in mkl_paths.values() for a in aten_paths.values()] + [(None, None, 2)]

    def measure(job):
        mkl_cbwr, aten, threads = job
        t = time.perf_counter()
        lines = _child(["--worker", *map(str, seeds), "--worker-threads", str(threads)], mkl_cbwr, aten)
        return job, lines, time.perf_counter() - t

    variants, runs = {}, []
    with ThreadPoolExecutor(jobs) as pool:
        for (mkl_cbwr, aten, threads), lines, seconds in pool.map(measure, todo):
            label = code_path(json.loads(lines[0]), threads)
            runs.append({"label": label, "MKL_CBWR": mkl_cbwr, "ATEN_CPU_CAPABILITY": aten,
                         "threads": threads})
            for line in lines[1:]:
                m = json.loads(line)
                variants.setdefault(m.pop("seed"), {})[label] = m
            log(f"  {label} (MKL_CBWR={mkl_cbwr}, ATEN_CPU_CAPABILITY={aten}): gap "
                + " ".join(variants[s][label]["imagination_gap_full"][:9] for s in seeds)
                + f"  ({seconds:.0f} s)", flush=True)
    spread = {k: max(max(v[k] for v in variants[s].values()) - min(v[k] for v in variants[s].values())
                     for s in seeds) for k in HEADLINE}
    band = {k: round(max(SAFETY_FACTOR * spread[k], COUNT_FLOOR if k in COUNTS else FLOOR), 6)
            for k in HEADLINE}
    here = platform_fingerprint()
    return {
        "how": (f"scripts/record_meta.py: seeds {list(seeds)} at the default config, one fresh process "
                f"per float code path: MKL_CBWR in {MKL_CBWR_VALUES[1:]} or unset, crossed with "
                f"ATEN_CPU_CAPABILITY in {ATEN_VALUES[1:]} or unset (values landing on a path already "
                f"seen are measured once), plus one run with 2 threads. spread: per metric, the "
                f"largest max-min over the paths of one seed. band: max({SAFETY_FACTOR} x spread, "
                f"{FLOOR}; {COUNT_FLOOR} for counts), the allowed |fresh - recorded| for seed 0 on a "
                f"platform other than the recording one."),
        "measured_on": f"{here['cpu_model']}, {here['mkl']}, torch {here['torch']}",
        "safety_factor": SAFETY_FACTOR,
        "paths": runs,
        "spread": {k: round(v, 6) for k, v in spread.items()},
        "band": band,
        "variants": variants,
    }


# --- notebook 06: the real-data loop and the two other fixes (issue 11) ----------------------------
CLOSING_KEYS = ["imagination_gap", "imagination_gap_se_eval_horizon", "imagination_gap_train_horizon",
                "imagined_return_per_step", "real_return_per_step", "real_success_rate",
                "real_episodes_touching_block", "real_block_displacement", "spawn_tee_dist", "real_final_tee_dist",
                "real_pusher_at_wall_share", "zero_action_dream_return_per_step", "gap_drift_eval_horizon",
                "gap_training_train_horizon", "wm_one_step_ratio_tee_x", "wm_one_step_ratio_tee_y",
                "wm_open_loop_ratio_tee_x", "wm_open_loop_ratio_tee_y", "replay_pusher_err_eval_horizon",
                "wm_ensemble_disagreement_train_horizon", "wm_ensemble_disagreement_eval_horizon"]
LOOP_KEYS = CLOSING_KEYS[:13] + ["train_clips", "wm_policy_one_step_block_err", "wm_policy_one_step_pusher_err",
                                 "wm_policy_open_loop_block_err", "wm_policy_open_loop_pusher_err",
                                 "wm_policy_open_loop_block_copy_err", "wm_expert_one_step_block_err",
                                 "wm_expert_open_loop_block_err", "real_block_toward_target"]
# The two fixes, as notebook 06 runs them (its default config).
FIXES = {"delta": {"wm_predicts": "delta"}, "ensemble": {"ensemble_size": 3, "disagreement_penalty": 1.0}}


def _closing_worker(seed: int) -> None:
    """Child process: one JSON line with seed ``seed``'s loop rounds and the two fixes' metrics."""
    from pusht.loop import run_loop

    with tempfile.TemporaryDirectory() as cache:
        t = time.perf_counter()
        res = run_loop(make_config(seed=seed), model_cache=cache, log=None)
        out = {"seed": seed, "loop": [{k: m[k] for k in ["round"] + LOOP_KEYS if k in m} for m in res.rounds],
               "loop_seconds": round(time.perf_counter() - t, 1)}
        for name, change in FIXES.items():
            t = time.perf_counter()
            m = run(make_config(seed=seed, **change), model_cache=cache, log=None).metrics
            out[name] = {k: m[k] for k in CLOSING_KEYS if k in m}
            out[f"{name}_seconds"] = round(time.perf_counter() - t, 1)
    print(json.dumps(out), flush=True)


def closing_acceptance(rounds: list) -> dict:
    """Issue 11's checks on one seed's loop, on the model's one-step error on the policy's own data
    (pusher and block): below round 0's in every later round, and below the previous round's in
    every round; and whether real success ever rose above 0 (the issue's stretch goal)."""
    parts = ("pusher", "block")
    err = {p: [m[metric_key(WM_ERR, data="policy", kind="one_step", body=p)] for m in rounds] for p in parts}
    return {"policy_data_one_step_error_below_round_0_in_every_round":
                all(e < err[p][0] for p in parts for e in err[p][1:]),
            "policy_data_one_step_error_fell_every_round":
                all(b < a for p in parts for a, b in zip(err[p], err[p][1:])),
            "real_success_above_0_in_some_round": any(m["real_success_rate"] > 0 for m in rounds)}


def measure_closing(seeds, log=print, jobs: int = 2) -> dict:
    """The ``closing`` section: per seed, the loop's rounds and one run of each fix, one process per
    seed (``jobs`` at a time; every run is single-threaded, so this changes no number)."""
    from concurrent.futures import ThreadPoolExecutor

    def measure(seed):
        return json.loads(_child(["--closing-worker", str(seed)])[-1])

    here = platform_fingerprint()
    section = {"how": ("scripts/record_meta.py --closing-only: per seed, pusht.loop.run_loop at the default "
                       "config (round 0 = the offline run), then one offline run per fix: "
                       + "; ".join(f"{k}: {v}" for k, v in FIXES.items())),
               "measured_on": f"{here['cpu_model']}, {here['mkl']}, torch {here['torch']}",
               "loop": {}, "delta": {}, "ensemble": {}, "seconds": {}, "acceptance": {}}
    with ThreadPoolExecutor(jobs) as pool:
        for out in pool.map(measure, seeds):
            s = out["seed"]
            section["loop"][s], section["delta"][s], section["ensemble"][s] = out["loop"], out["delta"], out["ensemble"]
            section["seconds"][s] = {k[:-len("_seconds")]: out[k] for k in out if k.endswith("_seconds")}
            section["acceptance"][s] = closing_acceptance(out["loop"])
            log(f"seed {s}: loop gaps " + " ".join(f"{m['imagination_gap']:+.3f}" for m in out["loop"])
                + f"; delta {out['delta']['imagination_gap']:+.3f}; ensemble {out['ensemble']['imagination_gap']:+.3f}",
                flush=True)
    return section


# --- what a fresh run is checked against, here ------------------------------------------------------
def platform_differences(recorded: dict, here: dict) -> list[str]:
    """The float-deciding fingerprint keys on which this host differs from meta.yaml's."""
    return [f"{k}: recorded {recorded.get(k)!r}, here {here.get(k)!r}" for k in FLOAT_KEYS
            if recorded.get(k) != here.get(k)]


def comparison_line(meta: dict, here: dict | None = None) -> str:
    """One line saying what tests/test_reproduce.py compares on this host, and why."""
    rec, here = meta["platform"], here or platform_fingerprint()
    diff = platform_differences(rec, here)
    if not diff:
        return (f"reproduce: platform matches meta.yaml ({rec['cpu_model']}, {rec['mkl']} path "
                f"{rec['mkl_path']}, torch {rec['torch']} {rec['cpu_capability']}): seed 0 checked "
                f"bit-exact")
    return ("reproduce: platform differs from meta.yaml (" + "; ".join(diff) + "): seed 0 checked "
            "against the lesson's invariants and the recorded tolerance bands, not bit for bit")


def out_of_band(fresh: dict, meta: dict) -> list[str]:
    """Headline metrics of ``fresh`` (a seed-0 run) farther from meta.yaml's seed 0 than the band."""
    rec, recorded = meta["seeds"][0], meta["tolerance"]["band"]
    band = {k: max(recorded[j] for j in _same_unit(k)) for k in HEADLINE}
    return [f"{k}: fresh {fresh[k]}, recorded {rec[k]}, |diff| {abs(fresh[k] - rec[k]):.6f} > band "
            f"{band[k]}" for k in HEADLINE if abs(fresh[k] - rec[k]) > band[k] + 1e-12]


# Metrics in one unit share the widest of their bands: the gap is imagined minus real return, so
# another CPU may move the real return by as much as this host moved the gap (one host samples
# the code paths thinly, and which of the two absorbs a shift is not known in advance).
UNITS = [("imagined_return_per_step", "real_return_per_step", "imagination_gap",
          "imagination_gap_train_horizon", "gap_drift_train_horizon", "gap_training_train_horizon",
          "gap_drift_eval_horizon", "gap_training_eval_horizon"),
         ("imagined_final_tee_dist", "real_final_tee_dist")]


def _same_unit(key: str) -> tuple:
    return next((g for g in UNITS if key in g), (key,))


# Where the numbers are shown: the README's headline (a few rows) and docs/results.md (every table),
# each between its markers, rendered from meta.yaml and never typed (tests/test_reproduce.py).
README = ROOT / "README.md"
RESULTS_PAGE = ROOT / "docs" / "results.md"
HEADLINE_START, HEADLINE_END = "<!-- headline:start", "<!-- headline:end -->"
RESULTS_START, RESULTS_END = "<!-- results:start", "<!-- results:end -->"
ROWS = [("imagined_return_per_step", "imagined reward/step (dream)", "+.3f"),
        ("real_return_per_step", "real reward/step (pymunk)", "+.3f"),
        ("imagination_gap", "imagination gap", "+.3f"),
        ("imagined_final_tee_dist", "dream final block-to-target (m)", ".3f"),
        ("real_final_tee_dist", "real final block-to-target (m)", ".3f"),
        ("spawn_tee_dist", "block spawn distance (m)", ".3f"),
        ("real_success_rate", "real success rate", ".2f"),
        ("real_block_displacement", "real block moved (m, mean)", ".3f"),
        ("real_episodes_touching_block", "real episodes the pusher touched the block", "d"),
        ("imagination_gap_position_eval_horizon", "... its position half (where the block is)", "+.3f"),
        ("imagination_gap_yaw_eval_horizon", "... its yaw half (how the block is turned)", "+.3f"),
        ("imagination_gap_train_horizon", "gap over the actor's training horizon (imag_horizon steps)", "+.3f"),
        ("gap_drift_train_horizon", "... of which drift (zero-action dream vs zero-action reality)", "+.3f"),
        ("gap_training_train_horizon", "... of which training (what training added in the dream beyond reality)", "+.3f"),
        ("real_pusher_at_wall_share", "share of real steps with the pusher against a wall", ".2f"),
        ("expert_pusher_at_wall_share", "... of expert-data steps", ".2f"),
        ("replay_pusher_err_train_horizon", "model's pusher error replaying the real actions, 1.5 s (m)", ".3f"),
        ("zero_action_dream_final_tee_dist", "control: zero-action dream, final distance (m)", ".3f"),
        ("untrained_actor_dream_final_tee_dist", "control: untrained-actor dream, final distance (m)", ".3f"),
        ("expert_signal_real_train_horizon", "expert control: reality pays the expert over standing still, "
         "training horizon", "+.3f"),
        ("expert_signal_dream_train_horizon", "expert control: the dream pays the expert over standing still, "
         "training horizon", "+.3f"),
        ("zero_dream_block_moved_train_horizon", "... valid only if the zero-action dream moves the untouched block "
         "at most 0.02 m; it moves it (m)", ".3f"),
        ("expert_gap_train_horizon", "the expert's own gap, dream minus reality, training horizon", "+.3f"),
        ("imagined_reward_first20_train", "imagined reward/step, first 20 iterations", "+.3f"),
        ("imagined_reward_last20_train", "imagined reward/step, last 20 iterations", "+.3f")]


# The README's few rows, in ROWS' order: the same policy in two worlds, and the share of the gap that
# is the model's own drift.
HEADLINE_ROWS = ("imagined_return_per_step", "real_return_per_step", "imagination_gap", "real_success_rate",
                 "imagination_gap_train_horizon", "gap_drift_train_horizon")


def _seeds_table(meta: dict, rows) -> list[str]:
    """The seeds' table, one line per (key, title, format) of ``rows``, the chapter page's seed 0 beside."""
    seeds = list(meta["seeds"])
    page = meta["page"]
    lines = ["| measured | " + " | ".join(f"seed {s}" for s in seeds) + " | chapter page, seed 0 |",
             "| --- |" + " --- |" * (len(seeds) + 1)]
    for key, title, fmt in rows:
        ref = page.get(key, {})
        ref = ref.get("seed0", ref.get("about", "")) if isinstance(ref, dict) else ""
        ref = format(ref, fmt) if isinstance(ref, (int, float)) and not isinstance(ref, bool) else ref
        lines.append(f"| {title} | " + " | ".join(format(meta["seeds"][s][key], fmt) for s in seeds)
                     + f" | {ref} |")
    return lines


def render_headline(meta: dict) -> str:
    """The README's headline: a few rows of docs/results.md's first table."""
    return "\n".join(_seeds_table(meta, [r for r in ROWS if r[0] in HEADLINE_ROWS]))


def render_results(meta: dict) -> str:
    """docs/results.md's tables, rendered from meta.yaml (never typed)."""
    seeds = list(meta["seeds"])
    plat = meta["platform"]
    where = (f"{plat['cpu_model']}, {plat['cpu_capability']}, {plat['mkl']} path {plat['mkl_path']}, "
             f"torch {plat['torch']}" if "mkl_path" in plat else
             f"{plat['cpu_capability']} CPU, torch {plat['torch']}")
    lines = [f"Default config, {meta['seeds'][seeds[0]]['eval_episodes']} held-out starts per seed "
             f"({where}):", ""] + _seeds_table(meta, ROWS)
    if "tolerance" in meta:
        band = meta["tolerance"]["band"]
        lines += ["", "On another platform a fresh seed 0 should land within these bands of the seed-0 "
                  f"column ({meta['tolerance']['safety_factor']}x the widest spread between float code "
                  "paths measured here; `meta.yaml`, `tolerance`): "
                  + ", ".join(f"{title} ±{int(band[key]) if fmt == 'd' else format(band[key], '.2g')}"
                              for key, title, fmt in ROWS if key in band) + "."]
    lines += ["", "The chapter page's wiring, in which the critic never reaches the actor (`--critic_wiring "
              "page`), on the same seeds:", "",
              "| measured | " + " | ".join(f"seed {s}" for s in meta.get("page_wiring", {})) + " |",
              "| --- |" + " --- |" * len(meta.get("page_wiring", {}))]
    for key, title, fmt in ROWS[:3] + [r for r in ROWS if r[0] == "gap_training_train_horizon"]:
        lines.append(f"| {title} | " + " | ".join(format(m[key], fmt) for m in meta["page_wiring"].values())
                     + " |")
    sweep = horizon_table(meta["horizon_sweep"])
    lines += ["", "Imagination horizon sweep (Exercise 2; world model of seed 0, "
              f"{len(next(iter(sweep.values()))['gaps'])} actor seeds per horizon):", "",
              "| horizon | gap, each actor seed | gap, mean | real success (all) |",
              "| --- | --- | --- | --- |"]
    for hz, row in sweep.items():
        lines.append(f"| {hz} | " + ", ".join(f"{g:+.3f}" for g in row["gaps"])
                     + f" | {np.mean(row['gaps']):+.3f} | {max(row['success']):.2f} |")
    if "closing" in meta:
        lines += ["", closing_table(meta["closing"])]
    return "\n".join(lines)


def closing_table(c: dict) -> str:
    """Notebook 06 side by side: each fix's gap (whole evaluation and training horizon), real return,
    real success and touches, per seed."""
    seeds = list(c["loop"])
    lines = [f"Closing the gap (notebook 06; measured on {c['measured_on']}): gap over the evaluation / over "
             "the training horizon, real reward per step, real successes, episodes touching the block, per seed:",
             "", "| run | " + " | ".join(f"seed {s}" for s in seeds) + " |", "| --- |" + " --- |" * len(seeds)]

    def cell(m):
        return (f"{m['imagination_gap']:+.3f} / {m['imagination_gap_train_horizon']:+.3f}, real "
                f"{m['real_return_per_step']:+.3f}, success {m['real_success_rate']:.0%}, touching "
                f"{m['real_episodes_touching_block']}")

    n = len(c["loop"][seeds[0]])
    for r in range(n):
        name = "offline (round 0)" if r == 0 else f"real-data loop, round {r}"
        lines.append(f"| {name} | " + " | ".join(cell(c["loop"][s][r]) for s in seeds) + " |")
    lines.append("| predict changes (offline) | " + " | ".join(cell(c["delta"][s]) for s in seeds) + " |")
    lines.append("| ensemble of 3, disagreement penalty 1 (offline) | "
                 + " | ".join(cell(c["ensemble"][s]) for s in seeds) + " |")
    lines += ["", "The loop's world model on the policy's own data (one-step error, metres, block / pusher, "
              "round 0 to last): " + "; ".join(
                  f"seed {s}: " + " -> ".join(f"{m['wm_policy_one_step_block_err']:.3f}/"
                                            f"{m['wm_policy_one_step_pusher_err']:.3f}" for m in c["loop"][s])
                  for s in seeds) + "."]
    return "\n".join(lines)


def horizon_table(sweep: dict) -> dict:
    """{horizon: {"gaps": [...], "success": [...]}} from the ``horizon_sweep`` block."""
    out: dict = {}
    for name, m in sweep.items():
        hz = int(name.split("_")[0][1:])
        row = out.setdefault(hz, {"gaps": [], "success": []})
        row["gaps"].append(m["imagination_gap"])
        row["success"].append(m["real_success_rate"])
    return dict(sorted(out.items()))


def pages_with_results(meta: dict) -> dict[Path, str]:
    """{path: its text with the numbers rendered from ``meta``}: the README's headline and
    docs/results.md's tables."""
    from scripts.release import splice

    return {README: splice(README, HEADLINE_START, HEADLINE_END, render_headline(meta)),
            RESULTS_PAGE: splice(RESULTS_PAGE, RESULTS_START, RESULTS_END, render_results(meta))}


def write_meta(record: dict, out: Path) -> None:
    header = ("# Written by scripts/record_meta.py: measured, never edited by hand.\n"
              "# 'page' holds the chapter page's own figures for comparison.\n")
    out.write_text(header + yaml.safe_dump(record, sort_keys=False, width=100))
    print(f"wrote {out}")
    if out == ROOT / "meta.yaml":
        for path, text in pages_with_results(yaml.safe_load(out.read_text())).items():
            path.write_text(text)
            print(f"updated the results in {path}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "meta.yaml")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--horizons", type=int, nargs="+", default=[5, 15, 30])
    p.add_argument("--actor-seeds", type=int, nargs="+", default=list(EX2_ACTOR_SEEDS),
                   help="actor seeds per horizon of the sweep (on the world model of seed 0)")
    p.add_argument("--tolerance-only", action="store_true",
                   help="re-measure only the tolerance section of an existing --out")
    p.add_argument("--seeds-only", action="store_true",
                   help="re-measure only the seeds block (and its acceptance) of an existing --out: after the "
                        "evaluation gains metrics, on the platform meta.yaml was recorded on")
    p.add_argument("--closing-only", action="store_true",
                   help="re-measure only notebook 06's section (the loop and the two fixes) of an existing --out")
    p.add_argument("--closing-worker", type=int, help=argparse.SUPPRESS)
    p.add_argument("--worker", type=int, nargs="+", help=argparse.SUPPRESS)
    p.add_argument("--worker-threads", type=int, default=1, help=argparse.SUPPRESS)
    p.add_argument("--probe", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.probe:
        print(json.dumps(platform_fingerprint()))
        return
    if args.worker:
        _worker(args.worker, args.worker_threads)
        return
    if args.closing_worker is not None:
        _closing_worker(args.closing_worker)
        return
    if args.seeds_only:
        record = yaml.safe_load(args.out.read_text())
        if platform_fingerprint() != record["platform"]:
            raise SystemExit("--seeds-only keeps the tolerance bands and the sweep, which were measured on "
                             "meta.yaml's platform; this is another one: run the whole script")
        for seed in args.seeds:
            record["seeds"][seed] = run(make_config(seed=seed), log=None).metrics
        record["acceptance"] = {seed: acceptance(m) for seed, m in record["seeds"].items()}
        write_meta(record, args.out)
        return
    if args.closing_only:
        record = yaml.safe_load(args.out.read_text())
        record["closing"] = measure_closing(args.seeds)
        write_meta(record, args.out)
        return
    if args.tolerance_only:
        record = yaml.safe_load(args.out.read_text())
        print("tolerance bands, one fresh process per float code path:", flush=True)
        record["tolerance"] = measure_tolerance()
        write_meta(record, args.out)
        return

    default = make_config()
    record = {"config": {k: v for k, v in default.to_dict().items() if k not in ("seed", "out")},
              "platform": platform_fingerprint(), "page": PAGE, "seeds": {}, "horizon_sweep": {},
              "page_wiring": {}}
    for seed in args.seeds:
        t = time.perf_counter()
        res = run(make_config(seed=seed), log=None)
        record["seeds"][seed] = res.metrics
        print(f"seed {seed}: gap {res.metrics['imagination_gap']:+.4f}  "
              f"({time.perf_counter() - t:.1f} s)", flush=True)
    # Exercise 2's sweep: one world model (seed 0), each horizon with several actor seeds, so a
    # change of the gap with the horizon can be judged against the spread between actor seeds.
    with tempfile.TemporaryDirectory() as cache:
        for hz in args.horizons:
            for a in args.actor_seeds:
                res = run(make_config(seed=0, imag_horizon=hz, actor_seed=a), model_cache=cache, log=None)
                record["horizon_sweep"][f"h{hz}_actor{a}"] = {k: res.metrics[k] for k in HEADLINE}
                print(f"horizon {hz} actor seed {a}: gap {res.metrics['imagination_gap']:+.4f}", flush=True)
    # The chapter page's wiring (the critic never reaches the actor), the contrast notebook 03 shows.
    record["page_wiring"] = {}
    for seed in args.seeds:
        res = run(make_config(seed=seed, critic_wiring="page"), log=None)
        record["page_wiring"][seed] = {k: res.metrics[k] for k in HEADLINE}
        print(f"seed {seed}, page wiring: gap {res.metrics['imagination_gap']:+.4f}", flush=True)
    record["acceptance"] = {seed: acceptance(m) for seed, m in record["seeds"].items()}
    print("notebook 06: the real-data loop and the two other fixes, one process per seed:", flush=True)
    record["closing"] = measure_closing(args.seeds)
    print("tolerance bands, one fresh process per float code path:", flush=True)
    record["tolerance"] = measure_tolerance()
    write_meta(record, args.out)


if __name__ == "__main__":
    main()
