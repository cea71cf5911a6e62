"""Notebook 05's claims about the learner's sweep: registered predicates (``pusht.nb.claims``) on
the runs' numbers, and :func:`judge_change` / :func:`judge_sign`, which read a quantity through
its four registered claims (each quantity's claims are built by one factory).

Changing a claim's name, sentence, control or keyword inputs invalidates ``benchmarks/claims.json``:
run ``make claims`` again (``tests/test_claims.py`` re-evaluates every recorded claim).
"""

from __future__ import annotations

import numpy as np

from .claims import claim
from .stats import LEVEL, MIN_REWARD_EFFECT, Test, clear_of_threshold, paired, sign_test


# --- claims -------------------------------------------------------------------------------------
# Each quantity compared between two horizons gets three registered claims: it rose, it fell (both
# beyond k standard errors of a paired t-test AND by at least the minimum effect), and the change
# was detected (beyond k standard errors, whatever its size). Each quantity judged against zero
# gets the same three with a one-sample t-test.
def _plain_list(values) -> list[float]:
    return [float(v) for v in np.asarray(list(values), dtype=float).ravel()]


def _register_change(q: str, what: str, control: str | None = "the shortest horizon") -> dict:
    def rose(*, short, long, min_effect):
        return paired(short, long, min_effect=min_effect).outcome == "up"

    def fell(*, short, long, min_effect):
        return paired(short, long, min_effect=min_effect).outcome == "down"

    def detected(*, short, long):
        return paired(short, long).detected

    def size_matters(*, short, long, min_effect):
        return paired(short, long, min_effect=min_effect).matters

    for f, tail in ((rose, "rose"), (fell, "fell"), (detected, "change_detected"),
                    (size_matters, "change_size_matters")):
        f.__name__ = f.__qualname__ = f"{q}_{tail}"
    ways = ("beyond k standard errors of a paired t-test over actor seeds and by at least the minimum "
            "effect that matters")
    return {"up": claim(f"05.{q}_rose", f"{what} rose from the shorter to the longer horizon, {ways}",
                        control=control)(rose),
            "down": claim(f"05.{q}_fell", f"{what} fell from the shorter to the longer horizon, {ways}",
                          control=control)(fell),
            "detected": claim(f"05.{q}_change_detected", f"{what} changed between the two horizons beyond k "
                              "standard errors of a paired t-test over actor seeds (whatever its size)")(detected),
            "size": claim(f"05.{q}_change_size_matters", f"the point change of {what} between the two horizons "
                          "is at least the minimum effect that matters (whatever the noise)")(size_matters)}


def _register_sign(q: str, what: str, control: str | None = None) -> dict:
    def positive(*, values, min_effect):
        return sign_test(values, min_effect=min_effect).outcome == "up"

    def negative(*, values, min_effect):
        return sign_test(values, min_effect=min_effect).outcome == "down"

    def detected(*, values):
        return sign_test(values).detected

    def size_matters(*, values, min_effect):
        return sign_test(values, min_effect=min_effect).matters

    for f, tail in ((positive, "positive"), (negative, "negative"), (detected, "nonzero_detected"),
                    (size_matters, "size_matters")):
        f.__name__ = f.__qualname__ = f"{q}_{tail}"
    ways = "beyond k standard errors of a one-sample t-test over actor seeds and by at least the minimum effect"
    return {"up": claim(f"05.{q}_positive", f"{what} is above zero, {ways}", control=control)(positive),
            "down": claim(f"05.{q}_negative", f"{what} is below zero, {ways}", control=control)(negative),
            "detected": claim(f"05.{q}_nonzero_detected", f"{what} differs from zero beyond k standard "
                              "errors of a one-sample t-test (whatever its size)")(detected),
            "size": claim(f"05.{q}_size_matters", f"the mean of {what} is at least the minimum effect that "
                          "matters in size (whatever the noise)")(size_matters)}


CHANGES = {
    "gap": _register_change("gap", "the gap over the whole evaluation (shortest vs longest horizon)"),
    "gap_step": _register_change("gap_step", "the gap over the whole evaluation, between neighbouring horizons"),
    "dream_rating": _register_change("dream_rating", "the dream's rating of the trained policy (reward per step)"),
    "real_rating": _register_change("real_rating", "reality's rating of the trained policy (reward per step)"),
    "training": _register_change("training", "the gap's training term over the whole evaluation"),
    "dream_training_effect": _register_change(
        "dream_training_effect", "the dream's rating, from the untrained to the trained actor of the shortest "
        "horizon (reward per step)"),
}


SIGNS = {
    "gap": _register_sign("gap", "the gap over the whole evaluation at one horizon"),
    "training": _register_sign("training", "the training term over the whole evaluation at one horizon",
                               "the untrained actor"),
    "training_own_span": _register_sign(
        "training_own_span", "the training term over the run's own first H steps (its training span)",
        "the untrained actor"),
    "own_gap": _register_sign("own_gap", "the gap over the run's own first H steps at one horizon"),
    "yaw_minus_position": _register_sign(
        "yaw_minus_position", "the size of the gap's yaw half minus the size of its position half, at one horizon"),
}


KINDS = ("up", "down", "small", "unresolved", "same")


def _kind(up: bool, down: bool, detected: bool, size: bool) -> str:
    """up / down (beyond the noise and the minimum effect), small (beyond the noise, below the
    minimum effect), unresolved (not beyond the noise, though at least the minimum effect in size:
    the seeds cannot tell it from luck) or same (neither beyond the noise nor the minimum effect)."""
    return "up" if up else "down" if down else "small" if detected else "unresolved" if size else "same"


def judge_change(q: str, short, long, min_effect: float = MIN_REWARD_EFFECT) -> tuple[Test, str]:
    """The paired t-test of ``long`` against ``short`` (per-seed values, seed i on both sides), through the claims of
    quantity ``q``: kind "up" or "down" (beyond k SE and at least ``min_effect``), "small" (beyond
    k SE but smaller than ``min_effect``), "unresolved" (not beyond k SE, though the point change is
    at least ``min_effect``) or "same" (not beyond k SE and smaller than ``min_effect``)."""
    c = CHANGES[q]
    s, lg = _plain_list(short), _plain_list(long)
    up = c["up"](short=s, long=lg, min_effect=min_effect)
    down = c["down"](short=s, long=lg, min_effect=min_effect)
    det = c["detected"](short=s, long=lg)
    size = c["size"](short=s, long=lg, min_effect=min_effect)
    kind = _kind(up, down, det, size)
    return paired(s, lg, min_effect=min_effect), kind


def judge_sign(q: str, values, min_effect: float = MIN_REWARD_EFFECT) -> tuple[Test, str]:
    """The one-sample t-test of ``values`` against zero, through the claims of quantity ``q``:
    kind "up", "down", "small", "unresolved" or "same" as in :func:`judge_change`."""
    c = SIGNS[q]
    v = _plain_list(values)
    up = c["up"](values=v, min_effect=min_effect)
    down = c["down"](values=v, min_effect=min_effect)
    det = c["detected"](values=v)
    size = c["size"](values=v, min_effect=min_effect)
    kind = _kind(up, down, det, size)
    return sign_test(v, min_effect=min_effect), kind


@claim("05.drift_same_every_run", "the drift term is the same number in every run of the sweep")
def drift_same_every_run(*, values, tol=1e-9):
    v = np.asarray(values, dtype=float)
    return bool(v.size > 0 and np.ptp(v) < tol)


@claim("05.motion_same_every_horizon", "for each actor seed, the untrained actor's motion term is the same at "
       "every horizon")
def motion_same_every_horizon(*, rows, tol=1e-9):
    return same_rows(rows, tol)


def same_rows(rows, tol: float = 1e-9) -> bool:
    r = [np.asarray(x, dtype=float) for x in rows]
    return all(x.shape == r[0].shape and np.allclose(x, r[0], rtol=0, atol=tol) for x in r)


@claim("05.mech_short_horizon_penalised", "the training term at the shortest horizon is below zero and it rose "
       "with the horizon (each beyond k SE and the minimum effect): the dream punishes what training on short "
       "dreams did, more than reality does", control="the untrained actor")
def mech_short_horizon_penalised(*, short, long, min_effect):
    return (sign_test(short, min_effect=min_effect).outcome == "down"
            and paired(short, long, min_effect=min_effect).outcome == "up")


@claim("05.mech_long_horizon_exploits", "the training term at the longest horizon is above zero and it rose with "
       "the horizon (each beyond k SE and the minimum effect): training on long dreams made the dream rosier than "
       "reality", control="the untrained actor")
def mech_long_horizon_exploits(*, short, long, min_effect):
    return (sign_test(long, min_effect=min_effect).outcome == "up"
            and paired(short, long, min_effect=min_effect).outcome == "up")


@claim("05.mech_short_horizon_exploits", "the training term at the shortest horizon is above zero and it fell "
       "with the horizon (each beyond k SE and the minimum effect)", control="the untrained actor")
def mech_short_horizon_exploits(*, short, long, min_effect):
    return (sign_test(short, min_effect=min_effect).outcome == "up"
            and paired(short, long, min_effect=min_effect).outcome == "down")


@claim("05.mech_long_horizon_penalised", "the training term at the longest horizon is below zero and it fell with "
       "the horizon (each beyond k SE and the minimum effect)", control="the untrained actor")
def mech_long_horizon_penalised(*, short, long, min_effect):
    return (sign_test(long, min_effect=min_effect).outcome == "down"
            and paired(short, long, min_effect=min_effect).outcome == "down")


@claim("05.penalty_beyond_training_span", "at the shortest horizon the training term is below zero over the whole "
       "evaluation (beyond k SE and the minimum effect) but not over the run's own first H steps", control="the untrained actor")
def penalty_beyond_training_span(*, whole, own, min_effect):
    return (sign_test(whole, min_effect=min_effect).outcome == "down"
            and sign_test(own, min_effect=min_effect).outcome != "down")


@claim("05.dream_block_ends_further", "the dreamed block ends further from the target than it spawned, by at least "
       "the success tolerance and beyond k SE (one-sample t-test over actor seeds)")
def dream_block_ends_further(*, final, spawn, min_effect):
    return sign_test(np.asarray(final, dtype=float) - spawn, min_effect=min_effect).outcome == "up"


@claim("05.real_block_ends_further", "the real block ends further from the target than it spawned, by at least the "
       "success tolerance and beyond k SE (one-sample t-test over actor seeds)")
def real_block_ends_further(*, final, spawn, min_effect):
    return sign_test(np.asarray(final, dtype=float) - spawn, min_effect=min_effect).outcome == "up"


@claim("05.dream_block_ends_nearer", "the dreamed block ends nearer the target than it spawned, by at least the "
       "success tolerance and beyond k SE (one-sample t-test over actor seeds)")
def dream_block_ends_nearer(*, final, spawn, min_effect):
    return sign_test(np.asarray(final, dtype=float) - spawn, min_effect=min_effect).outcome == "down"


@claim("05.real_block_ends_nearer", "the real block ends nearer the target than it spawned, by at least the "
       "success tolerance and beyond k SE (one-sample t-test over actor seeds)")
def real_block_ends_nearer(*, final, spawn, min_effect):
    return sign_test(np.asarray(final, dtype=float) - spawn, min_effect=min_effect).outcome == "down"


@claim("05.dream_pushing_beats_zero", "the trained actor's dreamed block ends nearer the target than the block of "
       "the zero-action dream (a pusher that never moves, same starts, same model), by at least the success "
       "tolerance and beyond k SE (one-sample t-test over actor seeds)", control="zero actions")
def dream_pushing_beats_zero(*, final, zero, min_effect):
    return sign_test(np.asarray(final, dtype=float) - zero, min_effect=min_effect).outcome == "down"


@claim("05.ex2_letter_decided", "Exercise 2's letter is decided beyond the noise: the gap's change from the shortest "
       "to the longest horizon is not 'unresolved', and its |t| is more than 10% away from k (paired t-test over "
       "actor seeds)", control="the shortest horizon")
def ex2_letter_decided(*, short, long, min_effect):
    t = paired(short, long, min_effect=min_effect)
    return not (t.matters and not t.detected) and clear_of_threshold(t.ratio, t.k)


@claim("05.dream_turns_untouched_block", "with zero actions the dreamed T ends nearer the target angle than the "
       "real T, by more than the yaw success tolerance", control="reality")
def dream_turns_untouched_block(*, dream_deg, real_deg, tol_deg):
    return real_deg - dream_deg > tol_deg


@claim("05.dream_turns_untouched_block_away", "with zero actions the dreamed T ends further from the target angle "
       "than the real T, by more than the yaw success tolerance", control="reality")
def dream_turns_untouched_block_away(*, dream_deg, real_deg, tol_deg):
    return dream_deg - real_deg > tol_deg


@claim("05.seed_spread_matters", "at some horizon the gap differs between actor seeds by at least the minimum "
       "effect that matters")
def seed_spread_matters(*, largest_range, min_effect):
    return largest_range >= min_effect


# --- statistics (pusht/stats.py) -----------------------------------------------------------
def gap_change(short, long, level: float = LEVEL, min_effect: float = MIN_REWARD_EFFECT) -> Test:
    """Did a quantity change from one horizon to another, beyond the spread across actor seeds and
    by at least the minimum effect that matters?

    ``short`` and ``long``: its value for each actor seed at the two horizons, in the same seed order; the
    paired t-test (:func:`pusht.stats.paired`). The outcome is "up" (``long`` is larger), "down" or "same":
    not beyond k standard errors, or smaller than ``min_effect`` (``.detected`` then tells the two
    apart).
    """
    return paired(short, long, level, min_effect)
