"""Taking the imagination gap apart: what the model does on its own and what the actor adds, each
with its standard error over the evaluation's starts.

Everything here reads rollouts the evaluation already made (``evaluate.two_world_eval``, which
calls it); nothing trains and nothing runs a model. The numbers go into ``metrics.json``.

The split of the gap (imagined minus real reward per step, over a span of steps):

    gap = drift + motion + training

* ``drift``    = zero-action dream - zero-action reality: the model alone, nobody pushes;
* ``motion``   = what the untrained actor's actions change in the dream beyond what they change
                 in reality (relative to zero actions);
* ``training`` = what training changes in the dream beyond what it changes in reality (relative
                 to the untrained actor): the actor exploiting the model.

The three terms sum to the gap exactly (it is an identity), so each is a share of it. Measured at
the actor's own training horizon (``imag_horizon`` steps, what its gradient saw) and over the whole
evaluation (``eval_horizon`` steps, far past the model's training clips).
"""

from __future__ import annotations

import numpy as np

from .metric_keys import ERROR_SIZE, EXPERT_GAP, EXPERT_SIGNAL, GAP, GAP_TERM, RETURN, YAW_MINUS_POSITION, \
    ZERO_BLOCK_MOVED, key

POLICIES = ("zero", "untrained", "trained")
PARTS = (None, "position", "yaw")      # the whole reward, and each of its two terms


def _rewards(rollout, part: str | None) -> np.ndarray:
    return rollout.rewards if part is None else rollout.reward_part(part)


def span_return(rollout, steps: int | None, part: str | None = None) -> float:
    """Reward per step over the first ``steps`` steps (all of them for None): each start's mean over
    the steps it lasted, averaged over the starts, as the headline's ``imagined_return_per_step`` and
    ``real_return_per_step`` are (one number per quantity: an episode that ends early, at a success,
    would weigh differently if every step of every start were pooled). With ``part`` ("position" or
    "yaw"), that term of the reward alone; the two terms add up to the whole start by start."""
    return float(np.nanmean(per_start(rollout, steps, part)))


def per_start(rollout, steps, part=None):
    """(B,) each start's reward per step over its first ``steps`` steps (those it lasted)."""
    r = _rewards(rollout, part)
    r = r if steps is None else r[:steps]
    return np.nanmean(r, axis=0)                                           # (B,)


def se(x: np.ndarray) -> float:
    """The standard error of the mean of ``x`` (NaN for fewer than two values)."""
    return float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")


def gap_split(rollouts: dict, steps: int | None, part: str | None = None, span: str | None = None) -> dict:
    """Per-step return of each policy in each world over the first ``steps`` steps, and the gap's
    three terms (see the module doc), under their metric keys (``metric_keys.RETURN``, ``GAP``,
    ``GAP_TERM``) for the span named ``span``. ``rollouts`` maps ``dream_<policy>`` and
    ``real_<policy>`` (``policy`` in POLICIES) to ``Rollout``. With ``part`` ("position" or "yaw")
    the same split of that term of the reward alone: the reward is the sum of its two terms, so every
    quantity here is the sum of its position and yaw versions."""
    at = {"part": part, "span": span}
    R = {(p, w): span_return(rollouts[f"{w}_{p}"], steps, part) for p in POLICIES for w in ("dream", "real")}
    out = {key(RETURN, policy=p, world=w, **at): v for (p, w), v in R.items()}
    out[key(GAP, **at)] = R["trained", "dream"] - R["trained", "real"]
    out[key(GAP_TERM, term="drift", **at)] = R["zero", "dream"] - R["zero", "real"]
    out[key(GAP_TERM, term="motion", **at)] = ((R["untrained", "dream"] - R["zero", "dream"])
                                               - (R["untrained", "real"] - R["zero", "real"]))
    out[key(GAP_TERM, term="training", **at)] = ((R["trained", "dream"] - R["untrained", "dream"])
                                                 - (R["trained", "real"] - R["untrained", "real"]))
    # The noise of each term: the standard error of its mean over the starts (every term is a mean
    # of per-start differences, all on the same starts). Whether a term is told apart from zero,
    # and whether it is large enough to matter, the notebooks decide (pusht/stats.py).
    P = {(p, w): per_start(rollouts[f"{w}_{p}"], steps, part) for p in POLICIES for w in ("dream", "real")}
    by_start = {"drift": P["zero", "dream"] - P["zero", "real"],
                "motion": (P["untrained", "dream"] - P["zero", "dream"]) - (P["untrained", "real"] - P["zero", "real"]),
                "training": (P["trained", "dream"] - P["untrained", "dream"])
                - (P["trained", "real"] - P["untrained", "real"])}
    gap = P["trained", "dream"] - P["trained", "real"]
    out[key(GAP, se=True, **at)] = se(gap)
    for term, x in by_start.items():
        out[key(GAP_TERM, term=term, se=True, **at)] = se(x)
    for (pol, w), x in P.items():                   # each world's rating of each policy, with its own noise
        out[key(RETURN, policy=pol, world=w, se=True, **at)] = se(x)
    # Exercise 1's question, "is the drift at least half of the gap?", as one quantity with its own
    # standard error over the starts (the drift is part of the gap, so the two are not independent)
    out[key(GAP_TERM, term="drift_minus_half_gap", **at)] = float(np.nanmean(by_start["drift"] - 0.5 * gap))
    out[key(GAP_TERM, term="drift_minus_half_gap", se=True, **at)] = se(by_start["drift"] - 0.5 * gap)
    return out


def size_split(rollouts: dict, steps: int | None, span: str | None = None) -> dict:
    """The SIZE of the gap's and of the drift's error over the first ``steps`` steps, and its exact
    standard error: a gap near zero can hide a large error when its position and yaw halves have
    opposite signs, so a change of the error is judged on |position half| + |yaw half|.

    For each error (the gap, ``imagination_gap``, and the drift, ``gap_drift``): its size
    (``metric_keys.ERROR_SIZE``) = |mean position half| + |mean yaw half|; its standard error is that
    of the per-start values s_p * position_i + s_y * yaw_i (s the sign of each half's mean), which
    average to the size exactly. When the halves share a sign the size is |gap| and its standard
    error is the gap's: one quantity, one test. ``YAW_MINUS_POSITION`` = |yaw half| - |position half|,
    with its exact standard error (per start s_y * yaw_i - s_p * position_i): which half is larger.
    """
    pos = {(p, w): per_start(rollouts[f"{w}_{p}"], steps, "position") for p in POLICIES for w in ("dream", "real")}
    yaw = {(p, w): per_start(rollouts[f"{w}_{p}"], steps, "yaw") for p in POLICIES for w in ("dream", "real")}
    out = {}
    for error, pol in (("imagination_gap", "trained"), ("gap_drift", "zero")):
        xp = pos[pol, "dream"] - pos[pol, "real"]
        xy = yaw[pol, "dream"] - yaw[pol, "real"]
        ok = ~(np.isnan(xp) | np.isnan(xy))
        xp, xy = xp[ok], xy[ok]
        sp, sy = np.sign(xp.mean()) or 1.0, np.sign(xy.mean()) or 1.0
        size, diff = sp * xp + sy * xy, sy * xy - sp * xp
        out[key(ERROR_SIZE, error=error, span=span)] = float(size.mean())
        out[key(ERROR_SIZE, error=error, se=True, span=span)] = se(size)
        out[key(YAW_MINUS_POSITION, error=error, span=span)] = float(diff.mean())
        out[key(YAW_MINUS_POSITION, error=error, se=True, span=span)] = se(diff)
    return out


def expert_signal(rollouts: dict, steps: int | None, span: str | None = None) -> dict:
    """Can the dream recognise success? The scripted expert solves the real task; its actions are
    replayed in the dream from the same starts (``dream_expert``). Over the first ``steps`` steps, under
    the keys of ``pusht.metric_keys`` for the span ``span``:

    * ``expert_{dream,real}_return_per_step`` (``RETURN``): what each world pays the expert;
    * ``expert_signal_{dream,real}`` (``EXPERT_SIGNAL``): the expert minus zero actions in each world,
      with standard errors over the starts (``..._se``). A dream whose signal is clearly positive rewards the
      pushes that solve the task over standing still: a learnable signal existed. A signal near
      zero, or negative, means the dream cannot tell success from doing nothing;
    * ``expert_signal_yaw_dream``/``_real`` and ``..._position_...``: the same for each term;
    * ``expert_gap`` (± ``expert_gap_se``, ``EXPERT_GAP``): the dream's pay for the expert's pushes minus reality's, per
      start: the expert's own imagination gap, which needs no zero-action control;
    * ``zero_dream_block_moved`` (``ZERO_BLOCK_MOVED``): how far the zero-action dream moves a block nobody touches (m, mean
      over the starts of its largest displacement in the span). The expert signal compares the expert
      with standing still; where the dream moves the untouched block beyond the success tolerance,
      "standing still" is not standing still in the dream, and the control is invalid.
    """
    out = {}
    # the expert's own gap: what the dream pays its pushes minus what reality pays them (no zero-action
    # control in it), and whether the zero-action control is valid: how far the dream moves a block
    # nobody touches (mean over starts of the largest displacement within the span, m; a real untouched
    # block does not move)
    x = per_start(rollouts["dream_expert"], steps) - per_start(rollouts["real_expert"], steps)
    x = x[~np.isnan(x)]
    out[key(EXPERT_GAP, span=span)], out[key(EXPERT_GAP, se=True, span=span)] = float(np.mean(x)), se(x)
    obs = np.asarray(rollouts["dream_zero"].obs)
    obs = obs if steps is None else obs[:steps + 1]
    out[key(ZERO_BLOCK_MOVED, span=span)] = float(np.linalg.norm(obs[:, :, 2:4] - obs[:1, :, 2:4], axis=-1).max(0).mean())
    for w in ("dream", "real"):
        out[key(RETURN, policy="expert", world=w, span=span)] = span_return(rollouts[f"{w}_expert"], steps)
        for part in PARTS:
            x = per_start(rollouts[f"{w}_expert"], steps, part) - per_start(rollouts[f"{w}_zero"], steps, part)
            out[key(EXPERT_SIGNAL, part=part, world=w, span=span)] = float(np.nanmean(x))
            out[key(EXPERT_SIGNAL, part=part, world=w, se=True, span=span)] = se(x[~np.isnan(x)])
    return out
