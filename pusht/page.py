"""The chapter page's own published figures, for comparison only.

These are the numbers the chapter page reports (seed 0 unless a range is given). They are never
used as results: every figure a learner reads as OUR result comes from a run (see meta.yaml).
Kept in the package so that notebooks can quote them wherever they run, Colab included.
"""

PAGE = {
    "imagined_return_per_step": {"seed0": -0.144, "seeds0_2": [-0.22, -0.144]},
    "real_return_per_step": {"seed0": -0.384, "seeds0_2": [-0.392, -0.383]},
    "imagination_gap": {"seed0": 0.240, "seeds0_2": [0.17, 0.24]},
    "imagined_final_tee_dist": {"seed0": 0.011},
    "real_final_tee_dist": {"seed0": 0.160},
    "spawn_tee_dist": {"about": 0.17},
    "real_success_rate": {"seed0": 0.0, "seeds0_2": [0.0, 0.0]},
    "final_imagined_reward_per_step_train": {"seed0": -0.244},
    "horizon_sweep_5_vs_30": "dream tee-dist ~0.01-0.02 m at both, real ~0.16 m, success 0.00 at both",
    "wall_clock_one_seed_s": 13,
}
