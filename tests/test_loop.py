"""The real-data loop (loop.py): collect with the current policy, grow the data, retrain, re-measure."""

import json

import numpy as np
import pytest
import torch

from pusht import loop
from pusht.config import make_config
from pusht.data import EVAL_SEED_BASE, LOOP_SEED_BASE, MONITOR_SEED_BASE, TRAIN_SEED_BASE, start_seeds
from pusht.dreamer import run
from pusht.evaluate import Rollout, policy_of, real_rollout

SMALL = dict(loop_rounds=2, loop_episodes=6, loop_episode_len=32, loop_imag_iters=10, loop_wm_epochs=2)


@pytest.fixture(scope="module")
def base():
    return run(make_config(smoke=True, seed=0), log=None)


@pytest.fixture(scope="module")
def small_loop():
    return loop.run_loop(make_config(smoke=True, seed=0, **SMALL), log=None)


def test_collection_without_noise_is_the_deterministic_policy(base):
    T = base.data.torch()
    seeds = start_seeds(LOOP_SEED_BASE, 0, 3)
    gen = torch.Generator().manual_seed(0)
    got = loop.collect_episodes(base.wm, base.agent, seeds, 12, T["mean"], T["std"], 0.0, gen)
    ref = real_rollout(base.wm, policy_of(base.agent), seeds, 12, T["mean"], T["std"])
    np.testing.assert_array_equal(got.obs, ref.obs)
    np.testing.assert_array_equal(got.actions, ref.actions)


def test_collection_noise_explores_inside_the_action_box_and_is_seeded(base):
    T = base.data.torch()
    seeds = start_seeds(LOOP_SEED_BASE, 0, 3)

    def collect(noise, seed):
        return loop.collect_episodes(base.wm, base.agent, seeds, 12, T["mean"], T["std"], noise,
                                     torch.Generator().manual_seed(seed))

    quiet, noisy = collect(0.0, 0), collect(0.5, 0)
    assert np.abs(noisy.actions).max() <= 1.0
    assert np.abs(noisy.actions - quiet.actions).mean() > 0.05
    np.testing.assert_array_equal(noisy.obs, collect(0.5, 0).obs)         # same generator seed, same data
    assert not np.array_equal(noisy.obs, collect(0.5, 1).obs)


def test_loop_starts_never_meet_the_other_seed_ranges():
    loop_seeds = set(start_seeds(LOOP_SEED_BASE, 2, 1000))
    for base in (TRAIN_SEED_BASE, EVAL_SEED_BASE, MONITOR_SEED_BASE):
        assert not loop_seeds & set(start_seeds(base, 2, 1000))
    assert max(start_seeds(LOOP_SEED_BASE, 99, 1000)) < 2 ** 32          # a valid numpy seed


def test_clips_are_cut_only_while_the_episode_ran():
    T, B, L = 40, 3, 16
    obs = np.arange((T + 1) * B * 6, dtype=float).reshape(T + 1, B, 6)
    rewards = np.zeros((T, B))
    rewards[20:, 1] = np.nan                      # episode 1 succeeded after 20 steps
    roll = Rollout(obs=obs, actions=np.ones((T, B, 2)), rewards=rewards, pos_err=rewards,
                   success=np.array([False, True, False]))
    c_obs, c_act = loop.rollout_clips(roll, L)
    # two whole clips fit in 40 steps; episode 1's second clip (steps 16-31) overlaps its end
    assert c_obs.shape == (5, L + 1, 6) and c_act.shape == (5, L, 2)
    np.testing.assert_array_equal(c_obs[0], obs[: L + 1, 0])                 # first clip, episode 0
    np.testing.assert_array_equal(c_obs[-1], obs[L: 2 * L + 1, 2])           # second clip, episode 2
    with pytest.raises(ValueError, match="loop_episode_len"):
        loop.rollout_clips(Rollout(obs=obs[:9], actions=np.ones((8, B, 2)), rewards=rewards[:8],
                                   pos_err=rewards[:8], success=roll.success), L)


def test_round_zero_is_the_offline_chapter_run(small_loop, base):
    m0 = small_loop.rounds[0]
    for key in ("imagination_gap", "real_return_per_step", "imagined_return_per_step", "real_success_rate",
                "imagination_gap_train_horizon", "gap_drift_eval_horizon"):
        assert m0[key] == base.metrics[key], key


def test_every_round_grows_the_data_changes_the_model_and_is_measured(small_loop):
    cfg, rounds = small_loop.cfg, small_loop.rounds
    assert [m["round"] for m in rounds] == list(range(cfg.loop_rounds + 1))
    clips_per_episode = cfg.loop_episode_len // cfg.seq_len
    for prev, cur in zip(rounds, rounds[1:]):
        added = cur["train_clips"] - prev["train_clips"]
        assert 0 < added <= cfg.loop_episodes * clips_per_episode
        assert cur["policy_episodes"] == prev["policy_episodes"] + cfg.loop_episodes
        # the model changed: its error on the same held-out expert data moved
        assert cur["wm_expert_one_step_block_err"] != prev["wm_expert_one_step_block_err"]
    for m in rounds:
        for key in ("imagination_gap", "imagination_gap_train_horizon", "real_return_per_step",
                    "imagined_return_per_step", "real_success_rate", "real_block_displacement",
                    "real_episodes_touching_block", "zero_action_dream_return_per_step",
                    "wm_policy_one_step_block_err", "wm_policy_open_loop_block_err",
                    "wm_policy_open_loop_block_copy_err", "wm_expert_open_loop_block_err"):
            assert np.isfinite(m[key]), (m["round"], key)
    assert len(small_loop.rollouts) == len(rounds)


def test_the_loop_is_deterministic(small_loop):
    again = loop.run_loop(make_config(smoke=True, seed=0, **SMALL), log=None)
    assert json.dumps(again.rounds, sort_keys=True) == json.dumps(small_loop.rounds, sort_keys=True)


def test_retrain_modes_run(small_loop):
    cfg = make_config(smoke=True, seed=0, **{**SMALL, "loop_rounds": 1}, loop_wm="retrain", loop_actor="retrain")
    res = loop.run_loop(cfg, log=None)
    assert json.dumps(res.rounds[0], sort_keys=True) == json.dumps(small_loop.rounds[0], sort_keys=True)
    assert res.rounds[1]["imagination_gap"] != small_loop.rounds[1]["imagination_gap"]


@pytest.mark.parametrize("field, value, match", [
    ("loop_wm", "finetune", "loop_wm must be 'continue' or 'retrain'"),
    ("loop_noise", -0.1, "loop_noise"),
    ("loop_episode_len", 8, "loop_episode_len"),
    ("loop_rounds", -1, "loop_rounds"),
])
def test_bad_loop_settings_are_refused_by_name(field, value, match):
    with pytest.raises(ValueError, match=match):
        make_config(**{field: value})


def test_cli_writes_every_round(tmp_path):
    out = tmp_path / "loop"
    args = ["--smoke", "--no-cache", "--quiet", "--out", str(out)] + [f"--{k}={v}" for k, v in SMALL.items()]
    assert loop.main(args) == 0
    rounds = json.loads((out / "loop.json").read_text())
    assert [m["round"] for m in rounds] == [0, 1, 2]
    assert (out / "round2.json").read_text() == json.dumps(rounds[2], indent=2, sort_keys=True) + "\n"
    assert len(json.loads((out / "timing.json").read_text())) == 3


def test_every_key_a_loop_writes_is_built_from_a_template_or_written_whole(small_loop):
    """Round 0 is the chapter's run (metrics.json), rounds 1+ the loop's: no key is composed out of
    sight (pusht/metric_keys.py); a key written whole is a literal at its writer."""
    from tests.test_metric_keys import unfindable

    keys = {k for m in small_loop.rounds for k in m}
    assert len(keys) > 250
    assert unfindable(keys) == []
