"""Notebook 05's support module: the horizon sweep's verdict flips with the numbers it is given
(judged against the spread across actor seeds), every figure draws with labelled axes, every
sentence reads the numbers it is given, and every self-check is well formed."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from pusht.nb import horizon as nb05  # noqa: E402
from pusht.selfcheck import Question, render  # noqa: E402

H = [5, 15, 30]


def labelled(fig):
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    assert axes and all(ax.get_xlabel() for ax in axes) and all(ax.get_ylabel() for ax in axes)
    assert all(ax.get_title() for ax in axes)


def sweep(means, spread=0.01):
    """{horizon: [three actor seeds' values]} around the given means."""
    return {h: [m - spread, m, m + spread] for h, m in zip(H, means)}


# --- the statistics ------------------------------------------------------------------------------
def test_t_quantile_matches_the_printed_tables():
    for df, k in ((1, 12.706), (2, 4.303), (4, 2.776), (10, 2.228), (30, 2.042), (1e6, 1.960)):
        assert nb05.t_quantile(df) == pytest.approx(k, abs=2e-3)
    assert nb05.t_quantile(2.5) < nb05.t_quantile(2) and nb05.t_quantile(4, level=0.99) > nb05.t_quantile(4)


def test_a_change_counts_only_beyond_the_spread_across_seeds():
    up = nb05.gap_change([-0.16, -0.15, -0.17], [0.21, 0.22, 0.20])
    assert up.outcome == "up" and up.diff == pytest.approx(0.37) and up.ratio > up.k
    assert nb05.gap_change([0.21, 0.22, 0.20], [-0.16, -0.15, -0.17]).outcome == "down"
    # the same mean difference (0.05) counts with a tight spread, not with a wide one
    assert nb05.gap_change([0.10, 0.11, 0.12], [0.15, 0.16, 0.17]).outcome == "up"
    wide = nb05.gap_change([0.0, 0.11, 0.22], [0.05, 0.16, 0.27])
    assert wide.outcome == "same" and wide.ratio < wide.k
    # k is Student's t at Welch's degrees of freedom: 4 for equal spreads and three seeds each
    assert nb05.gap_change([1, 2, 3], [2, 3, 4]).df == pytest.approx(4.0)
    assert nb05.gap_change([1, 2, 3], [2, 3, 4]).k == pytest.approx(2.776, abs=2e-3)
    with pytest.raises(ValueError, match="at least two actor seeds"):
        nb05.gap_change([0.1], [0.2, 0.3])


def test_identical_seeds_still_give_a_verdict():
    assert nb05.gap_change([0.2, 0.2], [0.2, 0.2]).outcome == "same"
    assert nb05.gap_change([0.2, 0.2], [0.3, 0.3]).outcome == "up"


def test_the_sign_of_one_horizon_is_judged_against_its_own_spread():
    assert nb05.sign_test([-0.10, -0.19, -0.18]).outcome == "down"
    assert nb05.sign_test([0.21, 0.22, 0.20]).outcome == "up"
    assert nb05.sign_test([-0.05, 0.0, 0.06]).outcome == "same"


# --- Exercise 2's verdict ------------------------------------------------------------------------
def test_the_verdict_maps_every_outcome_to_an_option():
    assert set(nb05.EX2_OPTIONS) == {"a", "b", "c"} == set(nb05.VERDICT_LETTER.values())
    assert nb05.ex2_verdict(sweep([0.10, 0.15, 0.20])) == "a"            # grows
    assert nb05.ex2_verdict(sweep([-0.15, 0.13, 0.21])) == "a"           # grows through a sign flip
    assert nb05.ex2_verdict(sweep([0.20, 0.15, 0.10])) == "b"            # shrinks
    assert nb05.ex2_verdict(sweep([0.15, 0.0, -0.15])) == "b"            # shrinks through a sign flip
    assert nb05.ex2_verdict(sweep([0.20, 0.20, 0.205])) == "c"           # within the spread
    assert nb05.ex2_verdict(sweep([0.20, 0.25, 0.24], spread=0.1)) == "c"  # a wide spread swallows it
    assert nb05.ex2_verdict({30: [0.2, 0.21, 0.22], 5: [0.0, 0.01, 0.02]}) == "a"   # any order of keys


def test_by_horizon_regroups_runs_per_actor_seed():
    runs = {(30, 0): {"g": 3.0}, (5, 1): {"g": 1.5}, (5, 0): {"g": 1.0}, (30, 1): {"g": 3.5}}
    assert nb05.by_horizon(runs, "g") == {5: [1.5, 1.0], 30: [3.0, 3.5]}
    assert list(nb05.by_horizon(runs, "g")) == [5, 30]


# --- sentences -----------------------------------------------------------------------------------
def test_the_reconciliation_names_each_horizon_and_the_sign_flip():
    text = nb05.reconcile_text(sweep([-0.15, 0.13, 0.21]), 30, 100)
    assert "5 steps: gap -0.150" in text and "30 steps: gap +0.210" in text and "**" not in text
    assert "From 5 to 30 steps the gap rose" in text and "changed sign" in text
    same = nb05.reconcile_text(sweep([0.20, 0.20, 0.205]), 30, 100)
    assert "did not change beyond the spread" in same and "changed sign" not in same


def test_the_worlds_sentence_says_which_side_moved():
    real = sweep([-0.41, -0.40, -0.41])
    succ = {h: [0, 0, 0] for h in H}
    s = nb05.worlds_sentence(sweep([-0.57, -0.27, -0.20]), real, succ, 30)
    assert "the dream's verdict moved; reality did not" in s and "0/90 at 30 steps" in s
    s = nb05.worlds_sentence(sweep([-0.2, -0.2, -0.2]), sweep([-0.5, -0.4, -0.3]), succ, 30)
    assert "reality's verdict moved, not the dream's" in s


def test_the_terms_sentence_sees_what_the_horizon_cannot_change():
    terms = {"drift": {h: [0.225] * 3 for h in H},
             "motion": {h: [0.011, 0.001, 0.005] for h in H},
             "training": sweep([-0.39, -0.10, -0.02])}
    s = nb05.terms_sentence(terms, sweep([-0.57, -0.27, -0.20]), {h: [-0.16, -0.17, -0.17] for h in H})
    assert "+0.225** per step in every run" in s and "same at every horizon" in s
    assert "Negative means" in s and "worse in the very world model" in s
    assert nb05.same_at_every_horizon(terms["drift"]) and not nb05.same_at_every_horizon(terms["training"])
    c = nb05.conclusion(sweep([-0.15, 0.13, 0.21]), sweep([-0.41, -0.40, -0.41]), terms)
    assert "Reality pays the same" in c and "The gap did move" in c and "all of that change" in c
    c = nb05.conclusion(sweep([0.20, 0.20, 0.205]), sweep([-0.5, -0.4, -0.3]), terms)
    assert "Reality moved" in c and "Nor did the gap move" in c


def test_the_other_sentences_read_their_numbers():
    s = nb05.own_horizon_sentence(sweep([0.045, 0.098, 0.17], spread=0.003))
    assert "+0.045" in s and "At every horizon" in s
    s = nb05.block_sentence(sweep([0.215, 0.104, 0.112]), sweep([0.169, 0.159, 0.171]), 0.158)
    assert "0.215 m" in s and "After training with 5-step dreams" in s
    assert "After training" not in nb05.block_sentence(sweep([0.1] * 3), sweep([0.16] * 3), 0.158)
    curve = np.array([0.15, 0.12, 0.10, 0.14, 0.2])                  # closest at step 2, 0.2 s
    assert nb05.closest_approach(curve) == (pytest.approx(0.10), pytest.approx(0.2))
    curves = {h: {"dream": np.stack([curve] * 3), "real": np.stack([curve] * 3)} for h in H}
    assert "0.2 s (0.100 m) after 5-step training" in nb05.block_sentence(
        sweep([0.2] * 3), sweep([0.16] * 3), 0.158, curves)


# --- figures -------------------------------------------------------------------------------------
def test_every_figure_draws_with_labelled_axes():
    gaps = sweep([-0.15, 0.13, 0.21])
    labelled(nb05.fig_gap_vs_horizon(gaps, sweep([-0.57, -0.27, -0.20]), sweep([-0.41, -0.40, -0.41]), 100))
    terms = {"drift": {h: [0.225] * 3 for h in H}, "motion": {h: [0.01, 0.0, 0.005] for h in H},
             "training": sweep([-0.39, -0.10, -0.02])}
    labelled(nb05.fig_gap_terms(terms, gaps))
    rng = np.random.default_rng(0)
    curves = {h: {w: rng.uniform(0.05, 0.2, (3, 21)) for w in ("dream", "real")} for h in H}
    labelled(nb05.fig_block_over_time(curves))
    one_seed = {5: [0.1], 30: [0.2]}                                  # a single seed still draws
    labelled(nb05.fig_gap_vs_horizon(one_seed, one_seed, one_seed, 20))
    import matplotlib.pyplot as plt
    plt.close("all")


def test_mean_block_distance_reads_the_block_columns():
    class Roll:
        obs = np.zeros((3, 2, 6))
    Roll.obs[:, :, 2:4] = [[0.3, 0.4], [0.0, 0.1]]
    assert nb05.mean_block_distance(Roll) == pytest.approx([0.3, 0.3, 0.3])


# --- self-checks ---------------------------------------------------------------------------------
def test_self_checks_are_well_formed():
    assert len(nb05.SELF_CHECKS) >= 3
    for name, q in nb05.SELF_CHECKS.items():
        assert isinstance(q, Question) and q.answer in q.options and len(q.options) >= 3, name
        assert q.why and "Type one of" in render(q, "")                  # an empty answer never fails
        assert "is right" in render(q, q.answer)
