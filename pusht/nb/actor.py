"""Notebook 03's figures and self-checks: learning to act inside the dream.

The notebook imports everything from here. Its claims live in ``actor_claims``, its measurements
in ``actor_measure``, its sentences in ``actor_words``.
"""

from __future__ import annotations

import numpy as np

from . import figure
from .prose import self_checks

# Re-exported: notebook 03 and learners' released copies import these from here.
from ..imagination import actor_params, lambda_return, set_gradients  # noqa: F401
from .actor_claims import (  # noqa: F401
    IMAGINED, OBJECTIVE, REAL_FLOOR, WIRING_FLOOR, WIRING_RISE, critic_loss_fell, critic_reaches_your_actor,
    critic_spares_page_actor, curve_identical, floor_changes_spread, floor_most_starts_unchanged,
    floor_reproduces_monitor, page_actor_spares_states, small_lam_higher,
    states_detach_idle_under_set_gradients, states_detach_needed_in_summed_backward, target_detach_needed,
    unchanged_starts_untouched, untrained_values_optimistic, verdict, your_actor_reaches_critic_weights,
    your_actor_reaches_states, your_critic_spares_states)
from .actor_measure import (  # noqa: F401
    GROUPS, ROUTES, actor_grad_change, changed_starts, critic_reaches_actor, detach_effects, floor_test,
    gradient_reach, metrics_rise_test, real_floor, rise, rise_test, states_undetached, target_undetached)
from .actor_words import (  # noqa: F401
    carry_forward, critic_reach_sentence, detach_sentence, detach_table, lambda_sentence, match_sentence,
    objective_sentence, reach_reading, reach_table, rose_beyond_noise, training_sentence, wiring_sentence)
from .stats import MIN_REWARD_EFFECT, Test, beyond, outcome, sign_test, t_quantile, welch  # noqa: F401


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
    ax.set_ylabel("lambda-return $G_t$ (reward units):\ndiscounted dreamed rewards from t on\n+ the critic's values")
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
SELF_CHECKS = self_checks("03_imagination_actor")  # the words: pusht/nb/text/03_imagination_actor.md
