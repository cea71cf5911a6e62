"""Notebook 06's figures and self-checks: closing the gap with real data, and two fixes.

What comes in. ``rounds`` is ``pusht.loop``'s list of per-round metrics, in order (``loop.json``):
round 0 is the offline chapter run, each later round has collected real episodes with the current
policy plus exploration noise, trained the world model further on all data and the actor further
in it, and measured both worlds on the chapter's evaluation starts again. The two other fixes are
single offline runs, each a ``metrics.json`` dict: a world model that predicts changes
(``wm_predicts="delta"``) and an ensemble with MOPO's disagreement penalty. Their reference is the
chapter's single state model, which is also the loop's round 0.

Where every threshold comes from (no tolerance is typed in; the two physical constants below say
why they are what they are):

* **A gap, and a change of it.** Every gap carries its standard error over the evaluation starts
  (``imagination_gap_se_<span>``, from ``pusht.split.gap_split``). A change between two runs
  (round 0 and the last round, or a fix against the single model) is judged against
  sqrt(se_1^2 + se_2^2), the standard error of a difference of two independent means. The two runs
  use the SAME starts, and a start that is hard for one is likely hard for the other: the per-start
  gaps are positively correlated, the true standard error of the difference is smaller, and this
  test is conservative (it calls fewer changes than the paired test would; the metrics do not keep
  the per-start values that test needs). A change counts beyond ``k`` standard errors, k the
  two-sided 95% point of Student's t at eval_episodes - 1 degrees of freedom
  (:func:`pusht.stats.t_quantile`: 1.98 for the default 100 starts). A difference that large would turn up
  by chance, in a run that changed nothing, in about one comparison in 20 or fewer. It must also be
  at least the minimum effect that matters, ``stats.MIN_REWARD_EFFECT`` (0.02 reward per step: the
  block held the 2 cm success tolerance nearer the target on every step). A gap **shrank** when its
  size fell by both, without ending on the other side of zero beyond the noise (that is a change of
  sign: the opposite error). A **fix** needs that at both horizons, a drift that does not turn into
  the opposite error, and a zero-action dream that moves the untouched block no farther than the
  reference's (:func:`fix_verdict`).
* **Claims.** Every sentence that depends on the run is chosen by a registered claim
  (``pusht.nb.claims``, names "06.*"), so ``make claims`` records each one on every seed.
* **Which world moved the gap.** The dream's and reality's ratings (reward per step) each carry
  their own per-start standard error (``split.gap_split``), and each side's change is judged
  against its own (:func:`sides`): reality varies far less from start to start than the dream, and
  the gap's yardstick would hide a real change of reality. Whether the dream came down for this
  policy or everywhere is read against the zero-action dream (:func:`policy_specific_words`).
* **Counts** (real successes, episodes touching the block, out of the evaluation starts). A success
  is an event, not an estimate: one is enough to leave 0%, which is what Exercise 3 asks. Whether a
  rise could be luck is Fisher's exact test on the two counts (:func:`count_rise_p`), one-sided,
  against 2.5%, the same bar as one side of the two-sided 95% tests.
* **Where the block goes** (mean over starts of how far it moved, and of spawn distance minus final
  distance). The metrics keep no per-start spread, but they keep the largest displacement, and each
  start's values are bounded by it: a displacement lies in [0, max], and a start's change of
  distance to the target is at most its displacement (triangle inequality). That bounds their
  standard errors (:func:`displacement_se_bound`, :func:`toward_se_bound`); a change counts beyond
  k of these bounds. Conservative again: a real change may go uncalled, a called one is real.
* **The world model's errors** (RMSE in metres over many clips) carry no standard error either.
  ``ERR_RES``: a change of an error counts when it exceeds 1 mm. That is a resolution, not a test:
  the sentences say so.
* **Which half of a gap is the larger.** A half is "the larger" only when the difference of the
  sizes, |yaw| - |position|, exceeds k of its standard errors and is at least the minimum reward
  effect (:func:`halves_order`); otherwise neither half is clearly the larger. Its standard error
  is computed start by start (``split.size_split``). So is that of the **size of the error**,
  |position| + |yaw| (the gap can reach zero with both halves large and of opposite signs: they
  cancel): a fix must shrink it too (:func:`fix_verdict`), and the drift is judged by its size the
  same way. Where the halves share a sign the size is the gap's size with the gap's standard error,
  so the gap and the size are one quantity under one test. Two halves **cancel almost exactly**
  when they have opposite signs and their sum is less than ``CANCEL_SHARE`` (a quarter) of
  |position| + |yaw|.
* **The expert control** (expert minus zero actions) is valid only where the zero-action dream
  leaves an untouched block within the success tolerance (``gap.expert_control_words``); where it
  does not, the sentences say so and read the expert's own gap (dream minus reality) instead.
* ``ARENA``: a dreamed pusher farther from the real one than the arena is wide is off the table.

The notebook imports everything from here. The claims live in ``closing_claims``; the measured
changes and the metric keys in ``closing_changes``; Exercise 3 in ``closing_exercise``; the
sentences about the rounds in ``closing_words``, about the fixes in ``closing_fixes``, and the
conclusion and summary table in ``closing_summary``.
"""

from __future__ import annotations

import numpy as np

from ..metric_keys import GAP, WM_COPY_ERR, WM_ERR, key
from ..palette import WORLD
from . import figure
from .prose import self_checks
from .closing_changes import (SPAN_KEYS, _dream_key, _real_key, _series, _steps, displacement_se_bound,
                              successes, toward_se_bound)
from .closing_words import DATA_LABELS

# Re-exported: notebook 06 and learners' released copies import these from here.
from ..env import ARENA_HALF, CONTROL_DT, OBS_NAMES, SUCCESS_POS  # noqa: F401
from .closing_changes import (  # noqa: F401
    COUNT_P, Change, ERR_RES, TEST_NAME, compare, expert_ratio, fix_change, gap_change, metric_change,
    success_rose, toward_outcome)
from .closing_claims import (  # noqa: F401
    EXPERT_CONTROL, beats_copy_last_everywhere, block_closer, block_farther, change_down, change_up,
    count_beyond_chance, dream_fell_for_the_policy, dream_gloomier, dream_penalises_expert,
    dream_rewards_expert, dream_rosier, drift_crossed_zero, error_accumulates, error_size_grew,
    error_size_shrank, ex3_letter_decided, fix_closed_gap, gap_crossed_zero, gap_grew, gap_reopened,
    gap_shrank, halves_cancel, model_better_on_policy, model_moves_untouched_block, model_worse_somewhere,
    no_real_success, position_half_clearly_larger, pusher_left_table, shared_bias, success_rose_claim,
    untouched_block_on_table, yaw_half_clearly_larger)
from .closing_exercise import (  # noqa: F401
    EX3_NOTE, EX3_OPTIONS, ex3_reconciliation, ex3_verdict, reconcile_text)
from .closing_fixes import (  # noqa: F401
    ARENA, TRAIN_TAIL, delta_sentence, ensemble_sentence, fix_verdict, fixes_table)
from .closing_summary import SUMMARY_KINDS, conclusion, summary_runs, summary_table  # noqa: F401
from .closing_words import (  # noqa: F401
    CANCEL_SHARE, ORDER_WORDS, block_sentence, error_size, expert_short, expert_words, halves_order,
    halves_rule, halves_words, model_error_sentence, path_words, policy_specific_words, reopen_words,
    rounds_sentence, rounds_table, sides, size_change, trend_phrase, yaw_share)
from .gap import NEAR, expert_control_words, register_expert_control  # noqa: F401
from .stats import (  # noqa: F401
    LEVEL, MIN_REWARD_EFFECT, THIN_MARGIN, Test, beyond, clear_of_threshold, count_rise_p, k_for,
    margin_words)


WORLD_COLORS = WORLD     # one colour per world, the site's too (pusht.palette)


DATA_COLORS = {"policy": "tab:red", "expert": "tab:blue"}


# --- figures --------------------------------------------------------------------------------------
def _round_axis(ax, rounds):
    r = [m["round"] for m in rounds]
    ax.set_xticks(r)
    ax.set_xlabel("loop round (0 = the offline chapter run)")
    ax.set_xlim(min(r) - 0.4, max(r) + 0.4)


def _legend_below(ax, ncol=2, y=-0.2):
    """A legend under the axes (its top ``y`` axes-heights below them), so it never covers a curve."""
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, y), ncol=ncol, frameon=False)


@figure
def fig_rounds(rounds: list):
    """Left: the gap per round over the training horizon and over the whole evaluation, ± one
    standard error over the starts. Middle: the gap's position and yaw halves per round (whole
    evaluation). Right: the dream's and reality's rating per round (whole evaluation), the zero-action
    dream beside them as the control, with each round's real successes under its round number. Legends
    sit under the axes."""
    import matplotlib.pyplot as plt

    x = np.array([m["round"] for m in rounds], dtype=float)
    last = rounds[-1]
    fig, axes = plt.subplots(1, 3, figsize=(17, 5.2))
    ax = axes[0]
    for dx, span, color in ((-0.06, "train_horizon", "tab:cyan"), (0.06, "eval_horizon", "k")):
        g = _series(rounds, key(GAP, span=span))
        se = _series(rounds, key(GAP, se=True, span=span))
        ax.errorbar(x + dx, g, yerr=se, fmt="o-", color=color, capsize=4, lw=1.5,
                    label=f"over {_steps(last, span)}")
    ax.axhline(0, color="gray", lw=1, ls="--", label="dream = reality")
    ax.set_ylabel("imagination gap (imagined minus real\nreward per step; bars: ± 1 standard error)")
    ax.set_title("The gap, round by round")
    _round_axis(ax, rounds)
    _legend_below(ax)
    ax = axes[1]
    for dx, part, color in ((-0.06, "position", "tab:blue"), (0.06, "yaw", "tab:red")):
        g = _series(rounds, key(GAP, part=part, span="eval_horizon"))
        se = _series(rounds, key(GAP, se=True, part=part, span="eval_horizon"))
        ax.errorbar(x + dx, g, yerr=se, fmt="o-", color=color, capsize=4, lw=1.5,
                    label=f"{part} half" + (" (the block's angle)" if part == "yaw" else " (its distance)"))
    ax.axhline(0, color="gray", lw=1, ls="--")
    ax.set_ylabel("part of the gap (reward per step;\nbars: ± 1 standard error)")
    ax.set_title(f"The gap's two halves ({_steps(last, 'eval_horizon')})")
    _round_axis(ax, rounds)
    _legend_below(ax)
    ax = axes[2]
    ax.plot(x, _series(rounds, _dream_key("eval_horizon")), "o-", color=WORLD_COLORS["dream"], lw=2,
            label="in the dream")
    ax.plot(x, _series(rounds, _real_key("eval_horizon")), "s-", color=WORLD_COLORS["real"], lw=2, label="in reality")
    # the control: the same dream for a pusher that never moves; if it falls as far, the dream did not come
    # down for this policy
    ax.plot(x, _series(rounds, "zero_action_dream_return_per_step"), "^:", color=WORLD_COLORS["dream"], lw=1.5,
            label="control: the dream of a pusher that never moves")
    ax.set_ylabel("mean reward per step\n(0 = block on target)")
    ax.set_title(f"Both worlds' ratings ({_steps(last, 'eval_horizon')};\nthe gap is dream minus reality)")
    _round_axis(ax, rounds)
    ax.set_xticks(x, [f"{int(r)}\n{successes(m)}/{m['eval_episodes']} solved" for r, m in zip(x, rounds)])
    ax.set_xlabel("loop round (0 = the offline chapter run),\nreal successes under each")
    _legend_below(ax, y=-0.34)
    fig.suptitle("Dreamer's real-data loop: collect with the policy, train the model on everything, dream again")
    fig.tight_layout()
    return fig


@figure
def fig_model_error(rounds: list):
    """The world model's one-step (top) and open-loop (bottom) RMSE per round, pusher (left) and
    block (right), on the policy's data and on held-out expert data; copy-last dashed."""
    import matplotlib.pyplot as plt

    x = [m["round"] for m in rounds]
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True)
    for i, kind in enumerate(("one_step", "open_loop")):
        for j, part in enumerate(("pusher", "block")):
            ax = axes[i, j]
            vals = []
            for data in ("policy", "expert"):
                model = _series(rounds, key(WM_ERR, data=data, kind=kind, body=part))
                copy_ = _series(rounds, key(WM_COPY_ERR, data=data, kind=kind, body=part))
                vals += model + copy_
                ax.plot(x, model, "o-", color=DATA_COLORS[data], lw=2, label=f"world model, {DATA_LABELS[data]}")
                ax.plot(x, copy_, "o--", color=DATA_COLORS[data], lw=1.2, alpha=0.7,
                        label=f"copy-last, {DATA_LABELS[data]}")
            if all(v > 0 for v in vals):                   # log scale only where every value can go on it
                ax.set_yscale("log")
            ax.set_ylabel(f"{part} position RMSE (m)")
            ax.set_title(f"{'One step ahead' if kind == 'one_step' else 'Open loop (the dream alone)'}: {part}")
            _round_axis(ax, rounds)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, fontsize=8, loc="lower center", ncol=4, frameon=False)
    fig.suptitle("The world model's error, round by round: on the policy's data (red) and the expert's (blue)")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


@figure
def fig_block(rounds: list):
    """What the real policy does to the block, per round: episodes touching it, how far it moved
    (mean, with the bound on its standard error, and the largest), and how much closer to the target
    it ends than it spawned (mean, with the bound on its standard error)."""
    import matplotlib.pyplot as plt

    x = np.array([m["round"] for m in rounds], dtype=float)
    n = rounds[-1]["eval_episodes"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    ax = axes[0]
    ax.bar(x, _series(rounds, "real_episodes_touching_block"), 0.6, color="tab:green", alpha=0.8)
    ax.set_ylim(0, n)
    ax.set_ylabel(f"evaluation episodes touching the block (of {n})")
    ax.set_title("Does the pusher reach the block?")
    _round_axis(ax, rounds)
    ax = axes[1]
    ax.errorbar(x, _series(rounds, "real_block_displacement"), yerr=[displacement_se_bound(m) for m in rounds],
                fmt="o-", color="tab:green", capsize=4, label="mean (bar: bound on 1 standard error)")
    ax.plot(x, _series(rounds, "real_block_displacement_max"), "v", color="tab:green", mfc="none",
            label="largest")
    ax.set_ylim(0, None)
    ax.set_ylabel("block displacement, spawn to end (m)")
    ax.set_title("How far the block moves")
    _legend_below(ax)
    _round_axis(ax, rounds)
    ax = axes[2]
    ax.errorbar(x, _series(rounds, "real_block_toward_target"), yerr=[toward_se_bound(m) for m in rounds],
                fmt="o-", color="tab:brown", capsize=4, label="mean (bar: bound on 1 standard error)")
    ax.axhline(0, color="gray", ls="--", lw=1, label="ends as far as it spawned")
    ax.set_ylabel("spawn distance minus final distance\nto the target (m; > 0 = closer)")
    ax.set_title("Does it move toward the target?")
    _legend_below(ax)
    _round_axis(ax, rounds)
    fig.suptitle(f"The real block under each round's policy ({n} evaluation starts)")
    fig.tight_layout()
    return fig


@figure
def fig_fixes(state_m: dict, loop_last_m: dict, delta_m: dict, ens_m: dict, labels=None):
    """The three fixes beside the single state model: the gap over the training horizon and over the
    whole evaluation (± one standard error), and both worlds' ratings, real successes under the bars.
    ``labels``: four names for the runs, in the order of the arguments."""
    import matplotlib.pyplot as plt

    runs = [state_m, loop_last_m, delta_m, ens_m]
    labels = list(labels) if labels is not None else [
        "single model\n(loop round 0)", f"loop, after\nround {loop_last_m.get('round', '?')}",
        "delta model", "ensemble\n+ penalty"]
    if len(labels) != len(runs):
        raise ValueError(f"need {len(runs)} labels, got {len(labels)}")
    colors = ["tab:gray", "tab:green", "tab:blue", "tab:purple"]
    x = np.arange(len(runs), dtype=float)
    fig, axes = plt.subplots(1, 4, figsize=(21, 5.4))
    for ax, span in zip(axes[:2], SPAN_KEYS):
        g = [m[key(GAP, span=span)] for m in runs]
        se = [m[key(GAP, se=True, span=span)] for m in runs]
        ax.bar(x, g, 0.6, yerr=se, capsize=5, color=colors, alpha=0.85)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_xlabel("run")
        ax.set_ylabel("imagination gap (imagined minus real reward\nper step; bars: ± 1 standard error)")
        ax.set_title(f"The gap over {_steps(state_m, span)}")
    ax = axes[2]
    for dx, part, color in ((-0.18, "position", "tab:blue"), (0.18, "yaw", "tab:red")):
        g = [m[key(GAP, part=part, span="eval_horizon")] for m in runs]
        se = [m[key(GAP, se=True, part=part, span="eval_horizon")] for m in runs]
        ax.bar(x + dx, g, 0.36, yerr=se, capsize=4, color=color, alpha=0.8,
               label=f"{part} half" + (" (the block's angle)" if part == "yaw" else " (its distance)"))
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_xlabel("run")
    ax.set_ylabel("part of the gap (reward per step;\nbars: ± 1 standard error)")
    ax.set_title(f"The gap's two halves ({_steps(state_m, 'eval_horizon')})")
    _legend_below(ax, y=-0.3)
    ax = axes[3]
    for dx, world, name in ((-0.18, "dream", _dream_key("eval_horizon")), (0.18, "real", _real_key("eval_horizon"))):
        ax.bar(x + dx, [m[name] for m in runs], 0.36, color=WORLD_COLORS[world], alpha=0.85,
               label="in the dream" if world == "dream" else "in reality")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(x, [f"{lab}\n{successes(m)}/{m['eval_episodes']} solved" for lab, m in zip(labels, runs)],
                  fontsize=8)
    ax.set_xlabel("run (real successes under each name)")
    ax.set_ylabel("mean reward per step\n(0 = block on target)")
    ax.set_title(f"Both worlds' ratings ({_steps(state_m, 'eval_horizon')})")
    _legend_below(ax, y=-0.36)
    fig.suptitle("Three fixes against the chapter's single state model, on the same evaluation starts")
    fig.tight_layout()
    return fig


# --- self-checks ----------------------------------------------------------------------------------
SELF_CHECKS = self_checks("06_closing_the_gap")  # the words: pusht/nb/text/06_closing_the_gap.md
