"""Expert data for the world model: short scripted-expert sequences from fresh random starts.

The envs run in lockstep so the vectorised expert decides for all of them in one call. Results are
deterministic by seed, and can be cached on disk: the file's name includes the source of every module
this one runs (``stage_cache.source_hash``: env.py and expert.py among them), so editing the physics
or the expert can never serve stale data.

Notebook 07's richer data (``DataMix``) adds three kinds of training sequence after the expert's,
each from its own starts (so the expert's sequences are the same with or without them):

* ``noisy``: the expert with Gaussian noise on its actions (it strays, and is corrected);
* ``pause``: the expert with one stretch of zero actions mid-sequence (the block off the target and
  nobody pushing it: the one place a zero action meets a block that must stay where it is);
* ``random``: a random walk of the pusher (smooth random actions, no expert at all);
* ``poke``: the same random walk, from a start beside the block, its first step a push into it:
  contacts in every direction, where the expert's pushes all head for the target (so in its data a
  block that moves moves toward the target, whatever pushed it).

With none of them (the chapter's default) the data is exactly the expert's, bit for bit.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from .config import MIX_STRIDE
from .env import (ACT_DIM, ARENA_HALF, OBS_DIM, PUSHER_RADIUS, WALL_RADIUS, PushTEnv, distance_to_tee,
                  sample_start)
from .expert import ScriptedExpert, contact_table
from .stage_cache import cached_file, source_hash

# Disjoint seed ranges: a start used for training can never be an evaluation start.
TRAIN_SEED_BASE = 0               # + run_seed * 1_000_000 + i
VAL_SEED_BASE = 500_000           # + run_seed * 1_000_000 + i
EVAL_SEED_BASE = 1_000_000_000    # + run_seed * 100_000 + episode
MONITOR_SEED_BASE = 2_000_000_000  # + run_seed * 100_000 + episode
LOOP_SEED_BASE = 3_000_000_000     # + run_seed * 100_000 + i: starts of the real-data loop (loop.py)
# The richer data's kinds, in the order their sequences follow the expert's (``ExpertData.train_kind``
# holds each training sequence's index into KINDS). Kind k's starts are the training range's
# k * MIX_STRIDE + i, disjoint from the expert's (i < MIX_STRIDE) and from validation (500_000 on).
KINDS = ("expert", "noisy", "pause", "random", "poke")
RANDOM_WALK_KEEP, RANDOM_WALK_STEP = 0.7, 0.6   # a_t = clip(0.7 a_{t-1} + 0.6 N(0, 1)): a smooth random walk


def start_seeds(base: int, run_seed: int, n: int) -> list[int]:
    """Env reset seeds for ``n`` starts of run ``run_seed`` in the range that begins at ``base``."""
    stride = 1_000_000 if base < EVAL_SEED_BASE else 100_000
    return [base + run_seed * stride + i for i in range(n)]


@dataclass(frozen=True)
class DataMix:
    """How many sequences of each of notebook 07's extra kinds follow the expert's (module doc), and
    the std of the noisy expert's action noise. All zero: the chapter's data, the expert's alone."""

    noisy: int = 0
    pause: int = 0
    random: int = 0
    noise: float = 0.3
    poke: int = 0

    @classmethod
    def of(cls, cfg) -> "DataMix":
        """The mix a ``Config`` asks for (its ``data_*`` fields)."""
        return cls(cfg.data_noisy_episodes, cfg.data_pause_episodes, cfg.data_random_episodes, cfg.data_noise,
                   cfg.data_poke_episodes)

    @property
    def counts(self) -> dict[str, int]:
        return {"noisy": self.noisy, "pause": self.pause, "random": self.random, "poke": self.poke}

    @property
    def empty(self) -> bool:
        return not any(self.counts.values())

    def tag(self) -> str:
        """The cache file's words for this mix ("" for none: the chapter's file name is unchanged)."""
        if self.empty:
            return ""
        noise = f"_sd{self.noise!r}" if self.noisy else ""
        poke = f"-{self.poke}" if self.poke else ""
        return f"_mix{self.noisy}-{self.pause}-{self.random}{poke}{noise}"


def _actor(kind: str, seeds, seq_len: int, noise: float):
    """``act(t, obs (N, 6)) -> actions (N, 2)`` for one kind of sequence (module doc), drawing its
    randomness from one generator per start (seeded by the kind and the start), so a sequence is the
    same whatever else is collected with it."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    expert = ScriptedExpert(len(seeds))
    if kind == "expert":
        return lambda t, obs: expert.act(obs)
    rngs = [np.random.default_rng([KINDS.index(kind), s]) for s in seeds]
    if kind == "noisy":
        return lambda t, obs: np.clip(expert.act(obs) + noise * np.array([r.standard_normal(ACT_DIM) for r in rngs]),
                                      -1.0, 1.0)
    if kind == "pause":   # one pause per sequence: seq_len/4 to seq_len/2 steps, starting anywhere it fits
        length = np.array([r.integers(max(1, seq_len // 4), max(1, seq_len // 2) + 1) for r in rngs])
        start = np.array([r.integers(0, seq_len - n + 1) for r, n in zip(rngs, length)])

        def pause(t, obs):
            a = expert.act(obs)
            a[(start <= t) & (t < start + length)] = 0.0
            return a
        return pause
    if kind == "poke":    # the first step pushes into the block, along a contact's normal (see poke_start)
        prev = np.array([r.uniform(0.3, 1.0) * n for r, n in zip(rngs, _poke_normals(seeds))])
    else:                 # "random": a smooth random walk from a random first action
        prev = np.array([r.uniform(-1.0, 1.0, ACT_DIM) for r in rngs])

    def walk(t, obs):
        nonlocal prev
        if t > 0:
            step = np.array([r.standard_normal(ACT_DIM) for r in rngs])
            prev = np.clip(RANDOM_WALK_KEEP * prev + RANDOM_WALK_STEP * step, -1.0, 1.0)
        return prev.copy()
    return walk


def poke_start(seed: int):
    """A ``poke`` sequence's start: a random start's T pose (``env.sample_start``) with the pusher
    moved beside a random contact of its outline (``expert.contact_table``), its rim 2-20 mm away.
    Returns ``(state for env.reset, world-frame inward normal of that contact)``."""
    rng = np.random.default_rng([KINDS.index("poke"), seed, 1])
    _, tee = sample_start(rng)
    points, normals = contact_table()
    c, s = np.cos(tee[2]), np.sin(tee[2])
    rot = np.array([[c, -s], [s, c]])
    limit = ARENA_HALF - WALL_RADIUS - PUSHER_RADIUS
    while True:
        j = rng.integers(len(points))
        pusher = tee[:2] + rot @ (points[j] - normals[j] * (PUSHER_RADIUS + rng.uniform(0.002, 0.02)))
        if np.all(np.abs(pusher) < limit) and distance_to_tee(pusher, tee) > PUSHER_RADIUS:
            return np.concatenate([pusher, tee]), rot @ normals[j]


def _poke_normals(seeds):
    return [poke_start(s)[1] for s in seeds]


def collect_sequences(seeds, seq_len: int, kind: str = "expert", noise: float = 0.0):
    """Run the expert (or another ``kind`` of :data:`KINDS`, see the module doc) from each start for
    ``seq_len`` steps, all envs in lockstep.

    Returns ``obs`` (N, seq_len+1, 6) and ``act`` (N, seq_len, 2), float64. An episode that
    succeeds early (rare within a few seconds of a random start) is padded with zero actions and
    its final frame: what the sim does under a zero command, up to the few millimetres a body
    coasts in the first 10 ms substep after a push.
    """
    envs = [PushTEnv() for _ in seeds]
    obs = np.zeros((len(seeds), seq_len + 1, OBS_DIM))
    act = np.zeros((len(seeds), seq_len, ACT_DIM))
    if kind == "poke":
        obs[:, 0] = [env.reset(state=poke_start(s)[0]) for env, s in zip(envs, seeds)]
    else:
        obs[:, 0] = [env.reset(s) for env, s in zip(envs, seeds)]
    actor = _actor(kind, seeds, seq_len, noise)
    live = np.ones(len(seeds), dtype=bool)
    for t in range(seq_len):
        a = actor(t, obs[:, t])
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
    train_kind: np.ndarray | None = None   # (N,) index into KINDS of each training sequence (None: all expert)

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
                     cache_dir: Path | str | None = None, mix: DataMix | None = None) -> ExpertData:
    """Collect (or load from ``cache_dir``) the expert data of one run. ``None`` disables caching.

    ``mix`` (notebook 07) appends its extra kinds of training sequence after the expert's; the
    validation sequences stay the expert's alone. The normalisation is over every training frame.
    """
    mix = mix or DataMix()
    if n_episodes > MIX_STRIDE or any(n > MIX_STRIDE for n in mix.counts.values()):
        raise ValueError(f"at most {MIX_STRIDE} sequences of each kind: their starts would overlap")
    path = None
    if cache_dir is not None:
        key = (f"expert_s{run_seed}_n{n_episodes}_v{n_val_episodes}_T{seq_len}{mix.tag()}_"
               f"{source_hash(__name__)}.npz")
        path = Path(cache_dir) / key
        found = cached_file(path)
        if found is not None:
            with np.load(found) as f:
                return ExpertData(**{k: f[k] for k in f.files})
    train_obs, train_act = collect_sequences(start_seeds(TRAIN_SEED_BASE, run_seed, n_episodes), seq_len)
    kinds = [np.zeros(n_episodes, dtype=np.int8)]
    for k, kind in enumerate(KINDS[1:], start=1):
        n = mix.counts[kind]
        if n:
            seeds = [s + k * MIX_STRIDE for s in start_seeds(TRAIN_SEED_BASE, run_seed, n)]
            o, a = collect_sequences(seeds, seq_len, kind, mix.noise)
            train_obs, train_act = np.concatenate([train_obs, o]), np.concatenate([train_act, a])
            kinds.append(np.full(n, k, dtype=np.int8))
    val_obs, val_act = collect_sequences(start_seeds(VAL_SEED_BASE, run_seed, n_val_episodes), seq_len)
    flat = train_obs.reshape(-1, OBS_DIM)
    data = ExpertData(train_obs, train_act, val_obs, val_act, flat.mean(0), np.maximum(flat.std(0), 1e-6),
                      np.concatenate(kinds))
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")   # its own: run_many's workers share a cache
        np.savez(tmp, **data.__dict__)
        os.replace(tmp, path)   # atomic: a half-written cache file is never read
    return data
