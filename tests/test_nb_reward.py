"""Notebook 02's support module: every figure, every conclusion (both ways), every self-check.

The figures and conclusions take the reward function as an argument (the notebook passes the
learner's); here they get the package's reference and a few deliberately wrong rewards.
"""

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
import torch
from matplotlib.figure import Figure

import pusht.nb.reward as nb02
import pusht.nb.world_model as nb01
from pusht.env import ANG_SCALE, POS_SCALE, shaped_reward
from pusht.reward import reward_from_obs
from pusht.selfcheck import Question, render

MEAN = torch.tensor([0.01, 0.0, 0.02, 0.0, 0.02, 0.13])
STD = torch.tensor([0.19, 0.2, 0.11, 0.11, 0.72, 0.68])
PUSHER = np.array([0.1, -0.1])


def squared(norm_obs, mean, std):
    """Wrong on purpose: the reward falls with the squared distance (a bowl, not a cone)."""
    r, pos, ang = reward_from_obs(norm_obs, mean, std)
    return -0.5 * (pos ** 2 / POS_SCALE + ang / ANG_SCALE), pos, ang


def lopsided(norm_obs, mean, std):
    """Wrong on purpose: x costs twice as much as y."""
    obs = norm_obs * std + mean
    pos = torch.sqrt((2 * obs[..., 2]) ** 2 + obs[..., 3] ** 2)
    ang = torch.abs(torch.atan2(obs[..., 4], obs[..., 5]))
    return -0.5 * (pos / POS_SCALE + ang / ANG_SCALE), pos, ang


def yaw_blind(norm_obs, mean, std):
    """A reward that barely cares about the yaw: a half turn is cheap."""
    r, pos, ang = reward_from_obs(norm_obs, mean, std)
    return -0.5 * (pos / POS_SCALE + 0.1 * ang / ANG_SCALE), pos, ang


def float32_only(norm_obs, mean, std):
    if norm_obs.dtype != torch.float32:
        raise TypeError("float32 only")
    return reward_from_obs(norm_obs, mean, std)


def assert_labelled(fig):
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert axes
    for ax in axes:
        assert ax.get_xlabel() and ax.get_ylabel(), f"unlabelled axes: {ax.get_title()!r}"
    assert any(ax.get_title() for ax in axes) or (fig._suptitle and fig._suptitle.get_text())
    plt.close(fig)


def views_and_dream(n=8, T=10, context=2, bias=0.0, seed=0):
    """Synthetic true frames, a reconstruction and a dream that puts the block ``bias`` m nearer
    the target (positive: a rosier dream), all normalised; plus the dream in metres."""
    g = torch.Generator().manual_seed(seed)
    obs = torch.zeros(n, T + 1, 6)
    obs[..., 2:4] = (torch.rand(n, 1, 2, generator=g) - 0.5) * 0.4 + 0.01 * torch.randn(n, T + 1, 2, generator=g)
    yaw = torch.rand(n, 1, generator=g).expand(n, T + 1)
    obs[..., 4], obs[..., 5] = yaw.sin(), yaw.cos()
    dream = obs[:, context + 1:].clone()
    dream[..., 2:4] *= 1 - bias / dream[..., 2:4].norm(dim=-1, keepdim=True).clamp(min=1e-6)
    norm = nb02.to_norm(obs, MEAN, STD)
    views = nb02.reward_views(reward_from_obs, MEAN, STD, norm, norm.clone(), nb02.to_norm(dream, MEAN, STD))
    return views, dream.numpy()


# --- the shape of the reward ------------------------------------------------------------------
def test_the_reference_reward_is_a_cone_and_wrong_ones_are_not():
    c = nb02.cone_verdict(reward_from_obs, MEAN, STD, PUSHER)
    assert c["is_cone"] and c["slope_per_10cm"] == pytest.approx(-0.1, abs=1e-5)
    assert c["misfit"] <= c["tol"] and "cone with its tip on the target" in nb02.cone_text(c)
    for wrong in (squared, lopsided):
        c = nb02.cone_verdict(wrong, MEAN, STD, PUSHER)
        assert not c["is_cone"], wrong.__name__
        assert "**not** a cone" in nb02.cone_text(c)


def test_a_float32_only_function_falls_back_to_float32_resolution():
    c = nb02.cone_verdict(float32_only, MEAN, STD, PUSHER)
    assert c["is_cone"] and c["noise"] == pytest.approx(np.finfo(np.float32).eps)


def test_cone_text_prices_notebook_01s_pre_push_motion():
    c = nb02.cone_verdict(reward_from_obs, MEAN, STD, PUSHER)
    assert "worth **0.040** per step" in nb02.cone_text(c, 0.04)
    assert "Notebook 01" not in nb02.cone_text(c, float("nan"))


def test_half_turn_against_the_farthest_spawn_both_ways():
    h = nb02.half_turn(reward_from_obs, MEAN, STD, PUSHER, -0.1)
    assert h["r_half"] == pytest.approx(-0.5, abs=1e-4) and h["equivalent_m"] == pytest.approx(0.5, abs=1e-3)
    assert h["r_far"] == pytest.approx(-math.hypot(0.22, 0.22), abs=1e-4)
    assert "more than the whole position term" in nb02.yaw_text(h)
    h = nb02.half_turn(yaw_blind, MEAN, STD, PUSHER, -0.1)
    assert h["r_half"] > h["r_far"] and "no better" in nb02.yaw_text(h)


# --- scoring decoded frames -------------------------------------------------------------------
@pytest.mark.parametrize("bias, sign", [(0.05, "higher"), (-0.05, "lower"), (0.0, "neither")])
def test_error_summary_calls_the_sign_only_beyond_the_noise(bias, sign):
    views, dream_m = views_and_dream(bias=bias)
    e = nb02.reward_errors(views)
    assert e["dream"].shape == (8, 10 - 2) and e["copy"].shape == e["dream"].shape
    s = nb02.error_summary(e)
    assert s["sign"] == sign and s["recon_abs"] == 0
    text = nb02.error_text(s, nb02.unit_circle(dream_m))
    assert (sign in text) if sign != "neither" else ("do not show it rosier or gloomier" in text)
    assert {"higher": "rosier than the truth", "lower": "gloomier", "neither": "roughly cancel"}[sign] \
        in nb02.carry_forward_text(s)


def test_reading_frames_beats_dreaming_only_beyond_the_noise():
    views, dream_m = views_and_dream(bias=0.05)
    s = nb02.error_summary(nb02.reward_errors(views))                 # recon exact, dream 5 cm off
    assert s["dream_worse"] and "reads the block better than it dreams it" in nb02.error_text(s, (1, 1))
    views, _ = views_and_dream(bias=0.0)
    s = nb02.error_summary(nb02.reward_errors(views))                 # both exact
    assert not s["dream_worse"] and "do not show the dream's error to be larger" in nb02.error_text(s, (1, 1))


def test_reward_errors_pair_each_dreamed_step_with_its_true_frame():
    views, _ = views_and_dream(bias=0.0)
    e = nb02.reward_errors(views)
    assert np.allclose(e["dream"], 0, atol=1e-6) and np.allclose(e["recon"], 0)
    true_r = views["true"][0]
    assert np.allclose(e["copy"][:, 0], true_r[:, 2] - true_r[:, 3])   # held from the dream's start frame


def test_unit_circle_measures_the_length_of_the_decoded_pairs():
    x = np.zeros((2, 6))
    x[0, 4:] = (0.6, 0.8)
    x[1, 4:] = (0.6, 1.2)
    lo, hi = nb02.unit_circle(x)
    assert lo == pytest.approx(1.0) and hi == pytest.approx(math.hypot(0.6, 1.2))


def test_recap_quotes_notebook_01s_verdict():
    err = {"one_step_model": np.r_[0.01, 0.01, 0.03, 0.03, 0.01, 0.01], "one_step_copy": np.full(6, 0.02),
           "open_loop_model": np.ones(6), "open_loop_copy": np.ones(6)}
    assert "**2 of 4 (tee_x, tee_y)**" in nb02.recap_text(nb01.copy_last_verdict(err))


# --- figures ----------------------------------------------------------------------------------
def test_every_figure_returns_a_labelled_figure():
    assert_labelled(nb02.fig_reward_heatmap(reward_from_obs, MEAN, STD, PUSHER, n=21))
    assert_labelled(nb02.fig_reward_heatmap(lambda o, m, s: tuple(torch.zeros(o.shape[:-1]) for _ in range(3)),
                                               MEAN, STD, PUSHER, n=11))     # flat: no contour to draw
    assert_labelled(nb02.fig_reward_yaw(reward_from_obs, MEAN, STD, PUSHER, 0.17))
    views, dream_m = views_and_dream()
    assert_labelled(nb02.fig_reward_one_sequence(views, 0, 0.1, context=2))
    assert_labelled(nb02.fig_final_pose(dream_m[0, -1], dream_m[1, -1], 0, 1.0))
    assert_labelled(nb02.fig_reward_error(nb02.reward_errors(views), np.arange(3, 11) * 0.1))


def test_while_nbgrader_runs_a_notebook_no_figure_is_drawn_and_nothing_it_is_given_runs(monkeypatch):
    """Figures grade nothing: under nbgrader (NBGRADER_EXECUTION set) a figure function returns None
    without calling the learner's function it was given, and opens no figure; outside it, it runs."""
    def learners(norm_obs, mean, std):
        raise RuntimeError("the learner's reward ran")

    monkeypatch.setenv("NBGRADER_EXECUTION", "autograde")
    open_before = plt.get_fignums()
    assert nb02.fig_reward_heatmap(learners, MEAN, STD, PUSHER, n=11) is None
    assert plt.get_fignums() == open_before
    monkeypatch.delenv("NBGRADER_EXECUTION")
    with pytest.raises(RuntimeError, match="learner's reward ran"):
        nb02.fig_reward_heatmap(learners, MEAN, STD, PUSHER, n=11)


def test_every_figure_function_of_every_notebook_is_skipped_while_grading():
    """The convention that makes the test above hold for a figure added later: every function of
    pusht.nb whose name says it draws a figure carries ``pusht.nb.figure``."""
    import importlib
    import inspect
    import pkgutil

    import pusht.nb

    skipped = pusht.nb.figure(lambda: None).__code__        # the code of figure's wrapper
    found = []
    for mod in pkgutil.iter_modules(pusht.nb.__path__, "pusht.nb."):
        module = importlib.import_module(mod.name)
        for name, fn in inspect.getmembers(module, inspect.isfunction):
            if fn.__module__ == module.__name__ and (name.startswith("fig_") or name.endswith("_figure")):
                found.append(name)
                assert fn.__code__ is skipped, f"{mod.name}.{name} lacks @figure"
    assert len(found) >= 20, found


# --- self-checks --------------------------------------------------------------------------------
def test_self_checks_are_valid_questions_and_an_empty_answer_never_fails():
    assert 3 <= len(nb02.SELF_CHECKS) <= 4
    for name, q in nb02.SELF_CHECKS.items():
        assert isinstance(q, Question) and len(q.options) >= 3 and q.answer in q.options, name
        assert q.text.strip() and q.why.strip()
        assert "Type one of" in render(q, "")
        assert "is right" in render(q, q.answer)
        wrong = next(k for k in q.options if k != q.answer)
        assert "Not (" in render(q, wrong)


def test_the_numbers_in_the_self_checks_are_the_rewards_own():
    base = shaped_reward([0.3, 0.0], 0.0)[0]
    assert shaped_reward([0.25, 0.0], 0.0)[0] - base == pytest.approx(0.05)          # cone_slope
    yaw30 = -shaped_reward([0.0, 0.0], math.radians(30))[0]
    pos3 = -shaped_reward([0.03, 0.0], 0.0)[0]
    assert yaw30 == pytest.approx(0.083, abs=1e-3) and pos3 == pytest.approx(0.03)  # yaw_vs_position
    assert math.degrees(math.atan2(0.6, 1.2)) == pytest.approx(26.6, abs=0.1)       # off_circle
    assert math.degrees(math.asin(0.6)) == pytest.approx(36.9, abs=0.1)
