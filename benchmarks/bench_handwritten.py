"""How much could the actor-critic update gain without autograd's per-operation cost? An upper bound.

    python -m benchmarks.bench_handwritten [--repeats 300]

Issue 12 asks for the default pipeline at 0.7x of af06280's wall time, and the actor-critic's 400
updates are the largest part of it (benchmarks/pipeline_wallclock.txt). Two parts of each update
are rewritten here by hand, the way one would to save autograd's bookkeeping, and timed against
the package's code on the same inputs, one torch thread, at the default sizes:

* the dream (``imagination.imagine``: 15 steps of actor, GRU and prior) with its backward pass to
  the actor's parameters: a ``torch.autograd.Function`` whose forward records nothing and whose
  backward is written out step by step, with the actor's weight gradients summed over all steps
  in one matrix product each (autograd makes one per step);
* the lambda-return (``imagination.lambda_return``, a loop of 15 steps) as one triangular matrix
  product, with its backward.

Each hand-written version is first checked against autograd's gradients (they agree to float
rounding, not bit for bit: a hand-written pass adds in another order, which would change every
number the chapter records). Then it prints the median time of each, the saving per update and
what that saving is worth over the default run's ``imag_iters`` updates. It is a bound on what a
rewrite could gain, not code the package uses: nothing in ``pusht`` imports this file.
"""

from __future__ import annotations

import sys
from pathlib import Path

import torch
import torch.nn.functional as F

from benchmarks.bench import host_description
from benchmarks.bench_ops import median_ms, setup
from pusht.agent import ActorCritic
from pusht.env import ACT_DIM, OBS_DIM
from pusht.imagination import freeze, imagine, lambda_return
from pusht.world_model import WorldModel

ROOT = Path(__file__).resolve().parents[1]


class HandwrittenDream(torch.autograd.Function):
    """``imagine``'s states (H+1, B, S) from the actor's parameters, with the backward written out.

    Forward: the same operations as ``imagine`` (actor MLP, tanh-squashed sample, ``nn.GRUCell``'s
    formula, prior MLP), nothing recorded. Backward: back through time, one step at a time, then
    each actor weight's gradient as one product over all steps."""

    @staticmethod
    def forward(ctx, h, z, noise, std, W1, b1, W2, b2, W3, b3, wm):
        gru, prior = wm.gru, wm.prior
        s, states, saved = torch.cat([h, z], -1), [], []
        states.append(s)
        for t in range(noise.shape[0]):
            a1 = F.linear(s, W1, b1).relu()
            a2 = F.linear(a1, W2, b2).relu()
            act = torch.tanh(torch.addcmul(F.linear(a2, W3, b3), std, noise[t]))
            xa = torch.cat([z, act], -1)
            i_r, i_z, i_n = F.linear(xa, gru.weight_ih, gru.bias_ih).chunk(3, 1)
            h_r, h_z, h_n = F.linear(h, gru.weight_hh, gru.bias_hh).chunk(3, 1)
            r, u = torch.sigmoid(i_r + h_r), torch.sigmoid(i_z + h_z)
            n = torch.tanh(torch.addcmul(i_n, r, h_n))
            h_new = torch.addcmul(n, u, h - n)                    # (1 - u) * n + u * h
            q = F.linear(h_new, prior[0].weight, prior[0].bias).relu()
            z_new = torch.tanh(F.linear(q, prior[2].weight, prior[2].bias))
            saved.append((s, a1, a2, act, h, h_n, r, u, n, q, z_new))
            h, z = h_new, z_new
            s = torch.cat([h, z], -1)
            states.append(s)
        ctx.saved, ctx.wm, ctx.W, ctx.noise = saved, wm, (W1, W2, W3), noise
        return torch.stack(states)

    @staticmethod
    def backward(ctx, g_states):
        gru, prior, (W1, W2, W3) = ctx.wm.gru, ctx.wm.prior, ctx.W
        H_dim, Z_dim = gru.weight_hh.shape[1], prior[2].weight.shape[0]
        g_h, g_z = g_states[-1].split([H_dim, Z_dim], -1)
        d_mean, d_pre2, d_pre1 = [], [], []
        for t in reversed(range(len(ctx.saved))):
            s, a1, a2, act, h, h_n, r, u, n, q, z_new = ctx.saved[t]
            d_pz = g_z * (1 - z_new * z_new)                              # prior
            g_h = g_h + (d_pz @ prior[2].weight).mul_(q > 0) @ prior[0].weight
            d_n = g_h * (1 - u) * (1 - n * n)                              # GRU
            d_r = d_n * h_n * r * (1 - r)
            d_u = g_h * (h - n) * u * (1 - u)
            g_h = g_h * u + torch.cat([d_r, d_u, d_n * r], 1) @ gru.weight_hh
            d_xa = torch.cat([d_r, d_u, d_n], 1) @ gru.weight_ih
            d_m = d_xa[:, Z_dim:] * (1 - act * act)                      # tanh of the sample
            d2 = (d_m @ W3).mul_(a2 > 0)                                  # actor
            d1 = (d2 @ W2).mul_(a1 > 0)
            g_s = d1 @ W1 + g_states[t]
            d_mean.append(d_m), d_pre2.append(d2), d_pre1.append(d1)
            g_h, g_z = g_h + g_s[:, :H_dim], d_xa[:, :Z_dim] + g_s[:, H_dim:]

        def rows(xs):                                                     # (H, B, .) -> (H*B, .)
            return torch.stack(xs).flatten(0, 1)
        S, A1, A2 = (rows([sv[k] for sv in ctx.saved]) for k in (0, 1, 2))
        DM, D2, D1 = rows(d_mean[::-1]), rows(d_pre2[::-1]), rows(d_pre1[::-1])
        g_std = (DM * ctx.noise.flatten(0, 1)).sum(0)
        return (None, None, None, g_std, D1.T @ S, D1.sum(0), D2.T @ A1, D2.sum(0), DM.T @ A2, DM.sum(0),
                None)


def lambda_return_matrix(rewards, values, gamma: float, lam: float):
    """``lambda_return`` unrolled: G_t = sum_k (gamma lam)^(k-t) (r_k + gamma (1-lam) V_(k+1)),
    plus (gamma lam)^(H-t) V_H, as one triangular matrix product."""
    H = rewards.shape[0]
    k = torch.arange(H, dtype=rewards.dtype)
    powers = torch.triu((gamma * lam) ** (k[None, :] - k[:, None]).clamp_min(0))   # (H, H)
    base = rewards + gamma * (1 - lam) * values[1:]
    return powers @ base + ((gamma * lam) ** (H - k))[:, None] * values[-1]


def main(argv=None) -> int:
    args, cfg = setup(argv, __doc__, repeats=300)
    B, H = cfg.imag_batch, cfg.imag_horizon
    wm = freeze(WorldModel(OBS_DIM, ACT_DIM, cfg.latent_dim, cfg.hidden_dim, cfg.embed_dim))
    agent = ActorCritic(cfg.hidden_dim + cfg.latent_dim, ACT_DIM, cfg.hidden_dim)
    h0, z0 = 0.5 * torch.randn(B, cfg.hidden_dim), torch.randn(B, cfg.latent_dim).tanh()
    actor = agent.actor
    weights = [actor[0].weight, actor[0].bias, actor[2].weight, actor[2].bias, actor[4].weight, actor[4].bias]
    params = weights + [agent.log_std]
    g_states = torch.randn(H + 1, B, cfg.hidden_dim + cfg.latent_dim)

    def by_autograd():
        torch.manual_seed(1)
        states, _, _ = imagine(wm, agent, h0, z0, H)
        return torch.autograd.grad(states, params, g_states)

    def by_hand():
        torch.manual_seed(1)
        noise = torch.randn(H, B, ACT_DIM)
        states = HandwrittenDream.apply(h0, z0, noise, torch.exp(agent.log_std), *weights, wm)
        return torch.autograd.grad(states, params, g_states)

    worst = max(float((a - b).abs().max() / a.abs().max()) for a, b in zip(by_autograd(), by_hand()))
    assert worst < 1e-4, f"the hand-written dream's gradients disagree with autograd's ({worst:.1e})"

    rewards, values = torch.randn(H, B, requires_grad=True), torch.randn(H + 1, B, requires_grad=True)

    def loop():
        return torch.autograd.grad(lambda_return(rewards, values, cfg.gamma, cfg.lam).mean(), [rewards, values])

    def matrix():
        return torch.autograd.grad(lambda_return_matrix(rewards, values, cfg.gamma, cfg.lam).mean(),
                                   [rewards, values])

    worst_l = max(float((a - b).abs().max() / a.abs().max()) for a, b in zip(loop(), matrix()))
    assert worst_l < 1e-4, f"the matrix lambda-return's gradients disagree ({worst_l:.1e})"

    print(f"host: {host_description()}; {cfg.threads} torch thread; median of {args.repeats} calls; "
          f"batch {B}, horizon {H}")
    total = 0.0
    for name, (package, hand), err in (
            ("dream, forward and backward to the actor", (by_autograd, by_hand), worst),
            ("lambda-return, forward and backward", (loop, matrix), worst_l)):
        a, b = median_ms(package, args.repeats), median_ms(hand, args.repeats)
        total += a - b
        print(f"  {name}: autograd {a:.2f} ms, by hand {b:.2f} ms, saved {a - b:.2f} ms per update "
              f"(gradients agree to {err:.0e} of their largest entry)")
    print(f"  both together: {total:.2f} ms per update, {total * cfg.imag_iters / 1e3:.2f} s over the default "
          f"run's {cfg.imag_iters} updates")
    return 0


if __name__ == "__main__":
    sys.exit(main())
