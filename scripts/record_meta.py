"""Re-measure the chapter's headline numbers and write them to meta.yaml.

    python scripts/record_meta.py            # seeds 0-2 at the default config + horizon sweep

Every number in meta.yaml comes from this script's runs; the chapter page's own figures are stored
beside ours (under ``page``) so a reader can compare, never mixed into them. The determinism test
(tests/test_reproduce.py) re-runs seed 0 and checks it against the ``seeds`` block here.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from pusht.config import make_config  # noqa: E402
from pusht.dreamer import platform_fingerprint, run  # noqa: E402
from pusht.page import PAGE  # noqa: E402

HEADLINE = ["imagined_return_per_step", "real_return_per_step", "imagination_gap",
            "imagined_final_tee_dist", "real_final_tee_dist", "spawn_tee_dist", "real_success_rate",
            "real_block_displacement", "real_episodes_touching_block",
            "zero_action_dream_return_per_step", "zero_action_dream_final_tee_dist",
            "untrained_actor_dream_return_per_step", "untrained_actor_dream_final_tee_dist",
            "final_imagined_reward_per_step_train", "imagined_reward_first20_train",
            "imagined_reward_last20_train"]


def acceptance(m: dict) -> dict:
    """The chapter's lesson, as checks on one run's metrics (see issue 2)."""
    return {
        "gap_above_0.05": m["imagination_gap"] > 0.05,
        "real_success_zero": m["real_success_rate"] == 0,
        "real_block_within_0.03m_of_spawn": abs(m["real_final_tee_dist"] - m["spawn_tee_dist"]) <= 0.03,
        "dream_dist_at_most_half_real": m["imagined_final_tee_dist"] <= 0.5 * m["real_final_tee_dist"],
        "imagined_reward_rose_by_0.03":
            m["imagined_reward_last20_train"] - m["imagined_reward_first20_train"] > 0.03,
        "wm_beats_copy_last_on_pusher": all(m[f"wm_one_step_ratio_{d}"] < 1 for d in ("agent_x", "agent_y")),
        "wm_loses_on_a_block_dim": any(m[f"wm_one_step_ratio_{d}"] > 1 for d in
                                       ("tee_x", "tee_y", "sin(tee_yaw)", "cos(tee_yaw)")),
    }


README = ROOT / "README.md"
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
        ("zero_action_dream_final_tee_dist", "control: zero-action dream, final distance (m)", ".3f"),
        ("untrained_actor_dream_final_tee_dist", "control: untrained-actor dream, final distance (m)", ".3f"),
        ("imagined_reward_first20_train", "imagined reward/step, first 20 iterations", "+.3f"),
        ("imagined_reward_last20_train", "imagined reward/step, last 20 iterations", "+.3f")]


def render_results(meta: dict) -> str:
    """The README's results block, rendered from meta.yaml (never typed)."""
    seeds = list(meta["seeds"])
    page = meta["page"]
    lines = [f"Default config, {meta['seeds'][seeds[0]]['eval_episodes']} held-out starts per seed "
             f"({meta['platform']['cpu_capability']} CPU, torch {meta['platform']['torch']}):", "",
             "| measured | " + " | ".join(f"seed {s}" for s in seeds) + " | chapter page, seed 0 |",
             "| --- |" + " --- |" * (len(seeds) + 1)]
    for key, title, fmt in ROWS:
        ref = page.get(key, {})
        ref = ref.get("seed0", ref.get("about", "")) if isinstance(ref, dict) else ""
        ref = format(ref, fmt) if isinstance(ref, (int, float)) and not isinstance(ref, bool) else ref
        lines.append(f"| {title} | " + " | ".join(format(meta["seeds"][s][key], fmt) for s in seeds)
                     + f" | {ref} |")
    lines += ["", "Imagination horizon sweep (Exercise 2):", "",
              "| run | gap | dream final distance (m) | real final distance (m) | real success |",
              "| --- | --- | --- | --- | --- |"]
    for name, m in meta["horizon_sweep"].items():
        lines.append(f"| {name} | {m['imagination_gap']:+.3f} | {m['imagined_final_tee_dist']:.3f} | "
                     f"{m['real_final_tee_dist']:.3f} | {m['real_success_rate']:.2f} |")
    return "\n".join(lines)


def readme_with_results(meta: dict) -> str:
    from release import splice_readme

    return splice_readme(RESULTS_START, RESULTS_END, render_results(meta))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=ROOT / "meta.yaml")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    p.add_argument("--sweep-seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--horizons", type=int, nargs="+", default=[5, 30])
    args = p.parse_args(argv)

    default = make_config()
    record = {"config": {k: v for k, v in default.to_dict().items() if k not in ("seed", "out")},
              "platform": platform_fingerprint(), "page": PAGE, "seeds": {}, "horizon_sweep": {}}
    for seed in args.seeds:
        t = time.perf_counter()
        res = run(make_config(seed=seed), log=None)
        record["seeds"][seed] = res.metrics
        print(f"seed {seed}: gap {res.metrics['imagination_gap']:+.4f}  "
              f"({time.perf_counter() - t:.1f} s)", flush=True)
    for seed in args.sweep_seeds:
        for hz in args.horizons:
            res = run(make_config(seed=seed, imag_horizon=hz), log=None)
            record["horizon_sweep"][f"seed{seed}_h{hz}"] = {k: res.metrics[k] for k in HEADLINE}
            print(f"seed {seed} horizon {hz}: gap {res.metrics['imagination_gap']:+.4f}", flush=True)
    record["acceptance"] = {seed: acceptance(m) for seed, m in record["seeds"].items()}
    header = ("# Written by scripts/record_meta.py: measured, never edited by hand.\n"
              "# 'page' holds the chapter page's own figures for comparison.\n")
    args.out.write_text(header + yaml.safe_dump(record, sort_keys=False, width=100))
    print(f"wrote {args.out}")
    if args.out == ROOT / "meta.yaml":
        README.write_text(readme_with_results(yaml.safe_load(args.out.read_text())))
        print(f"updated the results in {README}")


if __name__ == "__main__":
    main()
