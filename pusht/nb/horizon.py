"""Notebook 05's figures and self-checks: sweeping the imagination horizon.

Exercise 2 trains several actors at each horizon on ONE frozen world model: ``actor_seed`` 0, 1,
2, ... differ only in the actor-critic's initial weights and in the random dreams it trains on.
So the spread of their values at one horizon is what the horizon's effect has to beat. Every
verdict below asks two things (:mod:`pusht.stats`) and says which test it used:

* **beyond the noise**: a t-test on the per-seed values (paired by actor seed, for two horizons:
  every horizon trains the same actor seeds, and what a seed adds to both cancels in its difference;
  a one-sample t-test, for "differs from zero"): the difference must exceed ``k`` standard errors, ``k`` the
  two-sided 95% point of Student's t at the test's degrees of freedom (4.30 at two degrees of
  freedom, which is what three seeds give a one-sample test; the sweep uses four);
* **large enough to matter**: at least :data:`MIN_REWARD_EFFECT` reward per step (the reward of
  holding the block the 2 cm success tolerance nearer the target on every step); for a block
  distance, at least ``SUCCESS_POS`` (2 cm), the environment's own success tolerance.

A difference that passes the first and fails the second is reported as "detected, but smaller
than the minimum effect that matters", never as a change. One that fails the first is "not told
apart from no change by the spread across actor seeds", and when its point value is at least the
minimum effect that matters it says so: the sweep could not resolve it, which is not evidence that
nothing changed.

The standard errors are over actor seeds only: every run shares one world model (of ``SEED``) and
one fixed set of evaluation starts, so the error bars say nothing about another world model or
other starts.

Every sentence that reads the run is decided by a registered claim (``05.*``,
:mod:`pusht.nb.claims`), evaluated on the numbers it is given, with its true alternative printed
when it fails.

The runs come in as ``{(horizon, actor_seed): metrics}`` (``RunResult.metrics``); the helpers
regroup them as ``{horizon: [value per actor seed]}``.

The notebook imports everything from here. The claims live in ``horizon_claims``, Exercise 2 in
``horizon_exercise``, the sentences in ``horizon_words``.
"""

from __future__ import annotations

import numpy as np

from ..palette import WORLD
from . import figure
from .prose import self_checks
from .horizon_words import DT
from .stats import sign_test

# Re-exported: notebook 05 and learners' released copies import these from here.
from ..env import SUCCESS_ANG, SUCCESS_POS  # noqa: F401
from .horizon_claims import (  # noqa: F401
    CHANGES, KINDS, SIGNS, dream_block_ends_further, dream_block_ends_nearer, dream_pushing_beats_zero,
    dream_turns_untouched_block, dream_turns_untouched_block_away, drift_same_every_run, ex2_letter_decided,
    gap_change, judge_change, judge_sign, mech_long_horizon_exploits, mech_long_horizon_penalised,
    mech_short_horizon_exploits, mech_short_horizon_penalised, motion_same_every_horizon,
    penalty_beyond_training_span, real_block_ends_further, real_block_ends_nearer, same_rows,
    seed_spread_matters)
from .horizon_exercise import (  # noqa: F401
    EX2_ACTOR_SEEDS, EX2_HORIZONS, EX2_OPTIONS, EX2_RULE, VERDICT_LETTER, by_horizon, ex2_reconciliation,
    ex2_verdict, mechanism_text, reconcile_text, worlds_sentence)
from .horizon_words import (  # noqa: F401
    CHANGE_WORDS, ERROR_BAR_SCOPE, MIN_DIST_EFFECT, SIGN_WORDS, SUCCESS_ANG_DEG, block_sentence,
    change_phrase, closest_approach, conclusion, halves_sentence, horizon_line, interval_note,
    own_horizon_sentence, rule_text, same_at_every_horizon, sweep_table, takeaway, terms_sentence)
from .stats import LEVEL, MIN_REWARD_EFFECT, Test, clear_of_threshold, paired, t_quantile, welch  # noqa: F401


HORIZON_COLORS = ["tab:cyan", "tab:blue", "tab:purple", "tab:red", "tab:brown"]


WORLD_COLORS = WORLD     # one colour per world, the site's too (pusht.palette)


TERMS = {"drift": "drift (zero actions)", "motion": "untrained actor's motion",
         "training": "training"}


# --- figures ------------------------------------------------------------------------------------
def _jitter(n: int, width: float, rng) -> np.ndarray:
    return rng.uniform(-width, width, n) if n > 1 else np.zeros(n)


def _points_and_mean(ax, x: float, values, color, label=None, mean_label=None, width=0.6, rng=None):
    """Each actor seed as a dot, the mean as a bar of ±k standard errors (k of :func:`sign_test`).
    The dots sit left of ``x`` and the bar right of it, so that seeds that agree closely do not hide
    under the bar."""
    v = np.asarray(values, dtype=float)
    rng = rng if rng is not None else np.random.default_rng(0)
    shift = width * 0.22 if v.size > 1 else 0.0
    ax.scatter(x - shift + _jitter(v.size, width * 0.15, rng), v, s=28, color=color, alpha=0.75, zorder=3,
               edgecolors="k", linewidths=0.4, label=label)
    if v.size > 1:
        t = sign_test(v)
        ax.errorbar(x + shift, t.diff, yerr=t.k * t.se, fmt="_", ms=12, mew=2.5, color="k", capsize=4, lw=1.5,
                    zorder=4, label=mean_label)
    else:
        ax.plot([x - width / 2, x + width / 2], [v.mean()] * 2, color="k", lw=2.5, label=mean_label)


@figure
def fig_gap_vs_horizon(gaps: dict, imagined: dict, real: dict, eval_horizon: int):
    """Left: the gap at each horizon, one dot per actor seed, the mean with its 95% interval.
    Right: the two ratings it is the difference of, the dream's and reality's, the same way.
    All ``{horizon: [value per actor seed]}``."""
    import matplotlib.pyplot as plt

    hs = sorted(gaps)
    x = np.arange(len(hs), dtype=float)
    rng = np.random.default_rng(0)                          # horizontal jitter for the dots only
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.4))
    ax = axes[0]
    for i, h in enumerate(hs):
        _points_and_mean(ax, x[i], gaps[h], HORIZON_COLORS[i % len(HORIZON_COLORS)],
                         mean_label="mean, 95% interval over seeds" if i == 0 else None, rng=rng)
    ax.scatter([], [], s=28, color="lightgray", edgecolors="k", linewidths=0.4,
               label="one actor seed (colour: horizon)")
    ax.axhline(0, color="gray", lw=1, ls="--")
    ax.text(x[-1] + 0.45, 0, "dream = reality", va="bottom", ha="right", fontsize=8, color="gray")
    ax.set_ylabel("imagination gap\n(imagined minus real reward per step)")
    ax.set_title(f"The gap over the whole evaluation ({eval_horizon} steps)")
    ax.legend(fontsize=8, loc="best")
    ax = axes[1]
    for dx, (world, vals) in ((-0.15, ("dream", imagined)), (0.15, ("real", real))):
        for i, h in enumerate(hs):
            _points_and_mean(ax, x[i] + dx, vals[h], WORLD_COLORS[world], width=0.25, rng=rng,
                             label=("in the dream" if world == "dream" else "in reality") if i == 0 else None)
    ax.set_ylabel("mean reward per step\n(0 = block on target)")
    ax.set_title("The two ratings the gap is the difference of")
    ax.legend(fontsize=8, loc="best")
    for ax in axes:
        ax.set_xticks(x, [f"{h} steps\n({h * DT:.1f} s)" for h in hs])
        ax.set_xlim(-0.6, len(hs) - 0.4)
        ax.set_xlabel("imagination horizon during training")
    fig.suptitle("One frozen world model, several actors per horizon: dots are actor seeds")
    fig.tight_layout()
    return fig


@figure
def fig_gap_terms(terms: dict, gaps: dict):
    """The gap and its three terms (``pusht.analysis``) over the whole evaluation, per horizon:
    one dot per actor seed, the mean with its 95% interval. ``terms``: ``{term: {h: [...]}}``."""
    import matplotlib.pyplot as plt

    hs = sorted(gaps)
    series = {"gap": gaps, **terms}
    labels = {"gap": "the gap", **TERMS}
    fig, ax = plt.subplots(figsize=(10, 4.4))
    width = 0.8 / len(series)
    rng = np.random.default_rng(0)
    for j, (name, vals) in enumerate(series.items()):
        color = ["k", "tab:green", "tab:gray", "tab:red"][j % 4]
        for i, h in enumerate(hs):
            _points_and_mean(ax, i - 0.4 + width * (j + 0.5), vals[h], color, width=width, rng=rng,
                             label=labels[name] if i == 0 else None)
    ax.axhline(0, color="gray", lw=1, ls="--")
    ax.set_xticks(np.arange(len(hs)), [f"{h} steps" for h in hs])
    ax.set_xlabel("imagination horizon during training")
    ax.set_ylabel("reward per step (dream minus reality)")
    ax.set_title("The gap = drift + motion + training, whole evaluation (black bars: mean, 95% interval)")
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return fig


def mean_block_distance(rollout) -> np.ndarray:
    """(T+1,) mean block-to-target distance (m) over the starts of one ``Rollout``, step by step."""
    return np.linalg.norm(np.asarray(rollout.obs)[:, :, 2:4], axis=-1).mean(1)


@figure
def fig_block_over_time(curves: dict, dt: float = DT, zero: dict | None = None):
    """Mean block-to-target distance over the evaluation, per horizon, dream and reality.

    ``curves``: ``{horizon: {"dream": (A, T+1), "real": (A, T+1)}}`` with one row per actor seed
    (:func:`mean_block_distance`); thin lines are seeds, thick lines their mean. A dotted line
    marks each horizon's training span. ``zero``: ``{"dream": (T+1,), "real": (T+1,)}``, the same
    curves for a pusher that never moves (the same in every run): the control that says what the
    dream does to a block nobody pushes; drawn in black.
    """
    import matplotlib.pyplot as plt

    hs = sorted(curves)
    fig, ax = plt.subplots(figsize=(10, 4.6))
    for i, h in enumerate(hs):
        color = HORIZON_COLORS[i % len(HORIZON_COLORS)]
        for world, ls in (("dream", "-"), ("real", "--")):
            c = np.asarray(curves[h][world], dtype=float)
            t = np.arange(c.shape[1]) * dt
            for row in c:
                ax.plot(t, row, color=color, ls=ls, lw=0.8, alpha=0.35)
            ax.plot(t, c.mean(0), color=color, ls=ls, lw=2.2,
                    label=f"{'dream' if world == 'dream' else 'reality'}, trained on {h}-step dreams")
        ax.axvline(h * dt, color=color, ls=":", lw=1.2)
    if zero is not None:
        for world, ls in (("dream", "-"), ("real", "--")):
            c = np.asarray(zero[world], dtype=float)
            ax.plot(np.arange(c.size) * dt, c, color="k", ls=ls, lw=2.0,
                    label=f"{'dream' if world == 'dream' else 'reality'}, pusher that never moves (control)")
    ax.plot([], [], color="k", ls=":", lw=1.2, label="end of each training horizon (same colour)")
    ax.set_xlabel("time in the evaluation rollout (s)")
    ax.set_ylabel("mean block-to-target distance (m)")
    ax.set_title("Where the block is, step by step (thin: one actor seed; thick: their mean; black: nobody pushes)")
    ax.set_ylim(0, None)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


# --- self-checks --------------------------------------------------------------------------------
SELF_CHECKS = self_checks("05_horizon")  # the words: pusht/nb/text/05_horizon.md
