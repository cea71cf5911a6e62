"""Notebook 04's support module: every figure draws with labelled axes, every conclusion follows
the numbers it is given (and flips when they do), every self-check is well formed."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from pusht.analysis import at_wall, expert_replay_error, replay_error  # noqa: E402
from pusht.config import make_config  # noqa: E402
from pusht.dreamer import run  # noqa: E402
from pusht.evaluate import TOUCH_TOL  # noqa: E402
from pusht.nb import gap  # noqa: E402


@pytest.fixture(scope="module")
def smoke():
    return run(make_config(smoke=True), log=None)


def labelled(fig):
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    assert axes and all(ax.get_xlabel() or ax.get_xticklabels() for ax in axes)
    assert all(ax.get_ylabel() for ax in axes), [ax.get_title() for ax in axes if not ax.get_ylabel()]


def test_every_figure_draws_from_a_real_run(smoke):
    cfg, m, r = smoke.cfg, smoke.metrics, smoke.rollouts
    T = smoke.data.torch()
    labelled(gap.fig_two_worlds(r["dream"], r["real"], m["imagination_gap"], 0, 2.0))
    labelled(gap.fig_decomposition(m, {"train_horizon": cfg.imag_horizon, "eval_horizon": cfg.eval_horizon}))
    labelled(gap.fig_block_over_time(r, cfg.imag_horizon, cfg.seq_len, 0.02))
    rep = replay_error(smoke.wm, r["real"], T["mean"], T["std"])
    exp = expert_replay_error(smoke.wm, smoke.data.val_obs, smoke.data.val_act, T["mean"], T["std"])
    assert rep["pusher"].shape == (cfg.eval_horizon, cfg.eval_episodes) and (rep["block"] >= 0).all()
    labelled(gap.fig_distribution_shift(r["real"], r["dream"], at_wall(r["real"].obs[1:]), 0.0, rep, exp,
                                        cfg.seq_len))
    labelled(gap.fig_pusher_paths(r["real"], TOUCH_TOL, 2.0, 0, n=4))
    assert 0 <= gap.median_start(r["dream"], r["real"]) < cfg.eval_episodes


def test_the_sentences_read_the_run_they_are_given(smoke):
    m = smoke.metrics
    for span, n in (("train_horizon", 15), ("eval_horizon", 20)):
        s = gap.split_sentence(m, span, n)
        assert f"{m[f'imagination_gap_{span}']:+.3f}" in s and f"{m[f'gap_drift_{span}']:+.3f}" in s
    assert f"{m['real_pusher_at_wall_share']:.0%}" in gap.shift_sentence(m)
    assert "seed 0's" in gap.seeds_sentence({0: m})
    gap.dip_sentence(smoke.rollouts, smoke.cfg.imag_horizon)


def _m(gap_, gse, drift, dse, success=0.0):
    return {"imagination_gap": gap_, "imagination_gap_se_eval_horizon": gse, "gap_drift_eval_horizon": drift,
            "gap_drift_se_eval_horizon": dse, "real_success_rate": success}


def test_exercise_one_verdict_covers_every_outcome():
    assert gap.ex1_verdict([_m(0.2, 0.02, 0.2, 0.02, success=0.1), _m(0.2, 0.02, 0.2, 0.02)]) == "a"
    assert gap.ex1_verdict([_m(0.2, 0.02, 0.15, 0.02)] * 2) == "c"        # rosy with zero actions
    assert gap.ex1_verdict([_m(0.2, 0.02, 0.02, 0.02)] * 2) == "b"        # the actor's doing
    assert gap.ex1_verdict([_m(0.03, 0.02, 0.0, 0.02)] * 2) == "d"        # within noise: not rosier
    assert gap.ex1_verdict([_m(-0.2, 0.02, 0.0, 0.02)] * 2) == "d"        # the dream is gloomier
    assert gap.ex1_verdict([_m(0.2, 0.02, 0.15, 0.02), _m(0.2, 0.02, 0.01, 0.02)]) == "b"  # mixed: on the means
    assert set(gap.EX1_OPTIONS) == {"a", "b", "c", "d"}


def test_a_term_is_only_called_positive_beyond_twice_its_noise():
    assert gap.describe(0.05, 0.02) == "clearly positive"
    assert gap.describe(0.03, 0.02) == "not told apart from zero"
    assert gap.describe(-0.05, 0.02) == "clearly negative"
    m = {"gap_training_train_horizon": 0.05, "gap_training_se_train_horizon": 0.01,
         "gap_training_eval_horizon": 0.0, "gap_training_se_eval_horizon": 0.01,
         "gap_drift_train_horizon": 0.1, "imagination_gap_train_horizon": 0.15}
    assert "exploitation" in gap.split_story(m, 15) and "that advantage is gone" in gap.split_story(m, 15)
    m["gap_training_train_horizon"] = 0.01
    assert "found little to exploit" in gap.split_story(m, 15)


def test_self_checks_are_well_formed():
    for q in gap.SELF_CHECKS.values():
        assert q.answer in q.options and q.why and q.text.endswith("?")
