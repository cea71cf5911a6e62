"""Notebook 04's figures and self-checks: the imagination gap, taken apart.

Every threshold that decides a sentence here is a multiple of a standard error measured on the
same run (``pusht.analysis``: per-start spread over the evaluation starts, or the training
updates' own spread), never a typed-in amount. The multiple is ``k`` = :func:`k_se`, the two-sided
95% point of Student's t at n - 1 degrees of freedom for n evaluation starts (1.98 for the default 100 starts),
as in notebooks 05 and 06; a difference is also held to the minimum effect that matters
(:data:`~pusht.stats.MIN_REWARD_EFFECT`). Each verdict has four outcomes: beyond k standard
errors and the minimum effect (a change); beyond k standard errors but smaller than the minimum
effect ("detected, but smaller than the minimum effect that matters"); and within the noise.

The notebook imports everything from here. The claims live in ``gap_claims``, Exercise 1 in
``gap_exercise``, the sentences in ``gap_words`` and, for the controls (the scripted expert, the
pusher's replayed paths, the distribution shift), in ``gap_expert``.
"""

from __future__ import annotations

import numpy as np

from ..metric_keys import EXPERT_SIGNAL, GAP, GAP_TERM, RETURN, ZERO_BLOCK_MOVED, key
from ..split import PARTS
from ..env import SUCCESS_ANG, SUCCESS_POS, obs_to_pose
from ..palette import WORLD
from . import figure
from .prose import self_checks
from .gap_words import SPANS, TERMS, _k, _yaw_deg
from .stats import MIN_REWARD_EFFECT

# Re-exported: notebook 04 and learners' released copies import these from here.
from ..config import Config  # noqa: F401
from .gap_claims import (  # noqa: F401
    COUNT_P, DRIFT_SHARE, EXPERT_CONTROL, dream_block_drifts_back, dream_drifts_to_data_position,
    dream_drifts_to_data_yaw, dream_ends_collapse, dream_pays_expert, dream_penalises_expert,
    dream_reproduces_package, drift_half_of_gap, drift_half_on_means, drift_most_every_seed, drift_rosy,
    ex1_letter_decided, expert_solves_most, gap_rosy, half_dominates, pusher_tracked_better_tested,
    pusher_tracked_worse, pusher_tracked_worse_tested, real_beats_zero, real_success,
    real_success_beyond_chance, real_worse_than_zero, reality_pays_expert, register_expert_control,
    term_beyond_noise, term_negative, term_positive, training_exploits, training_exploits_eval,
    typical_pose_near_target, zero_dream_closer)
from .gap_exercise import EX1_OPTIONS, ex1_note, ex1_reconciliation, ex1_sentence, ex1_verdict  # noqa: F401
from .gap_expert import (  # noqa: F401
    SPAN_WORDS, company_text, expert_control_words, expert_text, pusher_paths_text, real_vs_zero, replay_test,
    shift_sentence)
from .gap_words import (  # noqa: F401
    DEFAULT_STARTS, HALVES, K_SE, NEAR, NEAR_DEG, SEED_COLUMNS, TEST_WORDS, after_horizon_training,
    clearly_positive, describe, dip_sentence, dominance_sentence, dominant_half, dream_check_text,
    exploitation_text, half_difference_se, headline_text, k_se, median_start, median_start_text,
    min_of_mean_distance, reading, seeds_sentence, seeds_table, split_sentence, split_story, test_words,
    typical_pose)
from .stats import LEVEL, beyond, count_rise_p, k_for, welch  # noqa: F401


COLORS = WORLD       # one colour per world, the site's too (pusht.palette)


POLICY_LABELS = {"zero": "zero actions", "untrained": "untrained actor", "trained": "trained actor"}


# --- figures -------------------------------------------------------------------------------------
def solved_at_some_step(rollout) -> np.ndarray:
    """(B,) whether the block pose meets the env's success thresholds at any step after the start."""
    _, tee = obs_to_pose(rollout.obs[1:])
    yaw_err = np.abs(np.arctan2(np.sin(tee[..., 2]), np.cos(tee[..., 2])))
    return ((np.linalg.norm(tee[..., :2], axis=-1) < SUCCESS_POS) & (yaw_err < SUCCESS_ANG)).any(axis=0)


@figure
def fig_two_worlds(dream_roll, real_roll, gap: float, seed: int, seconds: float):
    """Reward per step, final block distance and success of one policy in both worlds."""
    import matplotlib.pyplot as plt

    spawn = np.linalg.norm(real_roll.obs[0, :, 2:4], axis=-1)
    rng = np.random.default_rng(0)                       # horizontal jitter for the dots only
    fig, axes = plt.subplots(1, 3, figsize=(13, 5.0))
    ax = axes[0]
    vals = [dream_roll.return_per_step, real_roll.return_per_step]
    for x, (name, v) in enumerate(zip(["dream", "real"], vals)):
        ax.bar(x, v.mean(), 0.6, color=COLORS[name], alpha=0.8,
               label=f"{'imagined (in the dream)' if name == 'dream' else 'real (true PushT)'}: {v.mean():+.3f}")
        ax.scatter(x + rng.uniform(-0.15, 0.15, len(v)), v, s=10, color="k", alpha=0.5, zorder=3)
    ax.annotate("", xy=(0.5, vals[0].mean()), xytext=(0.5, vals[1].mean()),
                arrowprops=dict(arrowstyle="<->", color="k", lw=1.5))
    ax.text(0.55, (vals[0].mean() + vals[1].mean()) / 2, f"gap\n{gap:+.3f}", va="center")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks([0, 1], ["in the dream", "in reality"])
    ax.set_ylabel("mean reward per step (0 = block on target)")
    ax.set_title("Reward per step")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8)
    ax = axes[1]
    vals = [dream_roll.final_tee_dist, real_roll.final_tee_dist]
    for x, (name, v) in enumerate(zip(["dream", "real"], vals)):
        ax.bar(x, v.mean(), 0.6, color=COLORS[name], alpha=0.8, label=f"{name}: {v.mean():.3f} m")
        ax.scatter(x + rng.uniform(-0.15, 0.15, len(v)), v, s=10, color="k", alpha=0.5, zorder=3)
    ax.axhline(spawn.mean(), color="k", ls="--", lw=1, label=f"where the block spawned: {spawn.mean():.3f} m")
    ax.set_xticks([0, 1], ["in the dream", "in reality"])
    ax.set_ylabel("block-to-target distance at the end (m)")
    ax.set_title(f"Where the block ends ({seconds:.0f} s)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8)
    ax.set_ylim(0, max(v.max() for v in vals) * 1.1)
    ax = axes[2]
    solved = [solved_at_some_step(dream_roll), real_roll.success]
    for x, s in enumerate(solved):
        ax.bar(x, s.mean(), 0.6, color=list(COLORS.values())[x], alpha=0.8)
        ax.text(x, s.mean() + 0.03, f"{int(s.sum())}/{len(s)} starts", ha="center")
    ax.set_ylim(0, 1.05)
    ax.set_xticks([0, 1], ["dream (same thresholds\non the decoded block)", "reality (env's flag)"])
    ax.set_ylabel("fraction of starts solved at some step")
    ax.set_title("Task solved?")
    fig.suptitle(f"The same policy in two worlds (seed {seed}, {len(spawn)} held-out starts)")
    fig.tight_layout()
    return fig


@figure
def fig_decomposition(m: dict, steps: dict, n: int | None = None):
    """The controls in both worlds at both horizons, and the gap's three terms with bars of k
    standard errors (:func:`k_se`, from ``n`` or the metrics' ``eval_episodes``).

    ``steps`` maps "train_horizon" and "eval_horizon" to their number of steps.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 5.0), gridspec_kw={"width_ratios": [1, 1, 1.2]})
    x = np.arange(3)
    kk = _k(m, n)
    for ax, span in zip(axes[:2], SPANS):
        for dx, world in ((-0.2, "dream"), (0.2, "real")):
            ax.bar(x + dx, [m[key(RETURN, policy=p, world=world, span=span)] for p in POLICY_LABELS], 0.4,
                   color=COLORS[world], alpha=0.85, label="in the dream" if world == "dream" else "in reality")
        ax.set_xticks(x, list(POLICY_LABELS.values()))
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("mean reward per step")
        ax.set_title(f"First {steps[span]} steps ({SPANS[span]})")
    lo = min(m[key(RETURN, policy=p, world=w, span=s)] for p in POLICY_LABELS for w in ("dream", "real") for s in SPANS)
    for ax in axes[:2]:
        ax.set_ylim(1.3 * lo, 0)
    ax = axes[2]
    width = 0.18
    for j, span in enumerate(SPANS):
        keys = [(GAP, {}), *((GAP_TERM, {"term": t}) for t in TERMS)]
        vals = [m[key(t, span=span, **p)] for t, p in keys]
        errs = [kk * m[key(t, se=True, span=span, **p)] for t, p in keys]
        ax.bar(np.arange(4) + (j - 0.5) * 2 * width, vals, 2 * width, yerr=errs, capsize=3,
               color=("tab:cyan", "tab:blue")[j], label=f"first {steps[span]} steps ({SPANS[span]})")
    ax.set_xticks(np.arange(4), ["gap", *(v.replace(" (", "\n(").replace("actor's ", "actor's\n")
                                          for v in TERMS.values())], fontsize=8)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylabel("reward per step (dream minus reality)")
    ax.set_title(f"The gap = drift + motion + training\n(bars: ±{kk:.2f} standard errors, Student's t 95%)")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    axes[0].legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2)
    fig.suptitle("Three policies, two worlds, two horizons (same starts)")
    fig.tight_layout()
    return fig


@figure
def fig_block_over_time(rollouts: dict, H: int, clip: int, data_mean_dist: float,
                        data_mean_yaw_deg: float | None = None, dt: float = 0.1):
    """Mean block-to-target distance (left) and mean |yaw error| in degrees (right) over time: three
    policies in the dream, zero actions and the trained one in reality, with the training horizon,
    the model's training-clip length and the expert data's mean block pose marked."""
    import matplotlib.pyplot as plt

    fig, (ax, ay) = plt.subplots(1, 2, figsize=(13, 4.6))
    T = len(rollouts["dream_trained"].obs)
    t = np.arange(T) * dt
    dist = lambda r: np.linalg.norm(r.obs[:, :, 2:4], axis=-1).mean(1)           # noqa: E731
    yaw = lambda r: np.abs(_yaw_deg(r.obs)).mean(1)                              # noqa: E731
    curves = [(f"dream_{p}", ls, COLORS["dream"], f"dream, {POLICY_LABELS[p]}")
              for p, ls in zip(POLICY_LABELS, [":", "-.", "-"])]
    curves += [("real_zero", ":", COLORS["real"], "reality, zero actions"),
               ("real_trained", "-", COLORS["real"], "reality, trained actor")]
    for name, ls, color, label in curves:
        if name in rollouts:
            ax.plot(t, dist(rollouts[name]), ls=ls, color=color, label=label)
            ay.plot(t, yaw(rollouts[name]), ls=ls, color=color)
    for a in (ax, ay):
        a.axvline(H * dt, color="k", ls="--", lw=1, label=f"the actor's training horizon ({H} steps)" if a is ax else None)
        a.axvline(clip * dt, color="tab:gray", ls=":", lw=1.2,
                  label=f"the model's training clips ({clip} steps)" if a is ax else None)
        a.set_xlabel("time in the evaluation rollout (s)")
        a.set_ylim(0, None)
    ax.axhline(data_mean_dist, color="tab:green", ls=":", lw=1.5, label="the expert data's mean block pose")
    if data_mean_yaw_deg is not None:
        ay.axhline(data_mean_yaw_deg, color="tab:green", ls=":", lw=1.5)
    ax.set_ylabel("mean block-to-target distance (m)")
    ax.set_title("Where the block is (mean over the starts)")
    ay.set_ylabel("mean |yaw error| of the block (degrees)")
    ay.set_title("How the block is turned (mean over the starts)")
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", ncol=4, fontsize=8)
    fig.suptitle("The block step by step: three policies in the dream, two in reality")
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    return fig


@figure
def fig_expert_control(m: dict, steps: dict, n: int | None = None):
    """The scripted expert's pushes against zero actions, per step, in the dream and in reality,
    over both spans, for the whole reward and each of its terms, with bars of k standard errors
    (:func:`k_se`) and the minimum
    effect that matters shaded."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), sharey=True)
    x = np.arange(3)
    kk = _k(m, n)
    for ax, span in zip(axes, SPANS):
        for dx, world in ((-0.2, "dream"), (0.2, "real")):
            signal = [key(EXPERT_SIGNAL, part=p, world=world, span=span) for p in PARTS]
            noise = [key(EXPERT_SIGNAL, part=p, world=world, se=True, span=span) for p in PARTS]
            ax.bar(x + dx, [m[k] for k in signal], 0.4,
                   yerr=[kk * m[k] for k in noise], capsize=3, color=COLORS[world], alpha=0.85,
                   label="in the dream (the expert's actions replayed)" if world == "dream" else "in reality")
        ax.axhspan(-MIN_REWARD_EFFECT, MIN_REWARD_EFFECT, color="0.85", zorder=0,
                   label=f"smaller than the minimum effect (±{MIN_REWARD_EFFECT:.2f})")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, ["whole reward", "position term", "yaw term"])
        moved = m.get(key(ZERO_BLOCK_MOVED, span=span))
        invalid = moved is not None and moved > SUCCESS_POS
        ax.set_title(f"First {steps[span]} steps ({SPANS[span]})"
                     + (f"\ncontrol INVALID: the zero-action dream moves the untouched block {moved * 100:.0f} cm"
                        if invalid else ""), color="tab:red" if invalid else "k")
    axes[0].set_ylabel(f"expert minus zero actions\n(reward per step; bars: ±{kk:.2f} standard errors)")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8)
    fig.suptitle("Does each world pay the pushes that solve the task more than standing still?")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


@figure
def fig_distribution_shift(real_roll, dream_roll, at_wall_real: np.ndarray, expert_share: float,
                           replay: dict, expert_replay: dict, clip: int, dt: float = 0.1):
    """Three views of the policy leaving the data: the pusher at the walls, the model replaying the
    policy's real actions, and where the dreamed and the real blocks end."""
    import matplotlib.pyplot as plt

    from ..draw import setup_arena

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), gridspec_kw={"width_ratios": [0.7, 1.2, 1]})
    ax = axes[0]
    shares = [expert_share, float(np.nanmean(at_wall_real))]
    ax.bar([0, 1], shares, 0.6, color=["tab:green", COLORS["real"]], alpha=0.85)
    for x, v in enumerate(shares):
        ax.text(x, v + 0.02, f"{v:.0%}", ha="center")
    ax.set_xticks([0, 1], ["expert data\n(the model's training set)", "deployed policy\n(real sim)"])
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("share of steps with the pusher against a wall")
    ax.set_title("Where the pusher spends its time")
    ax = axes[1]
    for body, color in (("pusher", "tab:blue"), ("block", "tab:red")):
        e = replay[body]
        t = (np.arange(len(e)) + 1) * dt
        ax.plot(t, e.mean(1), color=color, lw=2, label=f"{body}, replaying the policy's real actions")
        ex = expert_replay[body]
        ax.plot((np.arange(len(ex)) + 1) * dt, ex.mean(1), color=color, ls="--", lw=1.5,
                label=f"{body}, replaying held-out expert clips")
    ax.axvline(clip * dt, color="tab:gray", ls=":", lw=1.2, label=f"length of the training clips ({clip} steps)")
    ax.set_xlabel("time since the start frame (s)")
    ax.set_ylabel("distance between dreamed and true position\n(m, mean over the starts)")
    ax.set_title("The model replaying actions it is given")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    ax.set_ylim(0, None)
    ax = axes[2]
    setup_arena(ax, "Where the blocks end (one dot per start)")
    ax.scatter(real_roll.obs[0, :, 2], real_roll.obs[0, :, 3], s=60, facecolors="none", edgecolors="k",
               lw=1, label="spawn")
    ax.scatter(real_roll.obs[-1, :, 2], real_roll.obs[-1, :, 3], s=16, color=COLORS["real"], label="reality, end")
    ax.scatter(dream_roll.obs[-1, :, 2], dream_roll.obs[-1, :, 3], s=16, color=COLORS["dream"], label="dream, end")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3)
    fig.suptitle("Does the deployed policy leave the data the model knows?")
    fig.tight_layout()
    return fig


@figure
def fig_pusher_paths(real_roll, touch_tol: float, seconds: float, seed: int, n: int = 6):
    """The real pusher's path for the first ``n`` starts, with the block at spawn and at the end."""
    import matplotlib.pyplot as plt

    from ..draw import draw_state, setup_arena
    from ..evaluate import pusher_gap

    closest = np.nanmin(pusher_gap(real_roll), axis=0)
    show = np.arange(min(n, real_roll.obs.shape[1]))
    fig, axes = plt.subplots(2, 3, figsize=(12, 9.2))
    for ax, j in zip(axes.flat, show):
        setup_arena(ax, f"start {j}: " + ("the pusher touches the block" if closest[j] < touch_tol
                                          else f"closest approach {100 * closest[j]:.1f} cm"))
        draw_state(ax, real_roll.obs[0, j], alpha=0.6, label="T-block at spawn")
        draw_state(ax, real_roll.obs[-1, j], target=False, alpha=0.5, tee_color="none", label="T-block at the end")
        ax.plot(real_roll.obs[:, j, 0], real_roll.obs[:, j, 1], color="tab:blue", lw=1.2, label="pusher path")
        ax.plot(*real_roll.obs[-1, j, :2], "x", color="tab:red", ms=9, mew=2, label="pusher at the end")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    for ax in axes.flat[len(show):]:
        ax.axis("off")
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="lower center", ncol=5, fontsize=9)
    fig.suptitle(f"Where the trained policy drives the real pusher ({seconds:.0f} s, seed {seed})")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


# --- self-checks ---------------------------------------------------------------------------------
SELF_CHECKS = self_checks("04_imagination_gap")  # the words: pusht/nb/text/04_imagination_gap.md
