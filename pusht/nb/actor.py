"""Notebook 03's figures, conclusions and self-checks: learning to act inside the dream."""

from __future__ import annotations

import numpy as np
import torch

from ..selfcheck import Question
from . import figure

# --- what each loss reaches --------------------------------------------------------------------


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


def critic_reaches_actor(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float,
                         scale: float = 0.5, seed: int = 0) -> bool:
    """Does the critic change the actor's gradient? Perturb the critic's weights and compare.

    ``make_batch()`` must return (states, rewards, entropy) from a fresh dream of ``agent`` with
    the same action noise each call. The critic's weights are restored afterwards. This is a yes or
    no question with no noise: under the page's wiring the two gradients are bit-identical.
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
    return not all(torch.equal(a, b) for a, b in zip(before, after))


def reach_table(reach: dict[str, dict]) -> str:
    """Markdown table of :func:`gradient_reach` results, one column per wiring."""
    names = list(reach)
    first = reach[names[0]]
    rows = ["| loss | its gradient reaches | " + " | ".join(names) + " |",
            "|---|---|" + "---|" * len(names)]
    for (loss, part) in first:
        rows.append(f"| {loss} | {part} | " + " | ".join(f"{reach[n][loss, part]:.3g}" for n in names) + " |")
    return "\n".join(rows)


# --- conclusions -------------------------------------------------------------------------------


def rise(metrics: dict) -> tuple[float, float]:
    """(last-20 minus first-20 imagined reward per step, its standard error)."""
    return (metrics["imagined_reward_last20_train"] - metrics["imagined_reward_first20_train"],
            metrics["imagined_reward_rise_se"])


def rose_beyond_noise(metrics: dict, k: float = 2.0) -> bool:
    """Did the imagined reward rise over training by more than ``k`` standard errors?

    The standard error is measured from the run itself (the spread of the 20 per-update values at
    each end; each update scores a fresh random batch of dreams). k = 2: a rise that large happens
    by chance about once in 40 runs of a policy that did not improve.
    """
    up, se = rise(metrics)
    return bool(up > k * se)


def training_sentence(metrics: dict) -> str:
    """What training did to the imagined and the real reward, read from one run's metrics."""
    up, se = rise(metrics)
    real = metrics["real_reward_monitor_last"] - metrics["real_reward_monitor_first"]
    first, last = metrics["imagined_reward_first20_train"], metrics["imagined_reward_last20_train"]
    s = (f"Over training, the imagined reward per step went from **{first:+.3f}** (mean of the first 20 "
         f"updates) to **{last:+.3f}** (the last 20): a change of **{up:+.3f}**, with a standard error of "
         f"{se:.3f} measured from the updates' own spread. ")
    s += ("That is a real rise: more than twice its noise. " if rose_beyond_noise(metrics) else
          "That is within twice its noise: this run cannot tell it from no change. ")
    s += (f"On the real monitoring starts the same policy went from {metrics['real_reward_monitor_first']:+.3f} "
          f"to {metrics['real_reward_monitor_last']:+.3f} per step ({real:+.3f}).")
    return s


def wiring_sentence(dreamer: dict, page: dict) -> str:
    """Compare the two wirings' runs (metrics of each), in words, on the measured numbers only."""
    d_up, d_se = rise(dreamer)
    p_up, p_se = rise(page)
    diff, diff_se = d_up - p_up, float(np.hypot(d_se, p_se))
    s = (f"With the critic reaching the actor (Dreamer's wiring) the imagined reward rose by **{d_up:+.3f}** "
         f"(± {d_se:.3f}); with the page's wiring, where the actor sees only the dreamed rewards, by "
         f"**{p_up:+.3f}** (± {p_se:.3f}). ")
    if abs(diff) <= 2 * diff_se:
        s += "The two rises are within twice their combined noise of each other. "
    else:
        s += (f"The {'page' if diff < 0 else 'Dreamer'} wiring raised the imagined per-step reward more, "
              f"by {abs(diff):.3f} (beyond twice the combined noise of {diff_se:.3f}). ")
    s += ("Keep in mind what each one maximises: the page's actor pushes only the rewards of its "
          f"{dreamer['imag_horizon']} dreamed steps, Dreamer's pushes the lambda-return, in which the "
          "critic's values stand for everything after them. Deployed for the full evaluation, the gap is "
          f"**{dreamer['imagination_gap']:+.3f}** with Dreamer's wiring and **{page['imagination_gap']:+.3f}** "
          f"with the page's; real success is {dreamer['real_success_rate']:.0%} and "
          f"{page['real_success_rate']:.0%}.")
    return s


# --- figures -----------------------------------------------------------------------------------


def _smooth(x: np.ndarray, w: int) -> np.ndarray:
    return np.convolve(x, np.ones(w) / w, mode="valid")


@figure
def fig_lambda_returns(returns_by_lam: dict, train_lam: float, n_dreams: int):
    """Mean lambda-return per dreamed step for several lambdas (dict lam -> (H,) array)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.8))
    for (lam, G), style in zip(returns_by_lam.items(), (":", "-.", "-", "--", "-")):
        ax.plot(np.arange(len(G)), G, style, lw=2, marker="o", ms=3,
                label=f"lam = {lam:g}" + (" (training)" if lam == train_lam else ""))
    ax.set_xlabel("dreamed step t")
    ax.set_ylabel("lambda-return $G_t$\n(discounted sum of reward per step)")
    ax.set_title(f"Your lambda-return on {n_dreams} dreams, untrained critic (mean over dreams)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_training(hists: dict, monitor_episodes: int):
    """Imagined reward per update (moving average) and the real monitor, for each named run.

    ``hists`` maps a label (e.g. "Dreamer's wiring") to a training history.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 4.3))
    colors = ["tab:red", "tab:blue", "tab:green", "tab:purple"]
    for (label, h), color in zip(hists.items(), colors):
        imag = np.asarray(h["imag_reward"])
        w = max(1, min(20, len(imag) // 10))
        it = np.arange(len(imag))
        ax.plot(it, imag, color=color, alpha=0.15, lw=1)
        ax.plot(it[w - 1:], _smooth(imag, w), color=color, lw=2.2,
                label=f"{label}: imagined (moving average of {w} updates)")
        ax.plot(h["monitor_iters"], h["monitor_real_reward"], "s--", color=color, lw=1.2, ms=6,
                label=f"{label}: real sim, same policy ({monitor_episodes} starts)")
    ax.set_xlabel("policy update (iteration)")
    ax.set_ylabel("reward per step")
    ax.set_title("The same policy during training, in the dream and in the real sim")
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


@figure
def fig_critic_and_std(hist: dict):
    """The critic's loss and the actor's exploration noise over training."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 3.4), sharex=True)
    cl = np.asarray(hist["critic_loss"])
    it = np.arange(len(cl))
    w = max(1, min(20, len(cl) // 10))
    axes[0].plot(it, cl, color="tab:purple", alpha=0.3, lw=1, label="every update")
    axes[0].plot(it[w - 1:], _smooth(cl, w), color="tab:purple", lw=2, label=f"moving average of {w}")
    axes[0].set_title("Critic loss")
    axes[0].set_ylabel("0.5 x squared error\n(return units squared)")
    axes[0].legend(fontsize=8)
    ret = np.asarray(hist["imag_return"])
    axes[1].plot(it, ret, color="tab:red", alpha=0.3, lw=1)
    axes[1].plot(it[w - 1:], _smooth(ret, w), color="tab:red", lw=2)
    axes[1].set_title("What the actor maximises")
    axes[1].set_ylabel("mean lambda-return\n(critic's bootstrap included)")
    axes[2].plot(it, hist["log_std"], color="tab:green", lw=2)
    axes[2].set_title("Actor's exploration noise")
    axes[2].set_ylabel("log std of the action noise\n(before tanh, mean over both axes)")
    for ax in axes:
        ax.set_xlabel("policy update (iteration)")
    fig.tight_layout()
    return fig


# --- self-checks -------------------------------------------------------------------------------
SELF_CHECKS = {
    "lam_one": Question(
        "With `lam = 1`, which critic value still enters the return G_0?",
        {"a": "None: lam = 1 is the pure sum of the dreamed rewards",
         "b": "Only V_H, the value of the last dreamed state, discounted by gamma^H",
         "c": "All of V_1 .. V_H, each weighted equally"},
        "b", "G_H = V_H closes the recursion; every (1 - lam) V_{t+1} term vanishes, but the last "
             "state's value is still added, discounted by gamma^H."),
    "critic_detach": Question(
        "Suppose the critic's loss read the imagined states WITHOUT detaching them. What would "
        "training the critic then do?",
        {"a": "Nothing different: the critic's optimiser only steps the critic's weights",
         "b": "Its gradient would reach the actor's actions through the dream: value regression "
              "could then move the policy (toward states that are easy to predict)",
         "c": "The critic would learn faster because it sees more gradient"},
        "b", "The states are functions of the actor's actions. Dreamer detaches them in the "
             "critic's loss so that no gradient from value regression can reach the policy, "
             "whatever the optimiser set-up."),
    "page_wiring": Question(
        "Under the chapter page's wiring (values detached inside the actor's return), what does "
        "the actor learn from the critic?",
        {"a": "Nothing: its gradient comes only from the H dreamed rewards, so replacing the "
              "critic by zeros gives the same actor",
         "b": "The value of the states beyond the horizon, through V_H",
         "c": "Only the sign of the advantage"},
        "a", "A detached value is a constant to the actor's gradient. The test in this notebook "
             "perturbs the critic's weights and finds the page's actor gradient bit-identical."),
    "what_rises": Question(
        "The imagined reward rises during training. What does that, on its own, tell you about "
        "the real robot?",
        {"a": "That it improves too, maybe more slowly",
         "b": "Nothing yet: it measures the policy against the dream's picture of the block, which "
              "is the very thing the actor is free to exploit",
         "c": "That the world model is accurate"},
        "b", "Only a measurement in reality can say; the real monitor above and notebook 04 make it."),
}
