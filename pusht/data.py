"""Expert data for the world model: short scripted-expert sequences from fresh random starts.

The envs run in lockstep so the vectorised expert decides for all of them in one call. Results are
deterministic by seed, and can be cached on disk: the file's name includes the source of every module
this one runs (``stage_cache.source_hash``: env.py and expert.py among them), so editing the physics
or the expert can never serve stale data.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from .env import ACT_DIM, OBS_DIM, PushTEnv
from .expert import ScriptedExpert
from .stage_cache import cached_file, source_hash

# Disjoint seed ranges: a start used for training can never be an evaluation start.
TRAIN_SEED_BASE = 0               # + run_seed * 1_000_000 + i
VAL_SEED_BASE = 500_000           # + run_seed * 1_000_000 + i
EVAL_SEED_BASE = 1_000_000_000    # + run_seed * 100_000 + episode
MONITOR_SEED_BASE = 2_000_000_000  # + run_seed * 100_000 + episode
LOOP_SEED_BASE = 3_000_000_000     # + run_seed * 100_000 + i: starts of the real-data loop (loop.py)


def start_seeds(base: int, run_seed: int, n: int) -> list[int]:
    """Env reset seeds for ``n`` starts of run ``run_seed`` in the range that begins at ``base``."""
    stride = 1_000_000 if base < EVAL_SEED_BASE else 100_000
    return [base + run_seed * stride + i for i in range(n)]


def collect_sequences(seeds, seq_len: int):
    """Run the expert from each start for ``seq_len`` steps, all envs in lockstep.

    Returns ``obs`` (N, seq_len+1, 6) and ``act`` (N, seq_len, 2), float64. An episode that
    succeeds early (rare within a few seconds of a random start) is padded with zero actions and
    its final frame: what the sim does under a zero command, up to the few millimetres a body
    coasts in the first 10 ms substep after a push.
    """
    envs = [PushTEnv() for _ in seeds]
    obs = np.zeros((len(seeds), seq_len + 1, OBS_DIM))
    act = np.zeros((len(seeds), seq_len, ACT_DIM))
    obs[:, 0] = [env.reset(s) for env, s in zip(envs, seeds)]
    expert = ScriptedExpert(len(seeds))
    live = np.ones(len(seeds), dtype=bool)
    for t in range(seq_len):
        a = expert.act(obs[:, t])
        obs[:, t + 1] = obs[:, t]
        for i in np.flatnonzero(live):
            act[i, t] = a[i]
            obs[i, t + 1], _, done, _ = envs[i].step(a[i])
            live[i] = not done
    return obs, act


def default_cache_dir() -> Path:
    return Path(os.environ.get("PUSHT_CACHE", Path.home() / ".cache" / "pusht-dreamer"))


@dataclass
class ExpertData:
    """Raw (metres) expert sequences plus the normalisation every network uses."""

    train_obs: np.ndarray   # (N, T+1, 6)
    train_act: np.ndarray   # (N, T, 2), already in [-1, 1]: not normalised
    val_obs: np.ndarray     # (M, T+1, 6), held-out starts
    val_act: np.ndarray
    mean: np.ndarray        # (6,) over all training frames
    std: np.ndarray         # (6,)

    def normalise(self, obs):
        return (obs - self.mean) / self.std

    def torch(self, device="cpu"):
        """Float32 tensors: normalised train/val obs, actions, and mean/std."""
        def t(x):
            return torch.as_tensor(np.asarray(x), dtype=torch.float32, device=device)
        return {"train_obs": t(self.normalise(self.train_obs)), "train_act": t(self.train_act),
                "val_obs": t(self.normalise(self.val_obs)), "val_act": t(self.val_act),
                "mean": t(self.mean), "std": t(self.std)}


def load_expert_data(run_seed: int, n_episodes: int, n_val_episodes: int, seq_len: int,
                     cache_dir: Path | str | None = None) -> ExpertData:
    """Collect (or load from ``cache_dir``) the expert data of one run. ``None`` disables caching."""
    path = None
    if cache_dir is not None:
        key = f"expert_s{run_seed}_n{n_episodes}_v{n_val_episodes}_T{seq_len}_{source_hash(__name__)}.npz"
        path = Path(cache_dir) / key
        found = cached_file(path)
        if found is not None:
            with np.load(found) as f:
                return ExpertData(**{k: f[k] for k in f.files})
    train_obs, train_act = collect_sequences(start_seeds(TRAIN_SEED_BASE, run_seed, n_episodes), seq_len)
    val_obs, val_act = collect_sequences(start_seeds(VAL_SEED_BASE, run_seed, n_val_episodes), seq_len)
    flat = train_obs.reshape(-1, OBS_DIM)
    data = ExpertData(train_obs, train_act, val_obs, val_act, flat.mean(0), np.maximum(flat.std(0), 1e-6))
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")   # its own: run_many's workers share a cache
        np.savez(tmp, **data.__dict__)
        os.replace(tmp, path)   # atomic: a half-written cache file is never read
    return data
