"""Notebook 01's support module: every figure, every conclusion (both ways), every self-check.

Small synthetic inputs and an untrained tiny world model keep this to a few seconds; the notebook
itself runs in tests/test_notebooks.py.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
import torch
from matplotlib.figure import Figure

import pusht.nb.world_model as nb01
from pusht.env import OBS_NAMES
from pusht.selfcheck import Question, render
from pusht.world_model import WorldModel


def assert_labelled(fig):
    """A figure a learner can read: every plotting axes has both axis labels and a title is set."""
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert axes
    for ax in axes:
        assert ax.get_xlabel() and ax.get_ylabel(), f"unlabelled axes: {ax.get_title()!r}"
    assert any(ax.get_title() for ax in axes) or (fig._suptitle and fig._suptitle.get_text())
    plt.close(fig)


def sequences(n=6, T=10, push_at=4, step=0.01, seed=0):
    """Synthetic (n, T+1, 6) observations: the pusher walks every step; the block rests until
    transition ``push_at`` and then moves ``step`` m per step along x."""
    rng = np.random.default_rng(seed)
    obs = np.zeros((n, T + 1, 6))
    obs[:, :, 0] = np.linspace(0, 0.3, T + 1)
    obs[:, :, 2:4] = rng.uniform(-0.2, 0.2, (n, 1, 2))
    obs[:, push_at + 1:, 2] += step * np.arange(1, T - push_at + 1)
    obs[:, :, 5] = 1.0
    return obs


def error_dict(one_block=1.5, open_block=0.8):
    copy = np.full(6, 0.02)
    return {"one_step_model": np.r_[0.01, 0.01, [0.02 * one_block] * 4], "one_step_copy": copy,
            "open_loop_model": np.r_[0.05, 0.05, [0.02 * open_block] * 4], "open_loop_copy": copy,
            "block_moving_fraction": 0.3}


# --- what moves in the data -------------------------------------------------------------------
def test_an_untouched_block_does_not_creep_so_the_threshold_separates_rest_from_pushes():
    jitter = nb01.resting_jitter(n_starts=2, steps=3)
    assert 0 <= jitter < nb01.MOVE_THRESHOLD


def test_moving_share_counts_transitions_above_the_threshold():
    obs = sequences(T=10, push_at=4, step=0.01)             # 6 of 10 transitions move 1 cm
    assert nb01.moving_share(obs) == pytest.approx(0.6)
    assert nb01.moving_share(obs, threshold=0.02) == 0.0    # the same data, above the step size
    assert nb01.moving_share(obs, dims=nb01.PUSHER) == 1.0


def test_motion_text_says_when_the_jitter_reaches_the_threshold():
    obs = sequences()
    calm = nb01.motion_text(nb01.motion_shares(obs, obs, jitter=0.0))
    assert "exactly 0 m" in calm and "60%" in calm
    noisy = nb01.motion_text(nb01.motion_shares(obs, obs, jitter=0.002))
    assert "mix resting jitter with pushes" in noisy


def test_the_threshold_check_flips_when_the_two_shares_disagree():
    obs = sequences(T=10, push_at=4, step=0.01)
    s = nb01.motion_shares(obs, obs, jitter=0.0)
    assert s["n_train"] == 60 and nb01.threshold_insensitive(s)
    tiny = obs.copy()
    tiny[:, 1:5, 2] += 1e-4 * np.arange(1, 5)               # sub-millimetre creep before the push
    s = nb01.motion_shares(tiny, tiny, jitter=0.0)
    assert not nb01.threshold_insensitive(s) and "clearly hinge" in nb01.motion_text(s)


def test_expert_success_runs_the_expert_in_lockstep():
    runs = nb01.expert_success(n=2)
    assert runs["n"] == 2 and 0 <= runs["successes"] <= 2 and runs["steps"].shape == (2,)
    assert "2" in nb01.expert_text(runs)


# --- the model against copy-last --------------------------------------------------------------
def test_copy_last_verdict_and_text_follow_the_ratios_both_ways():
    v = nb01.copy_last_verdict(error_dict(one_block=1.5, open_block=0.8))
    assert v["pusher_one_wins"] == ["agent_x", "agent_y"]
    assert v["block_one_losses"] == list(OBS_NAMES[2:]) and v["block_open_wins"] == list(OBS_NAMES[2:])
    text = nb01.copy_last_text(v, open_steps=14)
    assert "(ratio above 1) on **all 4**" in text and "worse one step ahead yet better" in text

    flipped = nb01.copy_last_verdict(error_dict(one_block=0.5, open_block=1.5))
    assert flipped["block_one_losses"] == [] and flipped["block_open_wins"] == []
    text = nb01.copy_last_text(flipped, open_steps=14)
    assert "(ratio below 1) on **none of the 4**" in text and "one step ahead yet better" not in text


def test_a_ratio_within_its_noise_of_1_is_a_tie():
    se = {"one": np.full(6, 0.1), "open": np.full(6, 0.01)}
    v = nb01.copy_last_verdict(error_dict(one_block=1.1, open_block=0.8), se)
    assert v["block_one_losses"] == [] and v["block_one_ties"] == list(OBS_NAMES[2:])
    assert v["block_open_wins"] == list(OBS_NAMES[2:])                 # 0.8 is 20 s.e. below 1
    text = nb01.copy_last_text(v, open_steps=14)
    assert "(ratio above 1) on **all 4** dimensions; by more than 2 standard errors on **none of the 4**" in text
    assert "1.10 ± 0.10" in text and "Worse one step ahead, yet better" in text
    v = nb01.copy_last_verdict(error_dict(one_block=1.5, open_block=0.95), {"one": np.full(6, 0.01),
                                                                           "open": np.full(6, 0.1)})
    text = nb01.copy_last_text(v, open_steps=14)          # the open-loop win is within the noise
    assert v["block_open_below"] and not v["block_open_wins"] and "not beyond the noise" in text
    v = nb01.copy_last_verdict(error_dict(one_block=1.1, open_block=0.8), {"one": np.full(6, 0.01),
                                                                          "open": np.full(6, 0.01)})
    assert v["block_one_losses"] == list(OBS_NAMES[2:]) and not v["block_one_ties"]


def test_the_bootstrap_recomputes_the_package_ratios_and_measures_their_spread():
    from pusht.world_model import prediction_error_vs_copy_last

    torch.manual_seed(0)
    wm = WorldModel(6, 2, latent_dim=4, hidden_dim=8, embed_dim=4)
    obs, act = torch.randn(12, 9, 6), torch.rand(12, 8, 2) * 2 - 1
    noise = nb01.copy_last_noise(wm, obs, act, context=2)
    err = prediction_error_vs_copy_last(wm, obs, act, torch.ones(6), context=2)
    v = nb01.copy_last_verdict(err)
    assert np.allclose(noise["one_ratio"], v["one"], rtol=1e-4)
    assert np.allclose(noise["open_ratio"], v["open"], rtol=1e-4)
    assert (noise["one"] > 0).all() and (noise["open"] > 0).all()
    same = np.ones((5, 3))
    assert np.allclose(nb01.ratio_se(same, same), 0)                    # no spread, no noise
    assert np.isnan(nb01.ratio_se(same[:1], same[:1])).all()            # one sequence: unknown


# --- a dream next to the truth ----------------------------------------------------------------
def test_first_push_is_the_first_transition_that_moves_the_block():
    obs = sequences(T=10, push_at=4)
    obs[0, :, 2:4] = obs[0, 0, 2:4]                         # never pushed
    assert nb01.first_push(obs).tolist() == [10] + [4] * 5


def test_pre_push_motion_flips_between_a_still_and_a_drifting_dream():
    true = sequences(T=10, push_at=6)
    context = 2
    still = true[:, context:].copy()                        # a perfect dream
    p = nb01.pre_push_motion(true, still, context)
    assert p["n"] == 6 and p["median"] == 0
    assert not nb01.dream_moves_before_contact(p, noise=0.005)

    drifting = still.copy()
    drifting[:, :, 3] += 0.01 * np.arange(still.shape[1])   # 1 cm per step before any push
    p = nb01.pre_push_motion(true, drifting, context)
    assert p["median"] == pytest.approx(0.04)               # frames 2..6: four steps of drift
    assert nb01.dream_moves_before_contact(p, noise=0.005)
    assert not nb01.dream_moves_before_contact(p, noise=0.05)   # within decoding noise


def test_open_loop_error_splits_at_the_first_push():
    true = sequences(T=10, push_at=6)
    context = 2
    split = nb01.open_loop_by_contact(true, true[:, context:], context)
    assert split["model_before"] == 0 and split["model_after"] == 0
    assert split["copy_before"] == 0 and split["copy_after"] > 0     # copy-last is exact at rest
    assert split["frames_before"] == 6 * 4 and split["frames_after"] == 6 * 4


def test_dream_and_carry_forward_texts_follow_the_measurements():
    true = sequences(T=10, push_at=6)
    context, drifting = 2, true[:, 2:].copy()
    drifting[:, :, 3] += 0.01 * np.arange(drifting.shape[1])
    pre = nb01.pre_push_motion(true, drifting, context)
    split = nb01.open_loop_by_contact(true, drifting, context)
    first = nb01.first_push(true)
    text = nb01.dream_text(pre, split, 0.005, 0, first[0], context)
    assert "already moved **4.0 cm**" in text and "moves before any contact" in text
    v = nb01.copy_last_verdict(error_dict())
    shares = nb01.motion_shares(true, true, 0.0)
    assert "not a model of pushing" in nb01.carry_forward_text(v, pre, 0.005, shares)
    assert "no clear motion before contact" in nb01.carry_forward_text(v, pre, 0.05, shares)
    # pushed before the dream began: the one sequence cannot show the dream before contact
    early = sequences(T=10, push_at=1)
    pre = nb01.pre_push_motion(early, early[:, 2:], context)
    assert pre["n"] == 0
    assert "before the dream starts" in nb01.dream_text(pre, split, 0.005, 0, 1, context)


def test_open_loop_dream_and_decode_noise_on_a_tiny_model():
    torch.manual_seed(0)
    wm = WorldModel(6, 2, latent_dim=4, hidden_dim=8, embed_dim=4)
    obs, act = torch.randn(3, 9, 6), torch.rand(3, 8, 2) * 2 - 1
    dream = nb01.open_loop_dream(wm, obs, act, context=2)
    assert dream.shape == (3, 8 - 2 + 1, 6)
    noise = nb01.decode_noise(wm, obs, act, np.full(6, 0.1))
    assert np.isfinite(noise) and noise > 0


def test_loss_summary_and_text_say_which_way_each_loss_went():
    hist = {"recon": np.r_[np.full(5, 1.0), np.full(5, 0.01)], "dyn": np.r_[np.full(5, 0.01), np.full(5, 0.02)]}
    s = nb01.loss_summary(hist, n_updates_per_epoch=5)
    assert s["recon"] == (1.0, 0.01) and s["dyn"] == (0.01, 0.02)
    text = nb01.loss_text(s)
    assert "reconstruction MSE fell" in text and "dynamics MSE rose" in text


def test_most_moving_picks_the_sequence_whose_block_travels_farthest():
    obs = sequences(step=0.0)
    obs[3, -1, 2] += 0.2
    assert nb01.most_moving(obs) == (3, pytest.approx(0.2))


# --- figures ----------------------------------------------------------------------------------
def test_every_figure_returns_a_labelled_figure():
    obs = sequences(T=10, push_at=4)
    assert_labelled(nb01.fig_starts(seeds=(0,)))
    assert_labelled(nb01.fig_expert(obs[0], np.zeros((10, 2)), True))
    hist = {"recon": np.geomspace(1, 0.01, 20), "dyn": np.geomspace(0.02, 0.003, 20)}
    assert_labelled(nb01.fig_losses(hist, n_updates_per_epoch=5, batch_size=32))
    assert_labelled(nb01.fig_losses(hist))
    assert_labelled(nb01.fig_copy_last(error_dict(), open_steps=8))
    assert_labelled(nb01.fig_copy_last(error_dict(), open_steps=8, se={"one": np.full(6, 0.05),
                                                                          "open": np.full(6, 0.05)}))
    assert_labelled(nb01.fig_dream_vs_true(obs[0], obs[0, 2:], context=2, first_push_step=4, index=0))
    assert_labelled(nb01.fig_dream_vs_true(obs[0], obs[0, 2:], context=2, first_push_step=10, index=0))


def test_the_loss_figure_names_both_losses_and_their_units():
    fig = nb01.fig_losses({"recon": np.ones(4), "dyn": np.ones(4)}, 2, 32)
    ax = fig.axes[0]
    labels = " ".join(t.get_text() for t in ax.get_legend().get_texts())
    assert "reconstruction" in labels and "dynamics" in labels and "standard deviation" in labels
    assert "MSE" in ax.get_title() and "unitless" in ax.get_ylabel()
    plt.close(fig)


# --- self-checks --------------------------------------------------------------------------------
def test_self_checks_are_valid_questions_and_an_empty_answer_never_fails():
    assert 3 <= len(nb01.SELF_CHECKS) <= 4
    for name, q in nb01.SELF_CHECKS.items():
        assert isinstance(q, Question) and len(q.options) >= 3 and q.answer in q.options, name
        assert q.text.strip() and q.why.strip()
        assert "Type one of" in render(q, "")
        assert "is right" in render(q, q.answer)
        wrong = next(k for k in q.options if k != q.answer)
        assert "Not (" in render(q, wrong) and "not one of the options" in render(q, "zz")
