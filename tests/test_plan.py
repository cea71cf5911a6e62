"""Notebook 07's package part: the richer data's options, the gate, and the planner (CEM in the frozen
world model), each checked on tiny inputs (issue 41, item 2)."""

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from pusht.cli import parse_config
from pusht.config import make_config
from pusht.config import MIX_STRIDE
from pusht.data import EVAL_SEED_BASE, KINDS, TRAIN_SEED_BASE, VAL_SEED_BASE, DataMix, load_expert_data, start_seeds
from pusht.env import PUSHER_RADIUS, distance_to_tee, obs_to_pose
from pusht.gate import gate, verdict
from pusht.stats import wilson
from pusht.plan import RECIPE, SMOKE_PLAN, SMOKE_RECIPE, PlanSettings, cem_update, knot_index, plan_rollout
from pusht.stage_cache import stage_path
from pusht.wm_stage import WM_FIELDS
from pusht.world_model import WorldModel

ROOT = Path(__file__).resolve().parents[1]
TINY = PlanSettings(horizon=4, knots=2, samples=16, iters=2, elites=4, starts=3)


# --- the data options --------------------------------------------------------------------------
def test_the_default_config_leaves_the_expert_data_as_it_was():
    """The normalisation of seed 5's small expert data, recorded before the options existed (the
    whole arrays were compared then, at seeds 0 and 1 at the default sizes: identical bit for bit)."""
    cfg = make_config()
    assert DataMix.of(cfg).empty and DataMix.of(cfg).tag() == ""
    d = load_expert_data(5, 6, 2, 8, None, DataMix.of(cfg))
    np.testing.assert_allclose(d.mean, [0.12413245538166555, 0.00925243498371473, 0.021275570387095294,
                                        0.02834048060157859, -0.4149763105182928, 0.038004118878214074], rtol=1e-12)
    np.testing.assert_allclose(d.std, [0.18066199264484603, 0.21061320610122922, 0.15807971655438735,
                                       0.11853556236708818, 0.6315529185467483, 0.6538281576469466], rtol=1e-12)
    assert d.train_obs.shape == (6, 9, 6) and (d.train_kind == 0).all()


def test_each_kind_follows_the_expert_data_and_leaves_it_alone():
    plain = load_expert_data(3, 5, 2, 12, None)
    mix = DataMix(noisy=4, pause=4, random=4, noise=0.5, poke=4)
    mixed = load_expert_data(3, 5, 2, 12, None, mix)
    np.testing.assert_array_equal(mixed.train_obs[:5], plain.train_obs)
    np.testing.assert_array_equal(mixed.val_obs, plain.val_obs)              # validation: the expert's alone
    assert mixed.train_kind.tolist() == [0] * 5 + [1] * 4 + [2] * 4 + [3] * 4 + [4] * 4
    assert len(KINDS) * MIX_STRIDE <= VAL_SEED_BASE - TRAIN_SEED_BASE        # every kind's starts are its own
    act, obs = mixed.train_act, mixed.train_obs
    for i in np.flatnonzero(mixed.train_kind == KINDS.index("pause")):
        paused = np.flatnonzero(np.abs(act[i]).sum(-1) == 0)
        assert 3 <= len(paused) <= 12 and np.all(np.diff(paused) == 1)       # one stretch, a quarter to a half
        block = obs[i, paused[0] + 1: paused[-1] + 2, 2:4]
        assert np.abs(block - block[0]).max() < 0.01                         # nobody pushes: it stays put
    walk = act[mixed.train_kind == KINDS.index("random")]
    assert np.abs(walk).max() <= 1 and (np.abs(walk).sum(-1) > 0).all()
    poke = mixed.train_kind == KINDS.index("poke")
    gap = distance_to_tee(obs[poke, 0, :2], obs_to_pose(obs[poke, 0])[1]) - PUSHER_RADIUS
    assert (gap > 0).all() and (gap < 0.025).all()                           # it starts beside the block
    moved = np.linalg.norm(obs[poke, -1, 2:4] - obs[poke, 0, 2:4], axis=-1)
    assert (moved > 0.005).any()                                             # ... and pushes it
    again = load_expert_data(3, 5, 2, 12, None, mix)
    np.testing.assert_array_equal(again.train_act, mixed.train_act)


@pytest.mark.parametrize("change, message", [
    (dict(data_noise=-0.1), "data_noise must be in [0, 2]"),
    (dict(data_pause_episodes=-1), "data_pause_episodes must be a whole number from 0 to 100000"),
    (dict(data_random_episodes=200_000), "data_random_episodes must be a whole number from 0 to 100000"),
    (dict(data_poke_episodes=-2), "data_poke_episodes must be a whole number from 0 to 100000"),
    (dict(data_noisy_episodes=1.5), "data_noisy_episodes must be a whole number"),
    (dict(data_noisy_episodes=5, data_noise=0.0), "needs a data_noise above 0"),
])
def test_the_data_options_are_validated_with_a_clear_message(change, message):
    with pytest.raises(ValueError) as e:
        make_config(**change)
    assert message in str(e.value)


def test_the_data_options_are_flags_and_part_of_both_cache_keys(tmp_path):
    cfg, _ = parse_config(["--smoke", "--data_pause_episodes", "7", "--data_noise", "0.2"])
    assert cfg.data_pause_episodes == 7 and cfg.data_noise == 0.2
    with pytest.raises(SystemExit):
        parse_config(["--data_pause_episodes", "-3"])
    base = make_config(smoke=True)
    keys = {stage_path(tmp_path, "wm", base.replace(**c), WM_FIELDS, "pusht.wm_stage")
            for c in ({}, {"data_pause_episodes": 5}, {"data_random_episodes": 5}, {"data_noisy_episodes": 5},
                      {"data_noisy_episodes": 5, "data_noise": 0.1}, {"data_poke_episodes": 5})}
    assert len(keys) == 6
    load_expert_data(1, 3, 1, 4, tmp_path)
    load_expert_data(1, 3, 1, 4, tmp_path, DataMix(pause=2))
    assert len(list(tmp_path.glob("expert_*.npz"))) == 2


# --- the planner's pieces -------------------------------------------------------------------------
def test_knots_hold_each_action_for_equal_pieces_of_the_plan():
    assert knot_index(16, 4).tolist() == [0] * 4 + [1] * 4 + [2] * 4 + [3] * 4
    assert knot_index(5, 2).tolist() == [0, 0, 0, 1, 1]


def test_the_cem_update_moves_the_mean_toward_the_elites_on_a_quadratic():
    target = torch.tensor([0.6, -0.3])
    gen = torch.Generator().manual_seed(0)
    mean, std = torch.zeros(1, 2), torch.ones(1, 2)
    dist = [float((mean - target).norm())]
    for _ in range(6):
        samples = mean[:, None] + std[:, None] * torch.randn((1, 200, 2), generator=gen)
        scores = -((samples - target) ** 2).sum(-1)                            # best at the target
        new_mean, new_std = cem_update(samples, scores, elites=20, min_std=0.01)
        top = samples[0, scores[0].argsort(descending=True)[:20]]
        torch.testing.assert_close(new_mean[0], top.mean(0))                    # the elites' mean, exactly
        mean, std = new_mean, new_std
        dist.append(float((mean - target).norm()))
    assert dist[1] < dist[0] and dist[-1] < 0.05 and float(std.max()) < 0.2
    assert float(cem_update(samples, scores, 20, min_std=0.5)[1].min()) == 0.5  # the floor holds


@pytest.fixture(scope="module")
def tiny_model():
    data = load_expert_data(0, 6, 2, 8, None)
    T = data.torch()
    torch.manual_seed(0)
    wm = WorldModel(6, 2, 4, 16, 8, predicts="delta").eval()
    wm.set_delta_scale(T["train_obs"])
    return wm, T["mean"], T["std"]


def test_the_planner_is_deterministic_per_seed(tiny_model):
    wm, mean, std = tiny_model
    seeds = start_seeds(EVAL_SEED_BASE, 0, 2)
    a = plan_rollout(wm, seeds, 3, mean, std, TINY)
    b = plan_rollout(wm, seeds, 3, mean, std, TINY)
    np.testing.assert_array_equal(a.actions, b.actions)
    other = plan_rollout(wm, start_seeds(EVAL_SEED_BASE, 1, 2), 3, mean, std, TINY)
    assert not np.array_equal(a.actions, other.actions)
    assert np.abs(a.actions).max() <= 1 and a.rewards.shape == (3, 2)


@pytest.mark.parametrize("window", [0, 2])
def test_batched_planning_gives_the_actions_of_one_start_at_a_time(tiny_model, window):
    wm, mean, std = tiny_model
    seeds, s = start_seeds(EVAL_SEED_BASE, 0, 3), dataclasses.replace(TINY, window=window)
    batched = plan_rollout(wm, seeds, 4, mean, std, s)
    serial = plan_rollout(wm, seeds, 4, mean, std, s, batched=False)
    np.testing.assert_allclose(batched.actions, serial.actions, atol=1e-5)
    alone = plan_rollout(wm, seeds[1:2], 4, mean, std, s)                     # a start alone, as in a batch
    np.testing.assert_allclose(alone.actions[:, 0], batched.actions[:, 1], atol=1e-5)


def test_the_tolerance_objective_weighs_distance_and_angle_by_the_success_test(tiny_model):
    from pusht.env import SUCCESS_ANG, SUCCESS_POS
    from pusht.plan import dream_scores
    from pusht.reward import reward_from_obs

    wm, mean, std = tiny_model
    g = torch.Generator().manual_seed(0)
    h, z = wm._init(5)
    obs0 = torch.randn(5, 6, generator=g)
    z = wm.filter_step(h, obs0)
    actions = torch.rand(5, 4, 2, generator=g) * 2 - 1
    with torch.no_grad():
        hh, zz, outs = h, z, []
        for t in range(4):
            hh, zz = wm.img_step(hh, zz, actions[:, t])
            outs.append(wm.decode(hh, zz))
        r, pos, ang = reward_from_obs(wm.accumulate(torch.stack(outs), obs0), mean, std)
        torch.testing.assert_close(dream_scores(wm, h, z, obs0, actions, mean, std), r.mean(0))
        torch.testing.assert_close(dream_scores(wm, h, z, obs0, actions, mean, std, "tolerance"),
                                   -(pos / SUCCESS_POS + ang / SUCCESS_ANG).mean(0))
    seeds = start_seeds(EVAL_SEED_BASE, 0, 2)
    a = plan_rollout(wm, seeds, 3, mean, std, TINY)
    b = plan_rollout(wm, seeds, 3, mean, std, dataclasses.replace(TINY, objective="tolerance"))
    assert not np.array_equal(a.actions, b.actions)


def test_the_recipe_and_its_smoke_are_valid_configs():
    for recipe, smoke in ((RECIPE, False), (SMOKE_RECIPE, True)):
        cfg = make_config(smoke=smoke, **recipe)
        assert cfg.wm_predicts == "delta" and not DataMix.of(cfg).empty
    PlanSettings(**SMOKE_PLAN).validate()


@pytest.mark.parametrize("change, message", [
    (dict(knots=20), "knots (20) must be at most horizon (16)"),
    (dict(elites=300), "elites (300) must be at most samples (256)"),
    (dict(samples=0), "samples must be a whole number, at least 1"),
    (dict(init_std=0.0), "init_std must be in (0, 2]"),
    (dict(window=-1), "window must be a whole number, 0 or more"),
    (dict(objective="success"), "objective must be one of ('reward', 'tolerance')"),
])
def test_plan_settings_are_validated(change, message):
    with pytest.raises(ValueError) as e:
        PlanSettings(**change).validate()
    assert message in str(e.value)


# --- the gate and the intervals ---------------------------------------------------------------------
def test_the_gate_reads_both_worlds_and_its_verdict_is_the_dreams(tiny_model):
    wm, mean, std = tiny_model
    g = gate(wm, start_seeds(EVAL_SEED_BASE, 0, 3), 6, mean, std)
    for key in ("expert_signal_dream", "expert_signal_dream_se", "expert_signal_real", "expert_signal_real_se",
                "zero_dream_block_moved", "k", "passed"):
        assert key in g, key
    assert g["passed"] == g["dream_ranks_expert_first"] and g["n_starts"] == 3 and g["horizon"] == 6
    good = {"expert_signal_dream": 0.10, "expert_signal_dream_se": 0.01, "expert_signal_real": 0.1,
            "expert_signal_real_se": 0.01}
    assert verdict(good, 30)["passed"]
    assert not verdict({**good, "expert_signal_dream": -0.10}, 30)["passed"]      # ranked the wrong way
    assert not verdict({**good, "expert_signal_dream": 0.01, "expert_signal_dream_se": 0.001}, 30)["passed"]
    with pytest.raises(ValueError, match="at least 2 starts"):
        gate(wm, [1], 6, mean, std)


def test_the_wilson_interval():
    lo, hi = wilson(10, 30)
    assert lo == pytest.approx(0.1923, abs=1e-4) and hi == pytest.approx(0.5122, abs=1e-4)
    assert wilson(0, 30)[0] == 0 and wilson(0, 30)[1] == pytest.approx(0.1135, abs=1e-4)
    assert wilson(30, 30)[1] == 1
    with pytest.raises(ValueError):
        wilson(4, 3)


@pytest.mark.slow                     # a fresh process trains a smoke model: 5-15 s
def test_the_command_line_plans_a_smoke_run_and_prints_its_table(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "pusht.plan", "--smoke", "--seed", "0", "--no-cache", "--quiet",
                           "--serial", "2", "--serial_steps", "2", "--out", str(tmp_path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    for words in ("planner (CEM)", "zero actions", "scripted expert", "95% interval", "gate (3 starts",
                  "batched vs one start at a time"):
        assert words in proc.stdout, words
    res = json.loads((tmp_path / "plan.json").read_text())
    assert res["world_model"]["built_s"] >= res["world_model"]["data_s"] >= 0   # the model's cost, cached or not
    bad = subprocess.run([sys.executable, "-m", "pusht.plan", "--elites", "1"], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert bad.returncode == 2 and "elites must be at least 2" in bad.stderr and "Traceback" not in bad.stderr
