"""Is the pipeline's training bound by per-operation overhead or by arithmetic? One update of each
of its two training loops, timed at the default batch and at a batch of one.

    python -m benchmarks.bench_ops [--repeats 200]

At a batch of one the update runs exactly the same operations (the same Python, the same autograd
graph, the same kernels launched) on almost no numbers, so its time is the per-operation overhead;
what the default batch adds on top is arithmetic. Also prints the two extremes the updates are made
of: a small elementwise add (overhead only) and one of the GRU's matrix products at the default
batch (64 x 64 by 64 x 192), with the floating-point rate it reaches on one thread. One torch thread,
as the chapter runs (``Config.threads``). The figures belong to this host; see
benchmarks/pipeline_wallclock.txt for what was measured where.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import torch
import torch.nn.functional as F

from benchmarks.bench import host_description
from pusht.agent import ActorCritic
from pusht.config import make_config
from pusht.env import ACT_DIM, OBS_DIM
from pusht.imagination import actor_critic_losses, freeze, imagine, set_gradients
from pusht.optim import Adam
from pusht.reward import reward_from_obs
from pusht.world_model import WorldModel

ROOT = Path(__file__).resolve().parents[1]


def median_ms(fn, repeats: int, warmup: int = 20) -> float:
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times) * 1e3


def actor_critic_update(cfg, batch: int):
    """One of train_in_imagination's updates on random start states: dream, score, both losses,
    both gradients, one Adam step."""
    wm = freeze(WorldModel(OBS_DIM, ACT_DIM, cfg.latent_dim, cfg.hidden_dim, cfg.embed_dim))
    agent = ActorCritic(cfg.latent_dim + cfg.hidden_dim, ACT_DIM, cfg.hidden_dim)
    opt = Adam(agent.parameters(), lr=cfg.actor_lr)
    h, z = torch.randn(batch, cfg.hidden_dim), torch.randn(batch, cfg.latent_dim).tanh()
    obs0, mean, std = torch.randn(batch, OBS_DIM), torch.zeros(OBS_DIM), torch.ones(OBS_DIM)

    def step():
        states, obs_pred, entropy = imagine(wm, agent, h, z, cfg.imag_horizon, obs0)
        rewards = reward_from_obs(obs_pred, mean, std)[0]
        actor_loss, critic_loss = actor_critic_losses(agent, states, rewards, entropy, cfg.gamma, cfg.lam,
                                                      cfg.ent_coef)
        opt.zero_grad()
        set_gradients(agent, actor_loss, critic_loss)
        opt.step()
    return step


def world_model_update(cfg, batch: int):
    """One of train_world_model's updates on random sequences: filter, both losses, backward, Adam."""
    wm = WorldModel(OBS_DIM, ACT_DIM, cfg.latent_dim, cfg.hidden_dim, cfg.embed_dim)
    opt = Adam(wm.parameters(), lr=cfg.wm_lr)
    obs, act = torch.randn(batch, cfg.seq_len + 1, OBS_DIM), torch.rand(batch, cfg.seq_len, ACT_DIM) * 2 - 1

    def step():
        recon, dyn = wm.observe(obs, act)
        opt.zero_grad()
        (recon + dyn).backward()
        opt.step()
    return step


def setup(argv, doc: str, repeats: int):
    """The command line of a timing benchmark (``--repeats``) and the default config, with the
    config's torch threads and torch seeded: ``(args, cfg)``."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=repeats)
    args = p.parse_args(argv)
    cfg = make_config()
    torch.set_num_threads(cfg.threads)
    torch.manual_seed(0)
    return args, cfg


def main(argv=None) -> int:
    args, cfg = setup(argv, __doc__, repeats=200)
    print(f"host: {host_description()}; {cfg.threads} torch thread; median of {args.repeats} calls each")
    for name, make, batch, count in (("actor-critic update", actor_critic_update, cfg.imag_batch, cfg.imag_iters),
                                     ("world-model update", world_model_update, cfg.batch_size,
                                      cfg.wm_epochs * -(-cfg.n_episodes // cfg.batch_size))):
        full, one = median_ms(make(cfg, batch), args.repeats), median_ms(make(cfg, 1), args.repeats)
        print(f"  {name}: batch {batch} {full:.2f} ms, batch 1 {one:.2f} ms -> overhead {one / full:.0%}, "
              f"arithmetic {1 - one / full:.0%}; x{count} updates in the default run = {full * count / 1e3:.1f} s, "
              f"of which overhead {one * count / 1e3:.1f} s")
    a, b = torch.randn(64, 64), torch.randn(64, 64)
    w = torch.randn(3 * cfg.hidden_dim, cfg.hidden_dim)
    add_us = median_ms(lambda: a + b, 2000) * 1e3
    mm_us = median_ms(lambda: F.linear(a, w), 2000) * 1e3
    flops = 2 * a.shape[0] * w.shape[0] * w.shape[1]
    print(f"  one 64x64 add: {add_us:.1f} us; one GRU product 64x{cfg.hidden_dim} by {cfg.hidden_dim}x"
          f"{3 * cfg.hidden_dim}: {mm_us:.1f} us = {flops / mm_us / 1e3:.0f} GFLOP/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
