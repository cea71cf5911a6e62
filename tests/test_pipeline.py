"""The whole chapter in one command: what a learner or CI runs, end to end."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pusht.config import make_config
from pusht.data import EVAL_SEED_BASE, TRAIN_SEED_BASE, VAL_SEED_BASE, load_expert_data, start_seeds
from pusht.dreamer import PAGE_KEYS, run
from pusht.env import PushTEnv

ROOT = Path(__file__).resolve().parents[1]


def cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "pusht.dreamer", *args], cwd=cwd,
                          capture_output=True, text=True)


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("smoke")
    proc = cli("--smoke", "--seed", "0", "--out", str(out), "--cache", str(out / "cache"))
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout


def test_smoke_run_prints_the_chapter_blocks_and_writes_metrics(smoke_run):
    out, stdout = smoke_run
    assert "[wm] epoch" in stdout and "[imag] iter" in stdout and "the imagination gap" in stdout
    metrics = json.loads((out / "metrics.json").read_text())
    assert set(PAGE_KEYS) <= set(metrics)
    assert metrics["smoke"] is True and metrics["seed"] == 0
    assert metrics["imagination_gap"] == pytest.approx(
        metrics["imagined_return_per_step"] - metrics["real_return_per_step"], abs=2e-6)
    for key in ("zero_action_dream_return_per_step", "untrained_actor_dream_final_tee_dist",
                "spawn_tee_dist", "real_block_displacement", "real_pusher_min_gap"):
        assert np.isfinite(metrics[key]), key
    history = np.load(out / "history.npz")
    assert len(history["imag_reward"]) == metrics["imag_iters"]
    assert history["monitor_iters"][-1] == metrics["imag_iters"]


def test_same_seed_same_metrics(smoke_run, tmp_path):
    out, _ = smoke_run
    proc = cli("--smoke", "--seed", "0", "--out", str(tmp_path), "--no-cache", "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "metrics.json").read_text() == (out / "metrics.json").read_text()


@pytest.mark.parametrize("args, message", [
    (["--imag_iters", "0"], "imag_iters must be at least 1"),
    (["--gamma", "1.5"], "gamma must be in (0, 1]"),
    (["--actor_lr", "abc"], "invalid float value"),
    (["--context", "40"], "context (40) must be shorter than seq_len"),
    (["--device", "cuda:7"], "usage:"),
    (["--no-such-flag"], "unrecognized arguments"),
])
def test_bad_arguments_exit_with_usage_not_a_traceback(args, message, tmp_path):
    proc = cli(*args, "--out", str(tmp_path))
    assert proc.returncode == 2
    assert "usage:" in proc.stderr and message in proc.stderr
    assert "Traceback" not in proc.stderr


def test_help_lists_the_chapter_flags_with_their_real_defaults():
    proc = cli("--help")
    assert proc.returncode == 0
    help_text = " ".join(proc.stdout.split())                      # undo argparse's line wrapping
    for flag in ("--seed", "--out", "--smoke", "--imag_horizon", "--imag_iters", "--imag_batch",
                 "--actor_lr", "--gamma", "--lam", "--ent_coef", "--wm_epochs", "--wm_lr",
                 "--batch_size", "--context", "--latent_dim", "--hidden_dim", "--embed_dim",
                 "--eval_episodes", "--eval_horizon", "--device", "--rerun"):
        assert f"{flag} " in help_text, flag
    assert "(default: 400)" in help_text and "(default: 0.0001)" in help_text
    assert "(default: None)" not in help_text                      # "not given" is not a default


def test_training_and_evaluation_starts_never_overlap():
    train = set(start_seeds(TRAIN_SEED_BASE, 0, 300)) | set(start_seeds(VAL_SEED_BASE, 0, 60))
    for run_seed in range(3):
        assert not train & set(start_seeds(EVAL_SEED_BASE, run_seed, 30))


def test_expert_data_is_deterministic_and_cached(tmp_path):
    a = load_expert_data(5, n_episodes=6, n_val_episodes=2, seq_len=8, cache_dir=tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 1
    b = load_expert_data(5, n_episodes=6, n_val_episodes=2, seq_len=8, cache_dir=tmp_path)
    c = load_expert_data(5, n_episodes=6, n_val_episodes=2, seq_len=8, cache_dir=None)
    for name in ("train_obs", "train_act", "val_obs", "mean", "std"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        np.testing.assert_array_equal(getattr(a, name), getattr(c, name))
    assert a.train_obs.shape == (6, 9, 6) and a.train_act.shape == (6, 8, 2)
    assert np.abs(a.train_act).max() <= 1


def test_real_rollouts_keep_both_worlds_trajectories():
    res = run(make_config(smoke=True, out=Path("unused")), log=None)
    dream, real = res.rollouts["dream"], res.rollouts["real"]
    T, B = res.cfg.eval_horizon, res.cfg.eval_episodes
    assert dream.obs.shape == real.obs.shape == (T + 1, B, 6)
    assert dream.actions.shape == real.actions.shape == (T, B, 2)
    # Reality starts from the held-out starts; the dream is warmed on those same frames.
    seeds = start_seeds(EVAL_SEED_BASE, 0, B)
    np.testing.assert_array_equal(real.obs[0], [PushTEnv().reset(s) for s in seeds])
    assert np.isfinite(dream.obs).all()
    # The zero-action control really never moves the pusher's command.
    assert np.all(res.rollouts["dream_zero"].actions == 0)


def test_cached_stages_reproduce_a_fresh_run(tmp_path):
    cfg = make_config(smoke=True, out=tmp_path / "out")
    fresh = run(cfg, log=None)
    first = run(cfg, model_cache=tmp_path / "models", log=None)
    assert sorted(p.name.split("_")[0] for p in (tmp_path / "models").glob("*.pt")) == ["agent", "wm"]
    again = run(cfg, model_cache=tmp_path / "models", log=None)   # both stages load from disk
    assert fresh.metrics == first.metrics == again.metrics
    changed = run(cfg.replace(imag_iters=cfg.imag_iters + 1), model_cache=tmp_path / "models", log=None)
    assert len(list((tmp_path / "models").glob("agent_*.pt"))) == 2  # a new agent, the same model
    assert changed.metrics["imag_iters"] == cfg.imag_iters + 1
