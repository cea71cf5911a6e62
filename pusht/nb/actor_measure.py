"""What notebook 03 measures: where each loss's gradient reaches, what the critic loss's
stop-gradients change, and the imagined and real rises of training with their tests.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from ..imagination import actor_params, lambda_return, set_gradients
from .stats import MIN_REWARD_EFFECT, Test, outcome, sign_test, t_quantile, welch


def gradient_reach(agent, states, rewards, entropy, loss_fn, gamma: float, lam: float,
                   ent_coef: float) -> dict:
    """How large a gradient each loss of ``loss_fn`` sends into each part, on one batch of dreams.

    ``states`` (H+1, B, S), ``rewards`` (H, B) and ``entropy`` come from one dream. The states are
    the road back to the actor's actions; to see whether the critic's values use that road, the
    "states, via the values" row calls ``loss_fn`` once more with the rewards detached, so the
    only way from the loss to the states is through ``agent.value``. Returns
    {(loss, part): gradient norm}.
    """
    states = states.detach().requires_grad_(True)
    actor_loss, critic_loss = loss_fn(agent, states, rewards.detach(), entropy, gamma, lam, ent_coef)
    parts = {"actor's weights": [*agent.actor.parameters(), agent.log_std],
             "critic's weights": list(agent.critic.parameters()), "states, via the values": [states]}

    def norm(loss, params):
        grads = torch.autograd.grad(loss, params, retain_graph=True, allow_unused=True)
        return float(sum((g ** 2).sum() for g in grads if g is not None) ** 0.5)

    out = {}
    for name, loss in (("actor loss", actor_loss), ("critic loss", critic_loss)):
        for part in ("critic's weights", "states, via the values"):
            out[name, part] = norm(loss, parts[part])
    return out


def actor_grad_change(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float,
                      scale: float = 0.5, seed: int = 0) -> float:
    """How much the critic changes the actor's gradient: perturb the critic's weights, recompute
    the actor loss's gradient on the same dreams, and return the largest absolute change (0.0:
    bit-identical).

    ``make_batch()`` must return (states, rewards, entropy) from a fresh dream of ``agent`` with
    the same action noise each call. The critic's weights are restored afterwards. There is no
    noise in this measurement: under the page's wiring the two gradients are bit-identical.
    """
    def actor_grad():
        states, rewards, entropy = make_batch()
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef)
        grads = torch.autograd.grad(actor_loss, [*agent.actor.parameters(), agent.log_std],
                                    allow_unused=True)
        return [torch.zeros(1) if g is None else g for g in grads]

    before = actor_grad()
    saved = [p.detach().clone() for p in agent.critic.parameters()]
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for p in agent.critic.parameters():
            p.add_(scale * torch.randn(p.shape, generator=g))
    try:
        after = actor_grad()
    finally:
        with torch.no_grad():
            for p, s in zip(agent.critic.parameters(), saved):
                p.copy_(s)
    return _max_diff(before, after)


def critic_reaches_actor(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float,
                         scale: float = 0.5, seed: int = 0) -> bool:
    """Does the critic change the actor's gradient? (:func:`actor_grad_change` is not 0.)"""
    return actor_grad_change(agent, make_batch, loss_fn, gamma, lam, ent_coef, scale, seed) > 0


def _max_diff(a: list, b: list) -> float:
    """Largest absolute difference between two lists of same-shaped tensors (0.0: bit-identical;
    NaN where either holds a NaN)."""
    diffs = [float((x - y).abs().max()) for x, y in zip(a, b) if x.numel()]
    return float("nan") if any(d != d for d in diffs) else max(diffs, default=0.0)


def states_undetached(loss_fn):
    """``loss_fn`` with its critic loss replaced by one that reads the imagined states WITHOUT
    detaching them (the target stays detached): the actor loss is ``loss_fn``'s own."""
    def losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=lambda_return):
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn)
        values = agent.value(states)
        target = return_fn(rewards, values, gamma, lam).detach()
        return actor_loss, 0.5 * F.mse_loss(values[:-1], target)
    return losses


def target_undetached(loss_fn):
    """``loss_fn`` with its critic loss replaced by one whose states are detached but whose TARGET
    keeps its gradient (through the rewards, the states and the critic's own values)."""
    def losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=lambda_return):
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn)
        target = return_fn(rewards, agent.value(states), gamma, lam)
        return actor_loss, 0.5 * F.mse_loss(agent.value(states.detach())[:-1], target)
    return losses


ROUTES = ("set_gradients", "one summed backward()")


GROUPS = ("actor's weights", "critic's weights")


def _gradients(agent, make_batch, loss_fn, gamma, lam, ent_coef, route) -> dict:
    """Each parameter group's gradient after one update's backward pass along ``route``."""
    groups = {"actor's weights": actor_params(agent), "critic's weights": list(agent.critic.parameters())}
    every = [p for ps in groups.values() for p in ps]
    for p in every:
        p.grad = None
    states, rewards, entropy = make_batch()
    actor_loss, critic_loss = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef)
    if route == "set_gradients":               # the loop's: each loss on its own group only
        set_gradients(agent, actor_loss, critic_loss)
    elif route == "one summed backward()":     # one optimiser for both: every loss on every group
        (actor_loss + critic_loss).backward()
    else:
        raise ValueError(f"route must be one of {ROUTES}, got {route!r}")
    out = {name: [torch.zeros_like(p) if p.grad is None else p.grad.detach().clone() for p in ps]
           for name, ps in groups.items()}
    for p in every:
        p.grad = None
    return out


def detach_effects(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float) -> dict:
    """What each stop-gradient of the critic loss changes, measured on one update.

    For each variant of ``loss_fn`` (:func:`states_undetached`, :func:`target_undetached`) and
    each route of the gradients into the parameters (``set_gradients``, this loop's; one summed
    ``backward()``, a loop with one optimiser for both networks), the largest absolute difference
    of each parameter group's gradient from ``loss_fn``'s own on the same dreams: 0.0 means bit-identical.
    ``make_batch()``: as for :func:`actor_grad_change`. The agent's ``.grad`` are left None.
    Returns {(variant, route, group): difference}, plus {("norm", route, group): the gradient
    norm of ``loss_fn`` itself} for scale.
    """
    variants = {"critic loss reads the states undetached": states_undetached(loss_fn),
                "critic loss's target keeps its gradient": target_undetached(loss_fn)}
    out = {}
    for route in ROUTES:
        base = _gradients(agent, make_batch, loss_fn, gamma, lam, ent_coef, route)
        for group in GROUPS:
            out["norm", route, group] = float(sum((g ** 2).sum() for g in base[group]) ** 0.5)
        for name, fn in variants.items():
            other = _gradients(agent, make_batch, fn, gamma, lam, ent_coef, route)
            for group in GROUPS:
                out[name, route, group] = _max_diff(base[group], other[group])
    return out


def rise_test(hist: dict, n: int = 20) -> Test:
    """Last-``n`` minus first-``n`` imagined reward per step of a training history, as a Welch's
    t-test with the minimum effect :data:`~pusht.stats.MIN_REWARD_EFFECT`.

    Each update scores a fresh random batch of dreams, so the two windows' spreads measure the
    noise (with 40 updates or more, the standard error is the run's ``imagined_reward_rise_se``).
    A shorter history is split into two halves, so that the windows never overlap.
    """
    r = np.asarray(hist["imag_reward"], dtype=float)
    n = min(n, len(r) // 2)
    return welch(r[:n], r[-n:], min_effect=MIN_REWARD_EFFECT)


def _window(hist: dict, n: int = 20) -> int:
    return min(n, len(hist["imag_reward"]) // 2)


def rise(metrics: dict) -> tuple[float, float]:
    """(last-20 minus first-20 imagined reward per step, its standard error), from a run's metrics."""
    return (metrics["imagined_reward_last20_train"] - metrics["imagined_reward_first20_train"],
            metrics["imagined_reward_rise_se"])


def real_floor(wm, run, cfg, mean, std) -> dict:
    """The real floor's two ends, start by start: the untrained policy (``run.init_agent``, what the
    monitor ran before the first update) and the trained one (``run.agent``, its last point), each
    run again on the monitor's own starts (``MONITOR_SEED_BASE``) for ``cfg.eval_horizon`` steps.

    The training history keeps only the mean over the starts; the per-start values give the
    change its standard error. Returns {"first": (N,), "last": (N,)} reward per step, and
    {"moved_first", "moved_last": (N,)}: how far each start's block ever got from where it spawned (m).
    """
    from ..data import MONITOR_SEED_BASE, start_seeds
    from ..evaluate import policy_of, real_rollout

    seeds = start_seeds(MONITOR_SEED_BASE, cfg.seed, cfg.monitor_episodes)
    out = {}
    for end, agent in (("first", run.init_agent), ("last", run.agent)):
        roll = real_rollout(wm, policy_of(agent), seeds, cfg.eval_horizon, mean, std)
        out[end] = roll.return_per_step
        block = np.asarray(roll.obs)[:, :, 2:4]
        out[f"moved_{end}"] = np.nanmax(np.linalg.norm(block - block[:1], axis=-1), axis=0)
    return out


def floor_test(floor: dict) -> Test:
    """The real floor's change: a one-sample t-test on the per-start changes (the same starts
    before and after, so each start is its own control), minimum effect MIN_REWARD_EFFECT."""
    return sign_test(np.asarray(floor["last"]) - np.asarray(floor["first"]), min_effect=MIN_REWARD_EFFECT)


def metrics_rise_test(m: dict) -> Test:
    """:func:`rise_test` from a run's metrics alone (the two 20-update means and the standard error
    of their difference; 38 degrees of freedom, as two windows of 20 with equal spreads give)."""
    diff, se = rise(m)
    df = 38.0
    k = t_quantile(df)
    return Test(diff, se, df, k, outcome(diff, k * se, MIN_REWARD_EFFECT), MIN_REWARD_EFFECT, "Welch's t-test")


def changed_starts(floor: dict) -> int:
    """How many of the monitor's starts changed their real reward per step at all with training."""
    d = np.asarray(floor["last"], dtype=float) - np.asarray(floor["first"], dtype=float)
    return int(np.sum(d != 0))
