"""Notebook 06's figures, conclusions and self-checks: closing the gap with real data, and two fixes.

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
  (:func:`pusht.nb.stats.t_quantile`: 1.98 for the default 100 starts). A difference that large would turn up
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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..env import ARENA_HALF, CONTROL_DT, OBS_NAMES, SUCCESS_POS
from ..selfcheck import Question
from .claims import claim
from .gap import NEAR, expert_control_words, register_expert_control
from .stats import (LEVEL, MIN_REWARD_EFFECT, THIN_MARGIN, Test, beyond, clear_of_threshold, count_rise_p, k_for,
                    margin_words, outcome as _test_outcome)
from . import figure

# 1 mm: the resolution at which the model's errors are read as changed. Physically: a thirtieth of
# the pusher's radius (3 cm), a twentieth of the success radius (2 cm); it is also the package's
# threshold for "the block moved" (``prediction_error_vs_copy_last``'s ``block_moving_fraction``).
# Errors are RMSEs over hundreds of clips, but the metrics keep no spread for them.
ERR_RES = 1e-3
# The arena is 2 * ARENA_HALF = 1 m wide: a dreamed pusher more than that away from the real one
# can no longer be anywhere on the table.
ARENA = 2 * ARENA_HALF
COUNT_P = (1 - LEVEL) / 2          # one-sided bar for a count's rise (see the module doc)
# Two halves of opposite signs "cancel almost exactly" when what is left of them, |position + yaw|,
# is less than a quarter of their sizes added, |position| + |yaw|: three quarters or more of the
# error is hidden from the gap.
CANCEL_SHARE = 0.25
WORLD_COLORS = {"dream": "tab:purple", "real": "tab:orange"}
DATA_COLORS = {"policy": "tab:red", "expert": "tab:blue"}
DATA_LABELS = {"policy": "the policy's data", "expert": "held-out expert data"}
SPAN_KEYS = ("train_horizon", "eval_horizon")


# --- Exercise 3 ---------------------------------------------------------------------------------
EX3_OPTIONS = {
    "a": "The gap **shrinks** and real success **rises**: more real evaluation episodes succeed after the last "
         "round than in round 0.",
    "b": "The gap **shrinks**, but real success **does not rise**: no more real evaluation episodes succeed after "
         "the last round than in round 0 (0% in both, on most seeds).",
    "c": "The gap **does not shrink** (as the note defines it: it stays within the noise, moves by less than "
         "the minimum effect, grows, or changes sign), and real success **does not rise**.",
    "d": "The gap **does not shrink** (as the note defines it), yet real success **rises**.",
}
EX3_NOTE = ("\"Shrinks\" means: the gap's size |imagined minus real reward per step| over the whole "
            "evaluation is smaller after the last round than in round 0 (1) by more than the noise of the two "
            "measurements allows: k standard errors of the change, a t-test on the two rounds' means over the "
            "evaluation starts, k from Student's t at 95% two-sided; and (2) by at least the minimum effect "
            f"that matters, {MIN_REWARD_EFFECT:.2f} reward per step (the reward of holding the block 2 cm, the "
            "success tolerance, nearer the target on every step). A gap that ends on the other side of zero, "
            "beyond the noise at both ends, has changed sign, not shrunk: the dream traded one error for the "
            "opposite one. \"Rises\" means: more real successes after the last round than in round 0, "
            "where one success counts (a success is an event, not an estimate).")



# --- the claims: every run-dependent sentence of notebook 06 is decided by one of these ---------------
def _crossed(first: float, first_se: float, last: float, last_se: float, k: float) -> bool:
    return first * last < 0 and beyond(first, first_se, k) and beyond(last, last_se, k)


def _size_fell(first, first_se, last, last_se, k, min_effect) -> bool:
    drop = abs(first) - abs(last)
    se = math.sqrt(first_se ** 2 + last_se ** 2)
    return beyond(drop, se, k, min_effect, +1) and not _crossed(first, first_se, last, last_se, k)


def _size_rose(first, first_se, last, last_se, k, min_effect) -> bool:
    rise = abs(last) - abs(first)
    se = math.sqrt(first_se ** 2 + last_se ** 2)
    return beyond(rise, se, k, min_effect, +1)


@claim("06.gap_shrank", "the gap's size fell by more than k standard errors of the change and by at least the "
       "minimum effect, without ending on the other side of zero", control="round 0")
def gap_shrank(*, first, first_se, last, last_se, k, min_effect):
    return _size_fell(first, first_se, last, last_se, k, min_effect)


@claim("06.gap_grew", "the gap's size rose by more than k standard errors of the change and by at least the "
       "minimum effect", control="round 0")
def gap_grew(*, first, first_se, last, last_se, k, min_effect):
    return _size_rose(first, first_se, last, last_se, k, min_effect)


@claim("06.gap_crossed_zero", "the gap ended on the other side of zero, beyond k standard errors at both ends", control="round 0")
def gap_crossed_zero(*, first, first_se, last, last_se, k):
    return _crossed(first, first_se, last, last_se, k)


@claim("06.gap_reopened", "after its smallest round the gap's size rose again by the last round, beyond k "
       "standard errors of that change and by at least the minimum effect", control="round 0")
def gap_reopened(*, sizes, ses, k, min_effect):
    i = int(np.argmin(sizes))
    return i < len(sizes) - 1 and _size_rose(sizes[i], ses[i], sizes[-1], ses[-1], k, min_effect)


@claim("06.change_up", "the quantity rose beyond k standard errors and by at least the minimum effect", control="round 0")
def change_up(*, diff, se, k, min_effect, quantity=""):
    return _test_outcome(diff, k * se, min_effect) == "up"


@claim("06.change_down", "the quantity fell beyond k standard errors and by at least the minimum effect", control="round 0")
def change_down(*, diff, se, k, min_effect, quantity=""):
    return _test_outcome(diff, k * se, min_effect) == "down"


@claim("06.dream_rosier", "the dream rated the policy above reality, beyond k standard errors and by at least the "
       "minimum effect", control="reality")
def dream_rosier(*, value, se, k, min_effect):
    return beyond(value, se, k, min_effect, +1)


@claim("06.dream_gloomier", "the dream rated the policy below reality, beyond k standard errors and by at least the "
       "minimum effect", control="reality")
def dream_gloomier(*, value, se, k, min_effect):
    return beyond(value, se, k, min_effect, -1)


@claim("06.yaw_half_clearly_larger", "the yaw half of the gap is larger in size than the position half, by more "
       "than k standard errors of the difference (per start) and by at least the minimum effect")
def yaw_half_clearly_larger(*, position, yaw, diff_se, k, min_effect):
    diff = abs(yaw) - abs(position)
    return beyond(diff, diff_se, k, min_effect, +1)


@claim("06.position_half_clearly_larger", "the position half of the gap is larger in size than the yaw half, by "
       "more than k standard errors of the difference (per start) and by at least the minimum effect")
def position_half_clearly_larger(*, position, yaw, diff_se, k, min_effect):
    diff = abs(position) - abs(yaw)
    return beyond(diff, diff_se, k, min_effect, +1)


@claim("06.halves_cancel", "the two halves have opposite signs and their sum is less than a given share of their "
       "sizes added: they cancel almost exactly")
def halves_cancel(*, position, yaw, share):
    return position * yaw < 0 and abs(position + yaw) < share * (abs(position) + abs(yaw))


@claim("06.error_size_shrank", "the size of the error, |position half| + |yaw half|, fell by more than k standard "
       "errors of the change and by at least the minimum effect (the gap's own test: where the halves share a sign "
       "the size is the gap's size and its standard error the gap's)", control="round 0")
def error_size_shrank(*, first, first_se, last, last_se, k, min_effect):
    return _size_fell(first, first_se, last, last_se, k, min_effect)


@claim("06.error_size_grew", "the size of the error, |position half| + |yaw half|, rose by more than k standard "
       "errors of the change and by at least the minimum effect", control="round 0")
def error_size_grew(*, first, first_se, last, last_se, k, min_effect):
    return _size_rose(first, first_se, last, last_se, k, min_effect)


@claim("06.dream_rewards_expert", "the dream pays the scripted expert's actions more than zero actions, beyond k "
       "standard errors and by at least the minimum effect: it recognises success", control="zero actions")
def dream_rewards_expert(*, signal, se, k, min_effect):
    return beyond(signal, se, k, min_effect, +1)


@claim("06.dream_penalises_expert", "the dream pays the scripted expert's actions less than zero actions, beyond k "
       "standard errors and by at least the minimum effect", control="zero actions")
def dream_penalises_expert(*, signal, se, k, min_effect):
    return beyond(signal, se, k, min_effect, -1)


@claim("06.success_rose", "more real successes after the last round than in round 0", control="round 0")
def success_rose_claim(*, before, after):
    return after > before


@claim("06.untouched_block_on_table", "with zero actions the dreamed block ends, on average, no farther from the "
       "target than the walls are")
def untouched_block_on_table(*, final_dist, arena_half):
    return final_dist <= arena_half


@claim("06.fix_closed_gap", "the fix shrank the gap's size at both horizons (beyond k standard errors and the "
       "minimum effect, not through zero), its drift did not change sign beyond the noise (the opposite error), and "
       "its zero-action dream moves an untouched block no farther than the reference's does (by more than the "
       "success tolerance)", control="the state model")
def fix_closed_gap(*, first_tr, first_tr_se, last_tr, last_tr_se, first_ev, first_ev_se, last_ev, last_ev_se,
                   k, min_effect, drift_first, drift_first_se, drift_last, drift_last_se, moved, ref_moved, tol):
    return (_size_fell(first_tr, first_tr_se, last_tr, last_tr_se, k, min_effect)
            and _size_fell(first_ev, first_ev_se, last_ev, last_ev_se, k, min_effect)
            and not _crossed(drift_first, drift_first_se, drift_last, drift_last_se, k)
            and moved <= ref_moved + tol)


@claim("06.drift_crossed_zero", "the drift (zero-action dream minus zero-action reality) ended on the other side of "
       "zero, beyond k standard errors at both ends: the model's error with nobody pushing turned into the opposite "
       "one", control="round 0")
def drift_crossed_zero(*, first, first_se, last, last_se, k):
    return _crossed(first, first_se, last, last_se, k)


@claim("06.no_real_success", "no run of this notebook (loop, delta model, ensemble) had a single real success")
def no_real_success(*, successes):
    return all(int(x) == 0 for x in successes)


@dataclass(frozen=True)
class Change(Test):
    """One quantity, measured twice: stats' ``Test`` (``diff`` = last minus first, its standard
    error ``se`` = sqrt of the sum of the two squared standard errors, the degrees of freedom, the
    threshold ``k``, the minimum effect that matters and the ``outcome`` "up", "down" or "same")
    plus the two values themselves, ``first`` and ``last``, with their own standard errors."""

    first: float = math.nan
    last: float = math.nan
    first_se: float = math.nan
    last_se: float = math.nan

    @property
    def crossed(self) -> bool:
        """Ended on the other side of zero, beyond k of its own standard errors at both ends."""
        return _crossed(self.first, self.first_se, self.last, self.last_se, self.k)

    @property
    def shrank(self) -> bool:
        """The size |value| fell by more than k standard errors and by at least the minimum effect,
        toward zero, not through it (a crossing beyond the noise is a change of sign)."""
        return _size_fell(self.first, self.first_se, self.last, self.last_se, self.k, self.min_effect)

    @property
    def grew(self) -> bool:
        """The size |value| rose by more than k standard errors and by at least the minimum effect."""
        return _size_rose(self.first, self.first_se, self.last, self.last_se, self.k, self.min_effect)

    def claims(self) -> dict:
        """The registered claims on this change, evaluated (and recorded): shrank, grew, crossed."""
        kw = dict(first=self.first, first_se=self.first_se, last=self.last, last_se=self.last_se, k=self.k)
        return {"shrank": gap_shrank(**kw, min_effect=self.min_effect),
                "grew": gap_grew(**kw, min_effect=self.min_effect),
                "crossed": gap_crossed_zero(**kw)}

    def direction(self) -> str:
        """"up", "down" or "same", decided by the registered claims ``06.change_up``/``_down``."""
        kw = dict(diff=self.diff, se=self.se, k=self.k, min_effect=self.min_effect)
        return "up" if change_up(**kw) else "down" if change_down(**kw) else "same"


def _outcome(diff: float, bar: float) -> str:
    if beyond(diff, bar, 1.0):
        return "up" if diff > 0 else "down"
    return "same"


TEST_NAME = "t-test on two means over the same evaluation starts, their standard errors added in quadrature"


def compare(first: float, first_se: float, last: float, last_se: float, n_starts: int,
            level: float = LEVEL, min_effect: float = 0.0) -> Change:
    """Did a mean over ``n_starts`` evaluation starts change from ``first`` to ``last``, given each
    one's standard error, beyond k standard errors and by at least ``min_effect``? (See the module
    doc for why this is conservative on shared starts.)"""
    se = float(math.sqrt(first_se ** 2 + last_se ** 2))
    k = k_for(int(n_starts), level)
    diff = float(last - first)
    return Change(diff=diff, se=se, df=float(n_starts - 1), k=k,
                  outcome=_test_outcome(diff, k * se, min_effect), min_effect=float(min_effect),
                  test=TEST_NAME, first=float(first), last=float(last), first_se=float(first_se),
                  last_se=float(last_se))


def metric_change(a: dict, b: dict, key: str, se_key: str, level: float = LEVEL,
                  min_effect: float = MIN_REWARD_EFFECT) -> Change:
    """``compare`` of ``a[key]`` (± ``a[se_key]``) and ``b[key]``, on ``b``'s evaluation starts,
    against ``min_effect`` (by default the minimum reward effect: these are rewards per step)."""
    return compare(a[key], a[se_key], b[key], b[se_key], int(b["eval_episodes"]), level, min_effect)


def _gap_keys(span: str, part: str | None = None) -> tuple[str, str]:
    if span not in SPAN_KEYS:
        raise ValueError(f"span must be one of {SPAN_KEYS}, got {span!r}")
    tag = f"_{part}" if part else ""
    return f"imagination_gap{tag}_{span}", f"imagination_gap_se{tag}_{span}"


def gap_change(rounds: list, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap's change from round 0 to the last round (last minus round 0), over ``span``
    ("eval_horizon": the whole evaluation, ``imagination_gap``; or "train_horizon"), against the
    minimum reward effect ``MIN_REWARD_EFFECT``."""
    if len(rounds) < 2:
        raise ValueError(f"need round 0 and at least one later round, got {len(rounds)} round(s)")
    return metric_change(rounds[0], rounds[-1], *_gap_keys(span), level=level)


def fix_change(ref: dict, fix: dict, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap of a fix (``fix``'s metrics) against the reference run ``ref``, over ``span``,
    against the minimum reward effect."""
    return metric_change(ref, fix, *_gap_keys(span), level=level)


def successes(m: dict) -> int:
    """Real successes out of the evaluation starts."""
    return int(round(m["real_success_rate"] * m["eval_episodes"]))


@claim("06.count_change_beyond_chance", "a change of a count is beyond chance: Fisher's exact one-sided p below "
       "the bar")
def count_beyond_chance(*, p, bar):
    return p < bar


def success_rose(rounds: list) -> bool:
    """Exercise 3's "real success rises": more real successes after the last round than in
    round 0 (a success is an event: one counts, see the module doc). Claim ``06.success_rose``."""
    return success_rose_claim(before=successes(rounds[0]), after=successes(rounds[-1]))


@claim("06.ex3_letter_decided", "Exercise 3's letter is decided beyond the noise: the gap's size changed by well under "
       "the minimum effect, or its change's |t| is more than 10% away from k", control="round 0")
def ex3_letter_decided(*, first, first_se, last, last_se, k, min_effect):
    drop = abs(first) - abs(last)
    se = math.hypot(first_se, last_se)
    return abs(drop) < (1 - THIN_MARGIN) * min_effect or clear_of_threshold(abs(drop) / se if se > 0 else math.inf, k)


def ex3_verdict(rounds: list) -> str:
    """Exercise 3's measured outcome, a letter of ``EX3_OPTIONS``: does the gap over the whole
    evaluation shrink (claim ``06.gap_shrank``: beyond k standard errors and the minimum reward
    effect, not through zero; see ``EX3_NOTE``), and does real success rise (``06.success_rose``)?"""
    shrank, rose = gap_change(rounds).claims()["shrank"], success_rose(rounds)
    return {(True, True): "a", (True, False): "b", (False, False): "c", (False, True): "d"}[(shrank, rose)]


def ex3_reconciliation(rounds: list) -> tuple[str, str]:
    """Exercise 3's reconciliation, ``(measured letter, explanation)``, as notebook 06 hands them to
    ``pusht.predict.reconcile``: from the loop's rounds (``loop.run_loop(...).rounds``). One
    function, so that the notebook and ``python -m pusht.exercise ex3`` print the same words."""
    c = gap_change(rounds)
    drop = abs(c.first) - abs(c.last)
    margin = margin_words(abs(drop) / c.se if c.se > 0 else math.inf, c.k)
    decided = ex3_letter_decided(first=c.first, first_se=c.first_se, last=c.last, last_se=c.last_se, k=c.k,
                                 min_effect=c.min_effect)
    return ex3_verdict(rounds), (reconcile_text(rounds).replace("**", "")
                                 + f"\n\nThe letter's margin (the gap's size, round 0 against round {rounds[-1]['round']}): "
                                 f"{margin}." + ("" if decided else " This run does not decide the letter beyond the "
                                                 "noise: more evaluation starts would."))


# --- formatting ---------------------------------------------------------------------------------
def _se(se: float) -> str:
    return f"{se:.3f}" if se >= 0.001 or se == 0 else f"{se:.1e}"


def _pm(v: float, se: float) -> str:
    return f"{v:+.3f} ± {_se(se)}"


def _mm(x: float) -> str:
    return f"{1000 * x:.1f} mm"


def _ratio_words(c: Change) -> str:
    r = "many" if math.isinf(c.ratio) else f"{c.ratio:.1f}"
    return f"{r} standard errors; a change counts beyond {c.k:.2f}"


def _steps(m: dict, span: str) -> str:
    """'the first 15 steps' / 'all 100 steps', or 'the training horizon' where the metrics do not
    say how long it is (loop rounds do not carry ``imag_horizon``)."""
    if span == "eval_horizon":
        return f"all {m['eval_horizon']} steps"
    return f"the first {m['imag_horizon']} steps" if "imag_horizon" in m else "the training horizon"


def _short(m: dict, span: str) -> str:
    if span == "eval_horizon":
        return f"{m['eval_horizon']} steps"
    return f"{m['imag_horizon']} steps" if "imag_horizon" in m else "training horizon"


def _dream_key(span: str) -> str:
    return f"trained_dream_return_per_step_{span}"


def _real_key(span: str) -> str:
    return f"trained_real_return_per_step_{span}"


def sides(a: dict, b: dict, span: str = "eval_horizon") -> dict:
    """How each world's rating of the trained policy moved from run ``a`` to run ``b`` over ``span``.

    The gap is the dream's rating minus reality's, so ``gap_diff == dream - real`` exactly. Each side is
    judged against its own noise: its change beyond k of its own standard errors (the two runs' per-start
    standard errors in quadrature, as the gap's change is) and at least the minimum reward effect (claims
    ``06.change_up``/``06.change_down``). Reality's rating varies far less from start to start than the
    dream's, so the gap's yardstick would hide a real change of reality. Returns the changes, each side's
    bar and ``moved``, a dict ``{"dream": "up"|"down"|"same", "real": ...}``."""
    c = fix_change(a, b, span)
    out = {"gap": c.diff, "min_effect": c.min_effect, "moved": {}, "bar": {}}
    for world, key in (("dream", _dream_key(span)), ("real", _real_key(span))):
        se_key = key.replace("_return_per_step_", "_return_per_step_se_")
        d = float(b[key] - a[key])
        se = math.hypot(a[se_key], b[se_key])
        kw = dict(diff=d, se=se, k=c.k, min_effect=c.min_effect, quantity=f"{world} rating")
        out[world] = d
        out["bar"][world] = c.k * se
        out["moved"][world] = "up" if change_up(**kw) else "down" if change_down(**kw) else "same"
    return out


def _side_words(s: dict, a_name: str, b_name: str, a: dict, b: dict, span: str) -> str:
    """The sentence saying which world moved, with both numbers."""
    dk, rk = _dream_key(span), _real_key(span)
    text = (f"The dream's rating of the policy went from {a[dk]:+.3f} to {b[dk]:+.3f} per step ({s['dream']:+.3f}), "
            f"reality's from {a[rk]:+.3f} to {b[rk]:+.3f} ({s['real']:+.3f}), {a_name} to {b_name} "
            f"(each side counts as moved beyond k of its own standard errors, {s['bar']['dream']:.3f} for the dream "
            f"and {s['bar']['real']:.3f} for reality, and by at least {s['min_effect']:.2f}, the minimum effect). ")
    dream, real = s["moved"]["dream"], s["moved"]["real"]
    word = {"up": "rose", "down": "came down"}
    if dream != "same" and real == "same":
        text += (f"So the gap moved from the dream's side: the dream's rating {word[dream]}, reality's did not "
                 "move by that much. ")
    elif dream == "same" and real != "same":
        text += (f"So the gap moved from reality's side: what the policy really earns "
                 f"{'rose' if real == 'up' else 'fell'}, the dream's rating did not move by that much. ")
    elif dream != "same":
        same_way = dream == real
        text += ("Both worlds' ratings moved, " + ("in the same direction, so part of each cancels in the gap. "
                                                   if same_way else "in opposite directions. "))
    else:
        text += "Neither rating alone moved by that much. "
    return text


def _halves(m: dict, span: str = "eval_horizon") -> tuple[float, float, float, float]:
    """The gap's position and yaw halves over ``span`` and their standard errors."""
    p, pse = _gap_keys(span, "position")
    y, yse = _gap_keys(span, "yaw")
    return m[p], m[pse], m[y], m[yse]


def yaw_share(m: dict, span: str = "eval_horizon") -> float:
    """|yaw half| / (|position half| + |yaw half|) of the gap over ``span``: how much of the gap's
    two parts is the block's angle (NaN when both are 0)."""
    p, _, y, _ = _halves(m, span)
    tot = abs(p) + abs(y)
    return abs(y) / tot if tot > 0 else math.nan


def halves_order(position: float, yaw: float, diff_se: float, n_starts: int) -> str:
    """"yaw", "position" or "neither": which half of a gap is clearly the larger in size (claims
    ``06.yaw_half_clearly_larger``/``06.position_half_clearly_larger``): |yaw| - |position| beyond k
    times its standard error over the starts (``diff_se``, ``split.size_split``) and at least the
    minimum reward effect."""
    kw = dict(position=position, yaw=yaw, diff_se=diff_se, k=k_for(int(n_starts)), min_effect=MIN_REWARD_EFFECT)
    return "yaw" if yaw_half_clearly_larger(**kw) else "position" if position_half_clearly_larger(**kw) else "neither"


def _diff_se(m: dict, span: str = "eval_horizon", what: str = "imagination_gap") -> float:
    """The standard error over the starts of |yaw half| - |position half| of the gap (or, with
    ``what="gap_drift"``, of the drift)."""
    return m[f"{what}_yaw_minus_position_se_{span}"]


def _order(m: dict, span: str = "eval_horizon") -> str:
    p, _, y, _ = _halves(m, span)
    return halves_order(p, y, _diff_se(m, span), int(m["eval_episodes"]))


def error_size(m: dict, span: str = "eval_horizon", what: str = "imagination_gap") -> tuple[float, float]:
    """The size of the dream's error over ``span``, |position half| + |yaw half| of the gap (what a
    gap near zero can hide when the halves cancel; ``what="gap_drift"``: of the drift), and its
    standard error over the starts (``split.size_split``). Where the halves share a sign the size
    is the gap's size and its standard error the gap's: one quantity, one test."""
    return m[f"{what}_size_{span}"], m[f"{what}_size_se_{span}"]


def size_change(a: dict, b: dict, span: str = "eval_horizon", what: str = "imagination_gap") -> Change:
    """The size of the error (:func:`error_size`) from run ``a`` to run ``b``, against the minimum
    reward effect, by the gap's own test (:func:`compare`)."""
    (x, xs), (y, ys) = error_size(a, span, what), error_size(b, span, what)
    return compare(x, xs, y, ys, int(b["eval_episodes"]), min_effect=MIN_REWARD_EFFECT)


ORDER_WORDS = {"yaw": "the yaw half is the larger", "position": "the position half is the larger",
               "neither": "neither half is clearly the larger"}


def halves_rule(n_starts: int, short: bool = False) -> str:
    """The rule behind "the larger half", in one sentence (``short``: a parenthesis), for a reader."""
    if short:
        return (f"A half counts as the larger only beyond k = {k_for(int(n_starts)):.2f} standard errors of "
                f"the difference, and by at least {MIN_REWARD_EFFECT:.2f}.")
    return (f"A half counts as the larger only when its size exceeds the other's by more than k = "
            f"{k_for(int(n_starts)):.2f} standard errors of that difference (computed start by start, on the "
            f"same starts) and by at least the minimum effect of {MIN_REWARD_EFFECT:.2f} per step; otherwise "
            "neither half is clearly the larger.")


def _cancel_words(p: float, y: float) -> str:
    """A note when the two halves have opposite signs: they cancel almost exactly (claim
    ``06.halves_cancel``) or partly."""
    size = abs(p) + abs(y)
    if halves_cancel(position=p, yaw=y, share=CANCEL_SHARE):
        return (f" (the two halves have opposite signs and cancel almost exactly: their sum, {p + y:+.3f}, is less "
                f"than {CANCEL_SHARE:.0%} of their sizes added, {size:.3f}, so a gap near zero here hides an error "
                "of that size)")
    if p * y < 0:
        return (f" (the two halves have opposite signs and partly cancel: their sum is {p + y:+.3f}, their sizes "
                f"added {size:.3f})")
    return ""


def halves_words(m: dict, span: str = "eval_horizon") -> str:
    """"+0.073 ± 0.010 from the block's position and +0.112 ± 0.012 from its yaw (|yaw| - |position| =
    +0.039, standard error at most 0.022): the yaw half is the larger" (:func:`halves_order`), with a
    note when the two halves pull opposite ways (:func:`_cancel_words`). The rule: :func:`halves_rule`."""
    p, pse, y, yse = _halves(m, span)
    dse = _diff_se(m, span)
    order = halves_order(p, y, dse, int(m["eval_episodes"]))
    s = (f"{_pm(p, pse)} from the block's position and {_pm(y, yse)} from its yaw (|yaw| - |position| = "
         f"{abs(y) - abs(p):+.3f} ± {_se(dse)}): {ORDER_WORDS[order]}")
    return s + _cancel_words(p, y)


EXPERT_CONTROL = register_expert_control("06")


def expert_words(m: dict, span: str = "eval_horizon") -> tuple[str, str]:
    """The expert control in one run: ``(numbers, verdict)``. Does the dream pay the scripted
    expert's actions (which succeed in reality) more than zero actions? Claims
    ``06.dream_rewards_expert`` and ``06.dream_penalises_expert``, read only where the control is
    valid (``06.zero_control_valid``: the zero-action dream leaves the untouched block in place);
    the expert's own gap, dream minus reality, beside it."""
    n = int(m["eval_episodes"])
    k = k_for(n)
    d, dse = m[f"expert_signal_dream_{span}"], m[f"expert_signal_dream_se_{span}"]
    r, rse = m[f"expert_signal_real_{span}"], m[f"expert_signal_real_se_{span}"]
    nums = f"expert minus zero actions: dream {_pm(d, dse)}, reality {_pm(r, rse)} per step"
    kw = dict(signal=d, se=dse, k=k, min_effect=MIN_REWARD_EFFECT)
    rewards, penalises = dream_rewards_expert(**kw), dream_penalises_expert(**kw)
    valid, control = expert_control_words(m, span, k, EXPERT_CONTROL)
    if not valid:
        verdict = control
    elif rewards:
        verdict = f"the dream recognises success: it pays the expert's pushes more than standing still. {control}"
    elif penalises:
        verdict = (f"the dream does not recognise success: it pays the expert's pushes less than standing still. "
                   f"{control}")
    else:
        verdict = ("the dream does not tell the expert's pushes from standing still (not beyond the noise and "
                   f"the minimum effect of {MIN_REWARD_EFFECT:.2f}). {control}")
    return nums, verdict


def expert_short(m: dict, span: str = "eval_horizon") -> str:
    """A round's expert control in a few words (the same claims as :func:`expert_words`)."""
    k = k_for(int(m["eval_episodes"]))
    kw = dict(signal=m[f"expert_signal_dream_{span}"], se=m[f"expert_signal_dream_se_{span}"], k=k,
              min_effect=MIN_REWARD_EFFECT)
    rewards, penalises = dream_rewards_expert(**kw), dream_penalises_expert(**kw)
    moved = m[f"zero_dream_block_moved_{span}"]
    if not EXPERT_CONTROL["valid"](moved=moved, tol=SUCCESS_POS):
        return f"control invalid: the zero-action dream moves the untouched block {moved * 100:.0f} cm"
    return ("pays them more than standing still" if rewards else "pays them less than standing still" if penalises
            else "does not tell them from standing still")


def path_words(values, fmt: str = "+.3f") -> str:
    """The path of a per-round quantity, round to round: "round 0 -> 1: -0.080; 1 -> 2: +0.065; ...",
    and whether it went one way throughout: a summary of the end points alone hides a path that
    goes down and back up."""
    steps = [b - a for a, b in zip(values, values[1:])]
    if not steps:
        return ""
    s = "; ".join(f"{i} -> {i + 1}: {d:{fmt}}" for i, d in enumerate(steps))
    one_way = all(d > 0 for d in steps) or all(d < 0 for d in steps)
    return f"round to round, {s}" + ("" if one_way or len(steps) == 1 else " (not one way: the path turns)")


# --- Exercise 3's reconciliation ------------------------------------------------------------------
def _change_words(c: Change, cl: dict) -> str:
    if cl["shrank"]:
        return f"its size fell from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise and the minimum effect"
    if cl["grew"]:
        return f"its size rose from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise and the minimum effect"
    if cl["crossed"]:
        return "it changed sign beyond the noise: not a shrink, the opposite error"
    return "its size did not fall beyond the noise and the minimum effect"


def _sign_change_words(c: Change, cl: dict, a_name: str, b_name: str) -> str:
    if not cl["crossed"]:
        return ""
    return (f" It changed sign: in {a_name} the dream rated the policy {'above' if c.first > 0 else 'below'} "
            f"reality, in {b_name} {'above' if c.last > 0 else 'below'} it, both beyond the noise.")


def reopen_words(rounds: list, span: str = "eval_horizon") -> str:
    """Did the gap's size fall round after round, or reopen after its smallest round (claim
    ``06.gap_reopened``)?"""
    gk, sk = _gap_keys(span)
    sizes = [abs(m[gk]) for m in rounds]
    ses = [m[sk] for m in rounds]
    k = k_for(int(rounds[-1]["eval_episodes"]))
    i = int(np.argmin(sizes))
    r_min = rounds[i]["round"]
    if gap_reopened(sizes=sizes, ses=ses, k=k, min_effect=MIN_REWARD_EFFECT):
        return (f"Its size was smallest in round {r_min} ({sizes[i]:.3f}) and then rose again to {sizes[-1]:.3f} "
                "by the last round, beyond the noise and the minimum effect: the gap reopened.")
    if i == len(sizes) - 1:
        return f"Its size was smallest in the last round ({sizes[i]:.3f})."
    return (f"Its size was smallest in round {r_min} ({sizes[i]:.3f}); the last round's {sizes[-1]:.3f} is not "
            "larger beyond the noise and the minimum effect.")


@claim("06.dream_fell_for_the_policy", "the dream's rating of the policy fell by more than its rating of a pusher "
       "that never moves, beyond k standard errors of the difference and the minimum effect: the model learned "
       "something about this policy, not only grew gloomier everywhere", control="zero actions")
def dream_fell_for_the_policy(*, diff, se, k, min_effect):
    return _test_outcome(diff, k * se, min_effect) == "down"


def policy_specific_words(a: dict, b: dict, sd: dict) -> str:
    """Did the model stop promising what THIS policy does not deliver, or did its whole dream grow gloomier?
    The control is the zero-action dream: its rating's change from ``a`` to ``b`` is the drift's change
    (reality's zero-action rating is the same on the same starts). The policy's dream fell specifically
    when it fell by more than that, beyond k standard errors (the gap's change and the drift's change in
    quadrature) and the minimum effect (claim ``06.dream_fell_for_the_policy``)."""
    z0, z1 = a["zero_action_dream_return_per_step"], b["zero_action_dream_return_per_step"]
    dz = float(z1 - z0)
    c = fix_change(a, b)
    dse = math.hypot(a["gap_drift_se_eval_horizon"], b["gap_drift_se_eval_horizon"])
    se = math.hypot(c.se, dse)
    diff = float(sd["dream"] - dz)
    specific = dream_fell_for_the_policy(diff=diff, se=se, k=c.k, min_effect=c.min_effect)
    nums = (f"The control, a pusher that never moves: the dream's rating of it went {z0:+.3f} -> {z1:+.3f} "
            f"({dz:+.3f}); the policy's changed {sd['dream']:+.3f}, that is {diff:+.3f} beyond the control's change "
            f"(± {_se(se)})")
    if specific:
        return (nums + ", beyond the noise and the minimum effect. The model stopped promising what this policy "
                "does not deliver, which is not the same as the policy delivering more.")
    return (nums + ", not beyond the noise and the minimum effect. The whole dream grew gloomier, standing still "
            "included: that is not the model learning what this particular policy does not deliver.")


def reconcile_text(rounds: list) -> str:
    """Exercise 3's measured outcome in words: the gap over the whole evaluation in round 0 and after
    the last round, its change against the noise and the minimum effect, round by round, from which
    world's side it moved, the same at the training horizon, and real success."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), int(last["round"])
    c = gap_change(rounds)
    cl = c.claims()
    lines = [f"The gap over {_steps(last, 'eval_horizon')} (the whole evaluation, {n} starts): round 0 "
             f"{_pm(c.first, first['imagination_gap_se_eval_horizon'])}, after round {R} "
             f"{_pm(c.last, last['imagination_gap_se_eval_horizon'])} (imagined minus real reward per step)."]
    per_round = ", ".join(f"{m['imagination_gap_eval_horizon']:+.3f}" for m in rounds)
    gap_path = path_words([abs(m["imagination_gap_eval_horizon"]) for m in rounds])
    lines.append(f"Round by round: {per_round}" + (f" (its size {gap_path})" if gap_path and len(rounds) > 2 else "")
                 + ". " + reopen_words(rounds))
    s = (f"The change is {c.diff:+.3f} ± {_se(c.se)} ({_ratio_words(c)}; the minimum effect that matters is "
         f"{c.min_effect:.2f} per step). The standard error adds the two rounds' per-start standard errors in "
         "quadrature, as if the rounds had used independent starts; they used the same ones, so this is "
         "conservative. ")
    if cl["shrank"]:
        s += (f"The gap shrank: its size fell from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise and "
              "the minimum effect.")
        lp, _, ly, _ = _halves(last)
        if lp * ly < 0:
            s += (f" (After round {R} its two halves have opposite signs, position {lp:+.3f} and yaw {ly:+.3f}: the "
                  f"size of the error they hide is {abs(lp) + abs(ly):.3f}, larger than the gap.)")
    elif cl["grew"]:
        s += (f"The gap grew: its size rose from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise and "
              "the minimum effect.")
    elif cl["crossed"]:
        s += ("The gap went through zero and out the other side, beyond the noise: it changed sign, which is "
              "not a shrink.")
    else:
        s += "The gap's size did not fall beyond the noise and the minimum effect: it did not shrink."
    s += _sign_change_words(c, cl, "round 0", f"round {R}")
    lines.append(s)
    # the control: did the gap shrink because the model's error with nobody pushing turned over?
    d0, d0se = first["gap_drift_eval_horizon"], first["gap_drift_se_eval_horizon"]
    d1, d1se = last["gap_drift_eval_horizon"], last["gap_drift_se_eval_horizon"]
    if cl["shrank"] and drift_crossed_zero(first=d0, first_se=d0se, last=d1, last_se=d1se, k=c.k):
        lines.append(f"The control says how: the drift, the dream's error with a pusher that never moves, went "
                     f"{_pm(d0, d0se)} -> {_pm(d1, d1se)}, through zero beyond the noise, while the part of the gap "
                     f"that is this policy's own (gap minus drift) went {c.first - d0:+.3f} -> {c.last - d1:+.3f}. The "
                     "gap shrank by the model trading its error with nobody pushing for the opposite one, not by "
                     "learning what this policy does.")
    sd = sides(first, last)
    lines.append(_side_words(sd, "round 0", f"round {R}", first, last, "eval_horizon").strip())
    if cl["shrank"] and sd["moved"] == {"dream": "down", "real": "same"}:
        lines.append("The dream came down to meet reality; reality did not rise to meet the dream. "
                     + policy_specific_words(first, last, sd))
    elif cl["shrank"] and sd["moved"] == {"dream": "same", "real": "up"}:
        lines.append("Reality rose to meet the dream: the policy earns more in the real world, and the model's "
                     "rating of it did not move by that much.")
    ct = gap_change(rounds, "train_horizon")
    lines.append(f"Over {_steps(last, 'train_horizon')} (what the actor's gradient sees) the gap went "
                 f"{_pm(ct.first, first['imagination_gap_se_train_horizon'])} -> "
                 f"{_pm(ct.last, last['imagination_gap_se_train_horizon'])}: {_change_words(ct, ct.claims())}.")
    s0, s1 = successes(first), successes(last)
    succ = f"Real successes: {', '.join(f'{successes(m)}/{n}' for m in rounds)} (round 0 to round {R}). "
    if success_rose(rounds):
        p = count_rise_p(s0, s1, n)
        succ += ("Real success rose" + (" above 0%" if s0 == 0 else "") + f" (Fisher's exact test, one-sided p = "
                 f"{p:.3f}: " + ("beyond chance)." if count_beyond_chance(p=p, bar=COUNT_P) else
                                 "with this few, it could be luck; rerun another seed before believing it)."))
    elif s0 == 0:
        succ += "Real success stayed at 0%."
    else:
        succ += f"Real success did not rise: round 0 already had {s0}/{n}, and the last round has no more."
    lines.append(succ)
    lines.append(f"So the measured answer is ({ex3_verdict(rounds)}).")
    return "\n".join(lines)


# --- the rounds, in a table and in sentences --------------------------------------------------------
def rounds_table(rounds: list) -> str:
    """A markdown table, one row per round: both gaps with their standard errors, both worlds'
    ratings over the whole evaluation, real successes and touches, where the block went, the share
    of real steps with the pusher at a wall, and the world model's error on the policy's data (clips
    of that round's real evaluation rollouts) against copy-last, in mm."""
    last = rounds[-1]
    head = ["round", "policy episodes so far", f"gap, {_short(last, 'train_horizon')}",
            f"gap, {_short(last, 'eval_horizon')}", "dream", "real", "real successes", "touching the block",
            "block moved (m)", "block toward target (m)", "pusher at a wall",
            "one-step block: model / copy-last (mm)", "one-step pusher (mm)",
            "open-loop block (mm)", "open-loop pusher (mm)",
            f"gap's halves, {_short(last, 'eval_horizon')}: position / yaw",
            f"expert signal in the dream, {_short(last, 'eval_horizon')}",
            f"expert signal in reality, {_short(last, 'eval_horizon')}"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def err(m, kind, part):
        return (f"{1000 * m[f'wm_policy_{kind}_{part}_err']:.1f} / "
                f"{1000 * m[f'wm_policy_{kind}_{part}_copy_err']:.1f}")

    for m in rounds:
        n = m["eval_episodes"]
        cells = [str(m["round"]), str(m.get("policy_episodes", "")),
                 _pm(m["imagination_gap_train_horizon"], m["imagination_gap_se_train_horizon"]),
                 _pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
                 f"{m[_dream_key('eval_horizon')]:+.3f}", f"{m[_real_key('eval_horizon')]:+.3f}",
                 f"{successes(m)}/{n}", f"{m['real_episodes_touching_block']}/{n}",
                 f"{m['real_block_displacement']:.3f}", f"{m['real_block_toward_target']:+.3f}",
                 f"{m['real_pusher_at_wall_share']:.0%}",
                 err(m, "one_step", "block"), err(m, "one_step", "pusher"),
                 err(m, "open_loop", "block"), err(m, "open_loop", "pusher")]
        p, pse, y, yse = _halves(m)
        cells += [f"{_pm(p, pse)} / {_pm(y, yse)}",
                  _pm(m["expert_signal_dream_eval_horizon"], m["expert_signal_dream_se_eval_horizon"]),
                  _pm(m["expert_signal_real_eval_horizon"], m["expert_signal_real_se_eval_horizon"])]
        rows.append("| " + " | ".join(cells) + " |")
    rows.append("")
    rows.append("Gaps are imagined minus real reward per step, ± one standard error over the evaluation starts; "
                "dream and real are reward per step over the whole evaluation (each start's mean over the steps it "
                "lasted, averaged over the starts, so the gap is exactly dream minus real); the four error columns are the world model's "
                "RMSE on the policy's data (clips of that round's real evaluation rollouts, never trained on) "
                "against copying the last frame. The gap's halves: the reward is a position term "
                "plus a yaw term, and the gap splits exactly into the two. The expert signal: the scripted "
                "expert's reward minus zero actions' reward per step, from the same starts, in each world (the "
                "expert's own actions replayed in the dream): positive means that world pays the pushes that "
                "solve the task more than standing still.")
    return "\n".join(rows)


def rounds_sentence(rounds: list) -> str:
    """Per round: the gap's position and yaw halves and which is clearly the larger (:func:`halves_order`),
    the rule once, whether the larger half changes between rounds (only where it is resolved in both), at both horizons for the first and last round; and the expert control:
    does the dream recognise success in each round, and did the loop teach the model to reward the
    expert's pushes (claims ``06.dream_rewards_expert``, ``06.change_up``/``_down`` on its change)?"""
    first, last = rounds[0], rounds[-1]
    R = last["round"]
    per = "; ".join(f"round {m['round']}: {halves_words(m)}" for m in rounds)
    lines = [f"**The gap's two halves** over {_steps(last, 'eval_horizon')} (imagined minus real reward per "
             f"step, ± one standard error): {per}."]
    lines.append(f"Over {_steps(last, 'train_horizon')}, round 0: {halves_words(first, 'train_horizon')}; after "
                 f"round {R}: {halves_words(last, 'train_horizon')}.")
    lines.append(halves_rule(int(last["eval_episodes"])))
    order = {m["round"]: _order(m) for m in rounds}

    def named(kind):
        rs = [str(r) for r, o in order.items() if o == kind]
        return ("round " if len(rs) == 1 else "rounds ") + ", ".join(rs)

    kinds = set(order.values())
    span = _steps(last, "eval_horizon")
    if kinds == {"yaw"}:
        lines.append(f"Over {span}, in every round, the block's angle, not its distance, is clearly the larger part "
                     "of the gap: a figure of where the block sits shows only the smaller half.")
    elif kinds == {"position"}:
        lines.append(f"Over {span}, in every round, the block's distance to the target is clearly the larger part "
                     "of the gap.")
    elif kinds == {"neither"}:
        lines.append(f"Over {span}, in no round is either half clearly the larger.")
    elif {"yaw", "position"} <= kinds:
        lines.append(f"Over {span} the larger half changes from round to round: yaw in {named('yaw')}, position in "
                     f"{named('position')}" + (f", neither clearly in {named('neither')}" if "neither" in kinds
                                               else "") + ".")
    else:
        one = (kinds - {"neither"}).pop()
        lines.append(f"Over {span} the {one} half is clearly the larger in {named(one)}, and neither half is clearly "
                     f"the larger in {named('neither')}: where one half is resolved, it is the same one.")
    short = {m["round"]: expert_short(m) for m in rounds}
    per_e = "; ".join(f"round {m['round']}: {_pm(m['expert_signal_dream_eval_horizon'], m['expert_signal_dream_se_eval_horizon'])}"  # noqa: E501
                      f" ({short[m['round']]})" for m in rounds)
    reals = [_pm(m["expert_signal_real_eval_horizon"], m["expert_signal_real_se_eval_horizon"]) for m in rounds]
    real = (f"{reals[0]} in every round (the same expert from the same starts)" if len(set(reals)) == 1
            else ", ".join(reals) + f" (round 0 to round {R})")
    wins = ", ".join(f"{int(round(m['expert_real_success_rate'] * m['eval_episodes']))}/{int(m['eval_episodes'])}"
                     for m in rounds[:1])
    lines.append("**Does the dream recognise success?** The control is the scripted expert, which succeeds in "
                 f"reality from {wins} of these starts. Its actions, replayed in the dream, minus zero actions, per "
                 f"step over {_steps(last, 'eval_horizon')}: {per_e}. In reality the same difference is {real}. A "
                 "dream counts as recognising success when it pays the expert's pushes more than standing still "
                 f"by more than k standard errors and at least {MIN_REWARD_EFFECT:.2f} per step, and only where "
                 f"standing still stands still in the dream (the zero-action dream moves the untouched block at most "
                 f"the {SUCCESS_POS * 100:.0f} cm success tolerance).")
    valid = [EXPERT_CONTROL["valid"](moved=m["zero_dream_block_moved_eval_horizon"], tol=SUCCESS_POS)
             for m in (first, last)]
    c = metric_change(first, last, "expert_signal_dream_eval_horizon", "expert_signal_dream_se_eval_horizon")
    d = c.direction()
    path = path_words(_series(rounds, "expert_signal_dream_eval_horizon"))
    head = (f"From round 0 to round {R} the dream's expert signal changed by {c.diff:+.3f} ± {_se(c.se)} "
            f"({_ratio_words(c)}; minimum effect {c.min_effect:.2f})" + (f"; {path}" if path else ""))
    if not all(valid):
        g = metric_change(first, last, "expert_gap_eval_horizon", "expert_gap_se_eval_horizon")
        gpath = path_words(_series(rounds, "expert_gap_eval_horizon"))
        lines.append(head + ". That change cannot be read as the loop teaching the model about the expert's pushes: "
                     "in round " + " and ".join(str(m["round"]) for m, v in zip((first, last), valid) if not v)
                     + " the zero-action dream moves the untouched block beyond the success tolerance, so the "
                     "control moves with the model. The expert's own gap, dream minus reality, which needs no such "
                     f"control, went {first['expert_gap_eval_horizon']:+.3f} -> {last['expert_gap_eval_horizon']:+.3f}"
                     f" ({g.diff:+.3f} ± {_se(g.se)}: "
                     + {"up": "rose", "down": "fell", "same": "not changed"}[g.direction()]
                     + " beyond the noise and the minimum effect" + (f"; {gpath}" if gpath else "") + ").")
    else:
        lines.append(head + ": "
                     + {"up": "the loop taught the model to pay the expert's pushes more, beyond the noise and the "
                              "minimum effect, against round 0.",
                        "down": "the loop made the model pay the expert's pushes less, beyond the noise and the "
                                "minimum effect, against round 0.",
                        "same": "the loop did not change what the model pays the expert's pushes, beyond the noise "
                                "and the minimum effect."}[d])
    return "\n\n".join(lines)


def _step_words(values) -> list[str]:
    """'down'/'up'/'level' for each change between consecutive values, at the ERR_RES resolution."""
    return [_outcome(b - a, ERR_RES).replace("same", "level") for a, b in zip(values, values[1:])]


def trend_phrase(values, rounds_idx=None) -> str:
    """'fell in every round', 'rose in every round', 'held level throughout (within 1 mm)', or which
    rounds it fell, rose and held in (``values``: one error per round, metres)."""
    words = _step_words(values)
    idx = list(rounds_idx) if rounds_idx is not None else list(range(1, len(values)))
    verbs = {"down": "fell", "up": "rose", "level": "held within 1 mm"}
    if len(set(words)) == 1:
        return {"down": "fell in every round", "up": "rose in every round",
                "level": "held within 1 mm throughout"}[words[0]]
    parts = []
    for w in ("down", "up", "level"):
        rs = [str(r) for r, x in zip(idx, words) if x == w]
        if rs:
            label = "round " + rs[0] if len(rs) == 1 else "rounds " + ", ".join(rs[:-1]) + " and " + rs[-1]
            parts.append(f"{verbs[w]} in {label}")
    return ", ".join(parts)


def _series(rounds, key) -> list[float]:
    return [float(m[key]) for m in rounds]


def _arrow(values) -> str:
    return " -> ".join(f"{1000 * v:.1f}" for v in values) + " mm"


def model_error_sentence(rounds: list) -> str:
    """Does the world model's one-step error on the policy's data fall every round, and on expert
    data? Names every round's number (mm), the copy-last error on the same data, and the open-loop
    errors' overall direction."""
    R = rounds[-1]["round"]
    idx = [m["round"] for m in rounds[1:]]
    out = [f"Below, an error \"fell\" or \"rose\" when it changed by more than {_mm(ERR_RES)}: a resolution, not a "
           "test against the noise (the metrics keep no spread for these errors, each an RMSE over many clips)."]
    for data in ("policy", "expert"):
        parts = []
        for part in ("block", "pusher"):
            v = _series(rounds, f"wm_{data}_one_step_{part}_err")
            parts.append(f"the {part}'s {_arrow(v)} ({trend_phrase(v, idx)})")
        where = ("On the policy's data (clips of each round's own real evaluation rollouts, never trained on)"
                 if data == "policy" else "On held-out expert data")
        out.append(f"{where} the world model's one-step error went: " + "; ".join(parts) + ".")
        if data == "policy":
            last = rounds[-1]
            rel = []
            for part in ("block", "pusher"):
                model, copy_ = last[f"wm_policy_one_step_{part}_err"], last[f"wm_policy_one_step_{part}_copy_err"]
                if model > copy_ + ERR_RES:
                    rel.append(f"the {part}'s is still {model / copy_:.1f}x copy-last's ({_mm(model)} vs {_mm(copy_)})"
                               if copy_ > 0 else f"the {part}'s is {_mm(model)}, copy-last's 0")
                elif model < copy_ - ERR_RES:
                    rel.append(f"the {part}'s beats copy-last ({_mm(model)} vs {_mm(copy_)})")
                else:
                    rel.append(f"the {part}'s is within 1 mm of copy-last's ({_mm(model)} vs {_mm(copy_)})")
            cb = _series(rounds, "wm_policy_one_step_block_copy_err")
            out.append(f"After round {R}, " + " and ".join(rel) + ". The data changed too: each round's policy "
                       f"data comes from that round's policy; copy-last's block error on it went {_arrow(cb)}, "
                       "a measure of how much the block moves in it.")
    ol = []
    for data in ("policy", "expert"):
        for part in ("block", "pusher"):
            v = _series(rounds, f"wm_{data}_open_loop_{part}_err")
            d = _outcome(v[-1] - v[0], ERR_RES)
            verb = {"down": "fell overall", "up": "rose overall", "same": "within 1 mm overall"}[d]
            ol.append(f"{DATA_LABELS[data]}, {part}: {_arrow(v)} ({verb}; {trend_phrase(v, idx)})")
    out.append(f"Open-loop (the dream running alone through each clip), round 0 to round {R}: "
               + "; ".join(ol) + ".")

    def ends(key):
        return [rounds[0][key], rounds[-1][key]]

    pol = [ends(f"wm_policy_{k}_{p}_err") for k in ("one_step", "open_loop") for p in ("block", "pusher")]
    exp = [ends(f"wm_expert_{k}_{p}_err") for k in ("one_step", "open_loop") for p in ("block", "pusher")]
    share = ""
    if "train_clips" in rounds[0] and rounds[-1]["train_clips"] > 0:
        share = (f" (after round {R}, {1 - rounds[0]['train_clips'] / rounds[-1]['train_clips']:.0%} of its "
                 f"{rounds[-1]['train_clips']} training clips are the policy's)")
    better = model_better_on_policy(firsts=[a for a, _ in pol], lasts=[b for _, b in pol], res=ERR_RES)
    worse_expert = model_worse_somewhere(firsts=[a for a, _ in exp], lasts=[b for _, b in exp], res=ERR_RES)
    if better and worse_expert:
        out.append("So, from round 0 to the last round, the model got better on the policy's data at every measure "
                   "here and worse, on some measures, on the expert's: its training data moved toward the "
                   f"policy's{share}.")
    elif better:
        out.append("So, from round 0 to the last round, the model got better on the policy's data at every measure "
                   "here, without losing ground on the expert's data.")
    elif model_worse_somewhere(firsts=[a for a, _ in pol], lasts=[b for _, b in pol], res=ERR_RES):
        out.append("So more data of the policy's own did not make the model better on it at every measure: on "
                   "some it ended worse than in round 0.")
    else:
        out.append("So more data of the policy's own did not make the model better on it at every measure: on "
                   "some it stayed within 1 mm of round 0.")
    return " ".join(out)


@claim("06.model_better_on_policy_data", "from round 0 to the last round every error of the model on the policy's "
       "data (one-step and open-loop, block and pusher) fell by more than 1 mm", control="round 0")
def model_better_on_policy(*, firsts, lasts, res):
    return all(b < a - res for a, b in zip(firsts, lasts))


@claim("06.model_worse_somewhere", "from round 0 to the last round at least one of these errors of the model rose by "
       "more than 1 mm", control="round 0")
def model_worse_somewhere(*, firsts, lasts, res):
    return any(b > a + res for a, b in zip(firsts, lasts))


def displacement_se_bound(m: dict) -> float:
    """An upper bound on the standard error of ``real_block_displacement`` (a mean over the starts):
    each displacement lies in [0, max], so their variance is at most mean * (max - mean)
    (Bhatia-Davis), sample variance n / (n - 1) times that."""
    n, mu, top = m["eval_episodes"], m["real_block_displacement"], m["real_block_displacement_max"]
    return float(math.sqrt(max(mu * (top - mu), 0.0) / (n - 1)))


def toward_se_bound(m: dict) -> float:
    """An upper bound on the standard error of ``real_block_toward_target`` (a mean over the starts).

    Each start's spawn distance minus final distance is at most its displacement d_i (triangle
    inequality), so its mean square is at most mean(d^2) <= mean(d) * max(d); minus the squared
    mean, n / (n - 1) times, over n."""
    n, mu, top = m["eval_episodes"], m["real_block_displacement"], m["real_block_displacement_max"]
    t = m["real_block_toward_target"]
    return float(math.sqrt(max(mu * top - t ** 2, 0.0) / (n - 1)))


def toward_outcome(m: dict) -> str:
    """"closer", "farther" or "same": where the real block ends relative to where it spawned, on
    average, judged against k times :func:`toward_se_bound` (and at least ``NEAR``, 5 mm)."""
    bar = max(k_for(int(m["eval_episodes"])) * toward_se_bound(m), NEAR)
    t = m["real_block_toward_target"]
    return "closer" if block_closer(toward=t, bar=bar) else "farther" if block_farther(toward=t, bar=bar) else "same"


@claim("06.block_closer", "on average the real block ends nearer the target than it spawned, beyond k bounds on its "
       "standard error and at least 5 mm")
def block_closer(*, toward, bar):
    return toward > bar


@claim("06.block_farther", "on average the real block ends farther from the target than it spawned, beyond k bounds "
       "on its standard error and at least 5 mm")
def block_farther(*, toward, bar):
    return toward < -bar


def block_sentence(rounds: list) -> str:
    """Where the real pusher goes and what it does to the block, round 0 against the last round: the
    share of steps at a wall, episodes touching the block (Fisher's test on the counts), the mean
    displacement (against its bound) and where the block ends relative to the target."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), last["round"]
    walls = ", ".join(f"{m['real_pusher_at_wall_share']:.0%}" for m in rounds)
    s = f"The share of real steps with the pusher pinned at a wall went {walls} (round 0 to round {R}). "
    t0, t1 = int(first["real_episodes_touching_block"]), int(last["real_episodes_touching_block"])
    touches = ", ".join(f"{int(m['real_episodes_touching_block'])}" for m in rounds)
    s += f"The pusher touched the block in {touches} of {n} evaluation episodes"
    fisher = ("Fisher's exact test, one-sided, against {bar}, treats the two rounds as independent samples; they "
              "used the same starts, and a paired test (McNemar's) would need which starts touched in each round, "
              "which the metrics do not keep, so this p is an approximation").format(bar=f"{COUNT_P:.3f}")
    if t1 != t0:
        lo, hi = sorted((t0, t1))
        p = count_rise_p(lo, hi, n)
        s += (f" (round 0 to round {R}: a {'rise' if t1 > t0 else 'fall'} "
              f"{'beyond chance' if count_beyond_chance(p=p, bar=COUNT_P) else 'that could be chance'}, p = {p:.3f}; "
              f"{fisher}). ")
    else:
        s += ". "
    b0, b1 = displacement_se_bound(first), displacement_se_bound(last)
    c = compare(first["real_block_displacement"], b0, last["real_block_displacement"], b1, n,
                min_effect=SUCCESS_POS)
    s += (f"The block moved a mean {first['real_block_displacement']:.3f} m in round 0 and "
          f"{last['real_block_displacement']:.3f} m after round {R} (at most "
          f"{last['real_block_displacement_max']:.3f} m), a change of {c.diff:+.3f} m: "
          + {"up": "more, beyond the noise and the minimum effect", "down": "less, beyond the noise and the minimum "
             "effect", "same": "not told apart by these starts"}[c.direction()]
          + f" (a t-test on the two means against k = {c.k:.2f} times {c.se:.3f} m, an upper bound on the standard "
          "error of the change built from each round's largest displacement, and a minimum effect of "
          f"{SUCCESS_POS:.2f} m, the success tolerance). ")
    t = last["real_block_toward_target"]
    bound = toward_se_bound(last)
    out = toward_outcome(last)
    s += (f"After round {R} the block ends on average {abs(t):.3f} m {'closer to' if t >= 0 else 'farther from'} "
          f"the target than it spawned (standard error at most {bound:.3f} m): ")
    s += {"closer": "closer, beyond the noise. ", "farther": "farther, beyond the noise. ",
          "same": "not told apart from where it spawned. "}[out]
    s += (f"It ends {last['real_final_tee_dist']:.3f} m from the target on average; a success needs "
          f"{SUCCESS_POS:.2f} m. ")
    if c.direction() == "up" and out != "closer":
        s += ("The policy moves the block more, but not toward the target: touching the block is not yet "
              "pushing it where it should go.")
    elif out == "closer":
        s += "The policy pushes the block toward the target, measurably."
    return s.strip()


# --- the other two fixes --------------------------------------------------------------------------
def expert_ratio(m: dict, kind: str, dim: str) -> float:
    """The model's error over copy-last's on held-out expert data, ``kind`` "one_step" or
    "open_loop", for one observation dimension (``metrics.json`` or a loop round)."""
    for key in (f"wm_{kind}_ratio_{dim}", f"wm_expert_{kind}_ratio_{dim}"):
        if key in m:
            return float(m[key])
    raise KeyError(f"no {kind} copy-last ratio for {dim} in these metrics")


def _sign_word(v: float, se: float, k: float) -> str:
    """"rosier than reality", "gloomier than reality" or "not told apart from reality": beyond k
    standard errors and the minimum reward effect (claims ``06.dream_rosier``/``06.dream_gloomier``)."""
    kw = dict(value=v, se=se, k=k, min_effect=MIN_REWARD_EFFECT)
    if dream_rosier(**kw):
        return "rosier than reality"
    if dream_gloomier(**kw):
        return "gloomier than reality"
    return "not told apart from reality"


@claim("06.beats_copy_last_everywhere", "the model's one-step error is below copy-last's on every observation "
       "dimension (held-out expert data)")
def beats_copy_last_everywhere(*, ratios):
    return all(math.isfinite(x) and x < 1 for x in ratios)


@claim("06.model_moves_untouched_block", "with zero actions the dreamed block ends more than 5 mm nearer or farther "
       "from the target than it spawned (a real untouched block does not move)", control="reality")
def model_moves_untouched_block(*, final_dist, spawn_dist, tol):
    return abs(final_dist - spawn_dist) > tol


@claim("06.pusher_left_table", "replaying the policy's real actions, the dreamed pusher ends farther from the real "
       "one than the arena is wide")
def pusher_left_table(*, err, arena):
    return err > arena


@claim("06.error_accumulates", "replaying the policy's real actions over the whole evaluation, the fix's dreamed "
       "pusher ends farther off than the state model's", control="the state model")
def error_accumulates(*, fix_err, ref_err):
    return fix_err > ref_err


def fix_verdict(ref: dict, fix: dict, name: str, ref_name: str) -> tuple[bool, str]:
    """Does ``fix`` count as a fix against ``ref``? Claim ``06.fix_closed_gap``: the gap's size shrank
    at both horizons, beyond k standard errors of the change and by at least ``MIN_REWARD_EFFECT``,
    without crossing zero beyond the noise; the drift (the zero-action control) did not cross zero
    beyond the noise (a model that now carries an untouched block away has traded one error for the
    opposite one, and the gap can close by that trade alone); and the fix's zero-action dream moves
    an untouched block no farther than the reference's does (``zero_dream_block_moved_eval_horizon``,
    within the success tolerance); and claim ``06.error_size_shrank`` at both horizons: the size of the
    error, |position half| + |yaw half| (:func:`error_size`), fell the same way, so halves that cancel do
    not pass for a fix. Returns the verdict and a sentence with each condition's numbers."""
    parts = []
    changes = {}
    for span in SPAN_KEYS:
        c = fix_change(ref, fix, span)
        changes[span] = c
        cl = c.claims()
        parts.append(f"over {_steps(fix, span)} {c.first:+.3f} -> {c.last:+.3f} ± {_se(c.last_se)} "
                     f"({_change_words(c, cl)})")
    tr, ev = changes["train_horizon"], changes["eval_horizon"]
    d0, d0se = ref["gap_drift_eval_horizon"], ref["gap_drift_se_eval_horizon"]
    d1, d1se = fix["gap_drift_eval_horizon"], fix["gap_drift_se_eval_horizon"]
    flipped = drift_crossed_zero(first=d0, first_se=d0se, last=d1, last_se=d1se, k=ev.k)
    moved, ref_moved = fix["zero_dream_block_moved_eval_horizon"], ref["zero_dream_block_moved_eval_horizon"]
    zd = fix["zero_action_dream_final_tee_dist"]
    on_table = untouched_block_on_table(final_dist=zd, arena_half=ARENA_HALF)
    table = (f"with zero actions its dream moves the untouched block {moved:.3f} m (the largest displacement of each "
             f"start, averaged; {ref_name}'s moves it {ref_moved:.3f} m, a real untouched block not at all) and ends it "
             f"{zd:.3f} m from the target (" + ("within" if on_table else "farther than")
             + f" the {ARENA_HALF:.1f} m to the nearest wall); its drift went {_pm(d0, d0se)} -> {_pm(d1, d1se)}"
             + (": it changed sign beyond the noise, the opposite error" if flipped else ""))
    closed = fix_closed_gap(first_tr=tr.first, first_tr_se=tr.first_se, last_tr=tr.last, last_tr_se=tr.last_se,
                            first_ev=ev.first, first_ev_se=ev.first_se, last_ev=ev.last, last_ev_se=ev.last_se,
                            k=ev.k, min_effect=ev.min_effect, drift_first=d0, drift_first_se=d0se, drift_last=d1,
                            drift_last_se=d1se, moved=moved, ref_moved=ref_moved, tol=SUCCESS_POS)
    sizes = []
    shrank_all = True
    for span in SPAN_KEYS:
        (a, ab), (b, bb) = error_size(ref, span), error_size(fix, span)
        fell = error_size_shrank(first=a, first_se=ab, last=b, last_se=bb, k=ev.k, min_effect=ev.min_effect)
        shrank_all = shrank_all and fell
        sizes.append(f"over {_steps(fix, span)} {a:.3f} -> {b:.3f} ("
                     + ("fell" if fell else "did not fall") + " beyond the noise and the minimum effect: k = "
                     f"{ev.k:.2f} times {math.sqrt(ab ** 2 + bb ** 2):.3f}, the change's standard error, "
                     f"and {MIN_REWARD_EFFECT:.2f})")
    holds = closed and shrank_all
    verdict = (f"{name} counts as a fix of the gap" if holds else f"{name} does not count as a fix of the gap")
    text = (f"{verdict}: against {ref_name} its gap went " + "; ".join(parts) + f", and {table}. The size of the "
            "dream's error, |position half| + |yaw half|, which a gap near zero can hide when the halves cancel, "
            "went " + "; ".join(sizes) + ". A fix needs the gap's size to fall at both horizons, beyond the noise "
            f"and by at least {MIN_REWARD_EFFECT:.2f} per step, without crossing zero, the size of the error to fall "
            "the same way (a gap that reaches zero by cancelling halves is not a fix), a drift that does not turn "
            "into the opposite error, and a dream that moves an untouched block no farther than "
            f"{ref_name}'s does (within the {SUCCESS_POS * 100:.0f} cm success tolerance).")
    return holds, text


def delta_sentence(state_m: dict, delta_m: dict) -> str:
    """The delta model against the state model: copy-last ratios on the block (one-step and
    open-loop, expert data), the gap at the training horizon and over the whole evaluation (and its
    halves), the zero-action dream, the pusher's replay error at the end of the evaluation, the
    expert control, and whether it counts as a fix (:func:`fix_verdict`)."""
    n = int(delta_m["eval_episodes"])
    k = k_for(n)
    pos = ("tee_x", "tee_y")
    r = {name: {kind: [expert_ratio(m, kind, d) for d in pos] for kind in ("one_step", "open_loop")}
         for name, m in (("state", state_m), ("delta", delta_m))}
    all_dims = [expert_ratio(delta_m, "one_step", d) for d in OBS_NAMES]
    # a ratio of 1 is copy-last itself: the baseline, not a tolerance
    fmt = lambda xs: "/".join(f"{x:.2f}" for x in xs)        # noqa: E731
    s = (f"On held-out expert data, the delta model's block position error is {fmt(r['delta']['one_step'])} (x/y) "
         f"of copy-last's one step ahead and {fmt(r['delta']['open_loop'])} open-loop; the state model's "
         f"{fmt(r['state']['one_step'])} and {fmt(r['state']['open_loop'])}. ")
    worst = max(range(len(all_dims)), key=lambda i: all_dims[i] if np.isfinite(all_dims[i]) else math.inf)
    s += ((f"One step ahead it beats copy-last on every one of the {len(all_dims)} observation dimensions (its "
           f"largest ratio, on {OBS_NAMES[worst]}, is {all_dims[worst]:.2f}). ")
          if beats_copy_last_everywhere(ratios=all_dims) else
          f"One step ahead it beats copy-last on {sum(np.isfinite(x) and x < 1 for x in all_dims)} of "
          f"{len(all_dims)} observation dimensions (the worst, {OBS_NAMES[worst]}, at {all_dims[worst]:.2f} of "
          "copy-last's error). ")
    words = {}
    for span in SPAN_KEYS:
        g, se = delta_m[f"imagination_gap_{span}"], delta_m[f"imagination_gap_se_{span}"]
        gs = state_m[f"imagination_gap_{span}"]
        words[span] = _sign_word(g, se, k)
        s += (f"Over {_steps(delta_m, span)} its gap is {_pm(g, se)} ({words[span]}; the state model "
              f"{gs:+.3f}). ")
    s += f"Over the whole evaluation its gap is {halves_words(delta_m)}. {halves_rule(n, short=True)} "
    mood = {"rosier than reality": "rosy", "gloomier than reality": "gloomy"}
    w_tr, w_ev = words["train_horizon"], words["eval_horizon"]
    if {w_tr, w_ev} == set(mood):
        s += (f"Its dream is {mood[w_tr]} over the span the actor trained on and {mood[w_ev]} over the whole "
              "evaluation: it changed sign on the way. ")
    d, dse = delta_m["gap_drift_eval_horizon"], delta_m["gap_drift_se_eval_horizon"]
    zd, spawn = delta_m["zero_action_dream_final_tee_dist"], delta_m["spawn_tee_dist"]
    s += (f"With zero actions its dream is {_pm(d, dse)} per step against reality ({_sign_word(d, dse, k)}; the "
          f"state model {state_m['gap_drift_eval_horizon']:+.3f}), and the untouched dreamed block ends "
          f"{zd:.3f} m from the target on average, where it spawned {spawn:.3f} m away")
    # NEAR (5 mm): an untouched real block does not move at all, so a dreamed one that ends more
    # than that away from its spawn distance was moved by the model alone
    s += (": the model moves a block nobody touches" if model_moves_untouched_block(
        final_dist=zd, spawn_dist=spawn, tol=NEAR) else "")
    if not untouched_block_on_table(final_dist=zd, arena_half=ARENA_HALF):
        s += (f". That is farther from the target than the walls are ({ARENA_HALF:.1f} m): a runaway dream, "
              "which carries untouched blocks into the corners or off the table")
    s += ". "
    e_tr, e_ev = delta_m["replay_pusher_err_train_horizon"], delta_m["replay_pusher_err_eval_horizon"]
    H = delta_m.get("imag_horizon")
    at_tr = f"after {H * CONTROL_DT:.1f} s" if H else "at the training horizon"
    secs = delta_m["eval_horizon"] * CONTROL_DT
    s += (f"Replaying the policy's real actions, its dreamed pusher is {e_tr:.3f} m off {at_tr} and "
          f"{e_ev:.3f} m off after {secs:.0f} s (state model: {state_m['replay_pusher_err_train_horizon']:.3f} "
          f"and {state_m['replay_pusher_err_eval_horizon']:.3f} m). ")
    if pusher_left_table(err=e_ev, arena=ARENA):
        s += (f"That is farther than the arena is wide ({ARENA:.0f} m): the dreamed pusher has left the table. ")
    clip = delta_m["train_clip_steps"]
    if error_accumulates(fix_err=e_ev, ref_err=state_m["replay_pusher_err_eval_horizon"]):
        s += (f"A change-predicting model adds each step's small error to all the earlier ones, and it trained on "
              f"{clip}-step clips: nothing in its training saw what {delta_m['dream_steps_per_train_clip']:.2f} "
              "times as many accumulated steps do. Beating copy-last one step ahead says nothing about that. ")
    else:
        s += (f"Over {delta_m['eval_horizon']} steps its accumulated changes stay no farther off than the state "
              "model's. ")
    nums, verdict = expert_words(delta_m)
    s += f"The expert control ({nums}): {verdict}. "
    s += fix_verdict(state_m, delta_m, "Predicting changes", "the state model")[1]
    return s.strip()


@claim("06.shared_bias", "the ensemble members disagree less (the larger disagreement figure) than their mean dream "
       "errs from reality (the smaller error figure)")
def shared_bias(*, disagreement, error):
    return disagreement < error


TRAIN_TAIL = 20    # the last iterations of the actor's training, as metrics.json's final imagined reward


def ensemble_sentence(single_m: dict, ens_m: dict, penalty: float | None = None, train_disagreement=None) -> str:
    """The ensemble (with MOPO's penalty) against the single model: its gap at both horizons (and its
    halves), real return and successes, its members' disagreement (m) against its error from
    reality, the expert control, and whether it counts as a fix (:func:`fix_verdict`).
    ``penalty``: the run's ``disagreement_penalty`` (reward per step per metre), if known;
    ``train_disagreement``: the run's ``history["imag_disagreement"]`` (the members' mean disagreement
    over each training iteration's dreams, m), if known: what the penalty cost the actor is read
    from its last ``TRAIN_TAIL`` iterations. Without it, the cost is read from the evaluation dream,
    and the sentence says so."""
    n = int(ens_m["eval_episodes"])
    s = ""
    for span in SPAN_KEYS:
        c = fix_change(single_m, ens_m, span)
        word = {"up": "higher than the single model's, beyond the noise and the minimum effect",
                "down": "lower than the single model's, beyond the noise and the minimum effect",
                "same": "not told apart from the single model's"}[c.direction()]
        s += (f"Over {_steps(ens_m, span)} the ensemble's gap is {_pm(c.last, ens_m[f'imagination_gap_se_{span}'])} "
              f"against the single model's {_pm(c.first, single_m[f'imagination_gap_se_{span}'])}: "
              f"{c.diff:+.3f}, {word} ({_ratio_words(c)}; minimum effect {c.min_effect:.2f}). ")
    s += f"Over the whole evaluation its gap is {halves_words(ens_m)}. {halves_rule(n, short=True)} "
    sd = sides(single_m, ens_m)
    s += (f"Reality pays its policy {ens_m[_real_key('eval_horizon')]:+.3f} per step, the single model's "
          f"{single_m[_real_key('eval_horizon')]:+.3f} ({sd['real']:+.3f}; "
          + ("not moved by" if sd["moved"]["real"] == "same" else "moved beyond")
          + f" k of its own standard errors ({sd['bar']['real']:.3f}) and the minimum effect); real successes {successes(ens_m)}/{n} "
          f"against {successes(single_m)}/{n}. ")
    if "wm_ensemble_disagreement_train_horizon" not in ens_m:
        return s + "These metrics hold no ensemble disagreement (a single model has none)."
    dis_tr, dis_ev = ens_m["wm_ensemble_disagreement_train_horizon"], ens_m["wm_ensemble_disagreement_eval_horizon"]
    err_tr, err_ev = ens_m["replay_block_err_train_horizon"], ens_m["replay_block_err_eval_horizon"]
    s += (f"Along its policy's evaluation dream (the dream the policy steers itself) the members disagree on where "
          f"the block is by {dis_tr:.3f} m on average over {_steps(ens_m, 'train_horizon')} and {dis_ev:.3f} m over "
          f"{_steps(ens_m, 'eval_horizon')}; their mean dream of a different rollout, the policy's real actions "
          f"replayed open-loop, has the block {err_tr:.3f} m off reality at the training horizon and {err_ev:.3f} m "
          "at the end. ")
    # the most cautious comparison the metrics allow: the larger disagreement figure against the
    # smaller error figure (the disagreement is a mean over steps, the error a value at one step)
    if shared_bias(disagreement=max(dis_tr, dis_ev), error=min(err_tr, err_ev)):
        s += (f"The members are closer to each other than their mean is to reality (by a factor of at least "
              f"{math.floor(10 * min(err_tr, err_ev) / max(dis_tr, dis_ev)) / 10:.1f}, the smaller error over the "
              "larger disagreement). "
              "The two figures come from two different rollouts of the same policy, from the same starts, so this "
              "is a comparison of scales, not of the same steps; it suggests that most of the error is one the "
              "members share, a bias of the data they all learned from, which a penalty on disagreement cannot "
              "see. ")
    else:
        s += ("Their disagreement is as large as their error from reality (the two figures come from two different "
              "rollouts of the same policy, so this compares scales, not the same steps): here it may flag the "
              "error. ")
    if penalty is not None:
        gap_tr = ens_m["imagination_gap_train_horizon"]
        hist = [float(x) for x in (train_disagreement if train_disagreement is not None else [])]
        if hist:
            tail = hist[-min(TRAIN_TAIL, len(hist)):]
            paid = float(np.mean(tail))
            s += (f"With a penalty of {penalty:g} per metre the actor paid about {penalty * paid:.3f} per step of "
                  f"dreamed reward in its own training dreams ({_steps(ens_m, 'train_horizon')}, started from "
                  f"frames of the training data; the members' disagreement there averaged {paid:.3f} m over the last {len(tail)} training "
                  f"iterations), against a gap of {gap_tr:+.3f} over that horizon. ")
        else:
            s += (f"With a penalty of {penalty:g} per metre, the disagreement along the evaluation dream over "
                  f"{_steps(ens_m, 'train_horizon')} would cost {penalty * dis_tr:.3f} per step of dreamed reward "
                  f"(the training dreams' own disagreement is not in these metrics), against a gap of {gap_tr:+.3f} "
                  "there. ")
    nums, verdict = expert_words(ens_m)
    s += f"The expert control ({nums}): {verdict}. "
    s += fix_verdict(single_m, ens_m, "The ensemble with its penalty", "the single model")[1]
    return s.strip()


# --- the conclusion -------------------------------------------------------------------------------
def _fix_line(name: str, ref: dict, fix: dict, ref_name: str) -> str:
    n = int(fix["eval_episodes"])
    sd = sides(ref, fix)
    _, verdict = fix_verdict(ref, fix, "it", ref_name)
    real = (f"In reality the policy earns {fix[_real_key('eval_horizon')]:+.3f} per step against "
            f"{ref[_real_key('eval_horizon')]:+.3f} ("
            + ("not moved by" if sd["moved"]["real"] == "same" else "moved beyond")
            + f" k of its own standard errors ({sd['bar']['real']:.3f}) and the minimum effect) and succeeds {successes(fix)}/{n} "
            f"times against {successes(ref)}/{n}.")
    p, _, y, _ = _halves(fix)
    halves = f"Its gap's halves over the whole evaluation: position {p:+.3f}, yaw {y:+.3f}."
    nums, ex = expert_words(fix)
    return f"**{name}**: {verdict} {halves} {real} Expert control ({nums}): {ex}."


def _share_cell(m: dict) -> str:
    """The yaw share of a run's gap, and "neither half clearly larger" where the halves' test says so: a
    share of 95% read alone would say the yaw half dominates when the noise cannot tell."""
    return f"{yaw_share(m):.0%}" + (" (neither half clearly larger)" if _order(m) == "neither" else "")


def _expert_cell(m: dict) -> str:
    """The dream's expert signal, and "control invalid" where the zero-action dream moves the untouched
    block beyond the success tolerance (claim ``06.zero_control_valid``)."""
    ok = EXPERT_CONTROL["valid"](moved=m["zero_dream_block_moved_eval_horizon"], tol=SUCCESS_POS)
    return (_pm(m["expert_signal_dream_eval_horizon"], m["expert_signal_dream_se_eval_horizon"])
            + ("" if ok else " (control invalid: the zero-action dream moves the block "
                             f"{m['zero_dream_block_moved_eval_horizon']:.2f} m)"))


def fixes_table(state_m: dict, loop_last_m: dict, delta_m: dict, ens_m: dict) -> str:
    """A markdown table of the three fixes beside the single state model: the gap at both horizons,
    its position and yaw halves (whole evaluation), the zero-action drift, where the untouched
    dreamed block ends, the expert signal in the dream and real successes."""
    runs = [("single model (loop round 0)", state_m), (f"loop, after round {loop_last_m.get('round', '?')}",
                                                      loop_last_m),
            ("delta model", delta_m), ("ensemble + penalty", ens_m)]
    m0 = state_m
    head = ["run", f"gap, {_short(m0, 'train_horizon')}", f"gap, {_short(m0, 'eval_horizon')}",
            "position / yaw halves", "yaw share", f"drift (zero actions), {_short(m0, 'eval_horizon')}",
            "untouched dreamed block from target (m)", "expert signal in the dream", "real successes"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, m in runs:
        p, pse, y, yse = _halves(m)
        rows.append("| " + " | ".join([
            name, _pm(m["imagination_gap_train_horizon"], m["imagination_gap_se_train_horizon"]),
            _pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
            f"{p:+.3f} / {y:+.3f}", _share_cell(m),
            _pm(m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]),
            f"{m['zero_action_dream_final_tee_dist']:.3f}", _expert_cell(m),
            f"{successes(m)}/{int(m['eval_episodes'])}"]) + " |")
    rows.append("")
    rows.append("Reward per step, ± one standard error over the evaluation starts. Yaw share: |yaw half| / "
                "(|position half| + |yaw half|) of the gap over the whole evaluation. The untouched block: with "
                f"zero actions, where the dreamed block ends (the walls are {ARENA_HALF:.1f} m from the target; a "
                "real untouched block stays where it spawned). Expert signal: the scripted expert's actions minus "
                "zero actions, in the dream.")
    return "\n".join(rows)


def _drift_words(m: dict, k: float) -> str:
    d, dse = m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]
    p, y = m["gap_drift_position_eval_horizon"], m["gap_drift_yaw_eval_horizon"]
    pse, yse = m["gap_drift_se_position_eval_horizon"], m["gap_drift_se_yaw_eval_horizon"]
    order = halves_order(p, y, _diff_se(m, "eval_horizon", "gap_drift"), int(m["eval_episodes"]))
    size, sse = error_size(m, "eval_horizon", "gap_drift")
    return (f"{_pm(d, dse)} per step (position {_pm(p, pse)}, yaw {_pm(y, yse)}: {ORDER_WORDS[order]}, by the rule "
            f"of the gap's halves above; its size, |position| + |yaw|, {_pm(size, sse)})")


def conclusion(rounds: list, state_m: dict, delta_m: dict, ens_m: dict) -> str:
    """What each fix bought in each world (whether it counts as a fix, its halves, real return and
    successes, the expert control), and, as open questions, what real success plausibly needs, each
    tied to a number and guarded by a claim."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), last["round"]
    lines = [_fix_line(f"The real-data loop ({R} round{'s' if R != 1 else ''}, "
                       f"{last.get('policy_episodes', '?')} real policy episodes)",
                       first, last, "round 0"),
             _fix_line("Predicting changes", state_m, delta_m, "the state model"),
             _fix_line("An ensemble with a disagreement penalty", state_m, ens_m, "the single model")]
    runs = {"the loop": last, "the delta model": delta_m, "the ensemble": ens_m}
    if no_real_success(successes=[successes(m) for m in runs.values()]):
        lines.append("**No fix produced a single real success.** Closing a gap is not solving the task: the gap "
                     "can close from the dream's side alone.")
    else:
        # a success counts against the fix's own reference (round 0, the state model), never against zero
        refs = {"the loop": (first, "round 0"), "the delta model": (state_m, "the state model"),
                "the ensemble": (state_m, "the single model")}
        said = []
        for w, m in runs.items():
            ref, ref_name = refs[w]
            a, b = successes(ref), successes(m)
            if b == 0:
                continue
            if b > a:
                p = count_rise_p(a, b, n)
                said.append(f"{w} {b}/{n} against {a}/{n} for {ref_name} (Fisher's exact one-sided p = {p:.3f}, "
                            + ("beyond chance)" if count_beyond_chance(p=p, bar=COUNT_P) else "could be chance)"))
            else:
                said.append(f"{w} {b}/{n}, no more than {ref_name}'s {a}/{n}: not something the fix bought")
        lines.append("Real successes: " + "; ".join(said) + ". One seed and a few starts; rerun other seeds before "
                     "calling any of it a fix.")
    k = k_for(n)
    open_ = [f"*Data the policy never collects.* The loop corrects the model only where its policy goes: after "
             f"round {R} the real block ends {last['real_final_tee_dist']:.3f} m from the target on average "
             f"(a success needs {SUCCESS_POS:.2f} m). The expert's data reach the goal, but by the expert's "
             "actions; the states between, which a better policy would have to pass through with its own "
             "actions, are in neither data set, and nothing corrects the dream there. Exploration aimed at "
             "what the model does not know would plausibly be needed."]
    nums, ex = expert_words(last)
    open_.append(f"*A dream that can tell success from standing still.* After round {R}, {nums}: {ex}. An actor "
                 "trained in a dream can only learn the pushes that dream pays for.")
    tr, tse = last["gap_training_train_horizon"], last["gap_training_se_train_horizon"]
    kw = dict(value=tr, se=tse, k=k, min_effect=MIN_REWARD_EFFECT)
    if dream_rosier(**kw):
        open_.append(f"*Reward exploitation.* After round {R} training still makes the dream rosier than reality "
                     f"over the training horizon by {_pm(tr, tse)} per step, beyond the noise and the minimum "
                     "effect: the actor keeps learning things only the model pays for, and a better actor would "
                     "find more of them.")
    elif dream_gloomier(**kw):
        open_.append(f"*Reward exploitation* is not what this run shows: after round {R} the gap's training term "
                     f"over the training horizon is {_pm(tr, tse)}, training made the dream gloomier, not rosier, "
                     "than reality. A stronger actor, though, searches harder, and every model has errors to find.")
    else:
        open_.append(f"*Reward exploitation.* After round {R} the gap's training term over the training horizon "
                     f"is {_pm(tr, tse)}, not beyond the noise and the minimum effect of {MIN_REWARD_EFFECT:.2f}; "
                     "but a stronger actor searches harder, and every model has errors to find.")
    dc = metric_change(first, last, "gap_drift_eval_horizon", "gap_drift_se_eval_horizon")
    d0se = first["gap_drift_se_eval_horizon"]
    causal = f"*Causal confusion.* With zero actions the round-0 dream is {_drift_words(first, k)} against reality"
    if dream_rosier(value=dc.first, se=d0se, k=k, min_effect=MIN_REWARD_EFFECT):
        causal += (": rosy with a pusher that never moves. In the expert data the block moves only when pushed, "
                   "and then toward the target's place and angle; a model can learn \"the block approaches the "
                   "target\" without the contact that causes it. ")
    else:
        causal += ". "
    sc = size_change(first, last, "eval_horizon", "gap_drift")
    kw = dict(first=sc.first, first_se=sc.first_se, last=sc.last, last_se=sc.last_se, k=sc.k,
              min_effect=sc.min_effect)
    flipped = drift_crossed_zero(first=dc.first, first_se=d0se, last=dc.last,
                                 last_se=last["gap_drift_se_eval_horizon"], k=k)
    fell, rose = error_size_shrank(**kw), error_size_grew(**kw)      # both evaluated, so both are recorded
    d = "flip" if flipped else "down" if fell else "up" if rose else "same"
    path = path_words(_series(rounds, "gap_drift_size_eval_horizon"))
    causal += (f"After round {R} that drift is {_drift_words(last, k)}. Judged by its size, as the gap is (halves "
               f"of opposite signs cancel in the signed drift), it went {sc.first:.3f} -> {sc.last:.3f}"
               + (f" ({path})" if path else "") + ": "
               + {"down": "it fell beyond the noise and the minimum effect, against round 0. ",
                  "up": "it rose beyond the noise and the minimum effect, against round 0. ",
                  "flip": "but the signed drift changed sign beyond the noise: the dream of a pusher that never "
                          "moves went from too rosy to too gloomy, the opposite error, not a smaller one. ",
                  "same": "not changed beyond the noise and the minimum effect. "}[d])
    pc, ec = last["wm_policy_one_step_block_copy_err"], last["wm_expert_one_step_block_copy_err"]
    z0, z1 = first["zero_dream_block_moved_eval_horizon"], last["zero_dream_block_moved_eval_horizon"]
    if d in ("down", "same") and not flipped and d0se > 0 and dc.first * dc.last < 0:
        causal += "(Its sign did change, though not beyond the noise.) "
    if d == "down" and pc < ec:
        if z1 < z0 - SUCCESS_POS:
            causal += (f"The policy's data, in which the block moves less (copy-last's one-step block error is "
                       f"{_mm(pc)} on them, {_mm(ec)} on the expert's), may have taught the model otherwise: its "
                       f"zero-action dream now moves the untouched block {z1:.3f} m, against {z0:.3f} m in round 0. ")
        else:
            causal += (f"Did the policy's data teach the model that an untouched block stays put? The control says "
                       f"not: its zero-action dream moves the untouched block {z1:.3f} m, against {z0:.3f} m in round "
                       "0 (a real one does not move). ")
    causal += ("Whether a model has the cause right is tested only by data where the cause and its usual "
               "companions come apart.")
    open_.append(causal)
    lines.append("**Open: what real success would plausibly need.** These runs suggest, they do not show: "
                 + " ".join(open_))
    return "\n\n".join(lines)


# --- every seed in this output folder ----------------------------------------------------------------
def _read_json(path):
    import json

    return json.loads(path.read_text())


def summary_runs(out_dir) -> dict:
    """Every seed's runs found under ``out_dir``: ``{seed: {"offline": m, "loop": last round,
    "delta": m, "ensemble": m}}`` (each present only where its file is). The offline run is the
    loop's round 0 (``metrics/closing/loop_seed<s>/loop.json``) or, without a loop, notebook 04's
    ``metrics/seed<s>.json``; the loop's entry is its last round; ``delta_seed<s>.json`` and
    ``ensemble_seed<s>.json`` are notebook 06's two other fixes."""
    import re
    from pathlib import Path

    out = Path(out_dir)
    closing = out / "metrics" / "closing"
    found: dict = {}

    def put(seed, kind, m):
        found.setdefault(int(seed), {})[kind] = m

    for path in sorted((out / "metrics").glob("seed*.json")):
        hit = re.fullmatch(r"seed(\d+)\.json", path.name)
        if hit:
            put(hit.group(1), "offline", _read_json(path))
    for path in sorted(closing.glob("loop_seed*/loop.json")):
        hit = re.fullmatch(r"loop_seed(\d+)", path.parent.name)
        rounds = _read_json(path)
        if hit and rounds:
            put(hit.group(1), "offline", rounds[0])
            if len(rounds) > 1:
                put(hit.group(1), "loop", rounds[-1])
    for kind in ("delta", "ensemble"):
        for path in sorted(closing.glob(f"{kind}_seed*.json")):
            hit = re.fullmatch(rf"{kind}_seed(\d+)\.json", path.name)
            if hit:
                put(hit.group(1), kind, _read_json(path))
    return dict(sorted(found.items()))


SUMMARY_KINDS = {"offline": "offline (single model)", "loop": "loop, last round", "delta": "delta model",
                 "ensemble": "ensemble + penalty"}


def summary_table(out_dir) -> str:
    """One markdown table, per seed and per fix found under ``out_dir`` (:func:`summary_runs`): the
    gap over the whole evaluation (± SE), the zero-action drift (± SE), the yaw share of the gap,
    real successes and the expert signal in the dream (± SE); and which seeds it found."""
    runs = summary_runs(out_dir)
    if not runs:
        return (f"No metrics found under `{out_dir}` (notebook 04 writes `metrics/seed<s>.json`, this notebook "
                "`metrics/closing/`).")
    head = ["seed", "run", "gap (whole evaluation)", "drift (zero actions)", "yaw share of the gap",
            "real successes", "expert signal in the dream", "rounds"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    missing = []
    for seed, kinds in runs.items():
        for kind, label in SUMMARY_KINDS.items():
            m = kinds.get(kind)
            if m is None:
                missing.append(f"seed {seed}: {label}")
                continue
            share = yaw_share(m)
            rows.append("| " + " | ".join([
                str(seed), label,
                _pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
                _pm(m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]),
                "n/a" if math.isnan(share) else _share_cell(m),
                f"{successes(m)}/{int(m['eval_episodes'])}", _expert_cell(m),
                str(m.get("round", "")) if kind == "loop" else ""]) + " |")
    seeds = list(runs)
    text = [f"Seeds found under `{out_dir}`: {', '.join(str(s) for s in seeds)} ({len(seeds)} seed"
            f"{'s' if len(seeds) != 1 else ''}).", "", *rows, "",
            "Reward per step over the whole evaluation, ± one standard error over the evaluation starts. Gap: "
            "imagined minus real; drift: the same with zero actions (the model on its own); yaw share: |yaw "
            "half| / (|position half| + |yaw half|) of the gap; expert signal: the scripted expert's actions "
            "minus zero actions, in the dream (a dream that recognises success pays the expert's pushes more "
            "than standing still)."]
    if missing:
        text.append("Not found (that notebook or seed was not run into this folder): " + "; ".join(missing) + ".")
    return "\n".join(text)


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
        g = _series(rounds, f"imagination_gap_{span}")
        se = _series(rounds, f"imagination_gap_se_{span}")
        ax.errorbar(x + dx, g, yerr=se, fmt="o-", color=color, capsize=4, lw=1.5,
                    label=f"over {_steps(last, span)}")
    ax.axhline(0, color="gray", lw=1, ls="--", label="dream = reality")
    ax.set_ylabel("imagination gap (imagined minus real\nreward per step; bars: ± 1 standard error)")
    ax.set_title("The gap, round by round")
    _round_axis(ax, rounds)
    _legend_below(ax)
    ax = axes[1]
    for dx, part, color in ((-0.06, "position", "tab:blue"), (0.06, "yaw", "tab:red")):
        g = _series(rounds, f"imagination_gap_{part}_eval_horizon")
        se = _series(rounds, f"imagination_gap_se_{part}_eval_horizon")
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
                model = _series(rounds, f"wm_{data}_{kind}_{part}_err")
                copy_ = _series(rounds, f"wm_{data}_{kind}_{part}_copy_err")
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
        g = [m[f"imagination_gap_{span}"] for m in runs]
        se = [m[f"imagination_gap_se_{span}"] for m in runs]
        ax.bar(x, g, 0.6, yerr=se, capsize=5, color=colors, alpha=0.85)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_xlabel("run")
        ax.set_ylabel("imagination gap (imagined minus real reward\nper step; bars: ± 1 standard error)")
        ax.set_title(f"The gap over {_steps(state_m, span)}")
    ax = axes[2]
    for dx, part, color in ((-0.18, "position", "tab:blue"), (0.18, "yaw", "tab:red")):
        g = [m[f"imagination_gap_{part}_eval_horizon"] for m in runs]
        se = [m[f"imagination_gap_se_{part}_eval_horizon"] for m in runs]
        ax.bar(x + dx, g, 0.36, yerr=se, capsize=4, color=color, alpha=0.8,
               label=f"{part} half" + (" (the block's angle)" if part == "yaw" else " (its distance)"))
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_xlabel("run")
    ax.set_ylabel("part of the gap (reward per step;\nbars: ± 1 standard error)")
    ax.set_title(f"The gap's two halves ({_steps(state_m, 'eval_horizon')})")
    _legend_below(ax, y=-0.3)
    ax = axes[3]
    for dx, world, key in ((-0.18, "dream", _dream_key("eval_horizon")), (0.18, "real", _real_key("eval_horizon"))):
        ax.bar(x + dx, [m[key] for m in runs], 0.36, color=WORLD_COLORS[world], alpha=0.85,
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
SELF_CHECKS = {
    "dream_side": Question(
        "Suppose a loop's world model gets more accurate on the policy's own data and the gap shrinks, yet the "
        "policy earns no more in reality than before. How can both be true? (Whether that is what happened on "
        "your run, the numbers above say; this is about what is possible.)",
        {"a": "They cannot: a more accurate model always yields a better policy",
         "b": "Trained on what this policy's actions really do, the model stops promising what they do not "
              "deliver: the dream's rating comes down to reality's. The gap is a difference, and it closes just "
              "as well when only the dream moves",
         "c": "The gap is measured on new evaluation starts each round, so the rounds cannot be compared"},
        "b", "The gap is imagined minus real return. Fitting the model to the policy's data can correct the "
             "imagined side for this policy; nothing in that by itself makes the real side rise. Read both "
             "ratings, not only their difference."),
    "shared_bias": Question(
        "Three world models are trained on the same data, each from its own initial weights and batch order. "
        "Why can they agree closely with each other and still all be wrong about the policy's real data?",
        {"a": "Because the disagreement penalty trains the members to agree",
         "b": "Because what they learn is set by the data: where the data never show something, every member "
              "fills it in with the same regularity the data did show. Disagreement measures how their guesses "
              "differ, not how far their common guess is from reality",
         "c": "Because three members are too few to disagree at all"},
        "b", "Random initialisation and batch order make members differ only where the data leave them free. "
             "A bias the data put into all of them (blocks that approach the target, a pusher never at a wall) "
             "is shared, and a penalty on their spread cannot see it. The penalty shapes the actor, not the "
             "members."),
    "delta_runaway": Question(
        "Suppose a world model that predicts the change from one frame to the next beats copy-last one step ahead "
        "on every dimension, yet its 100-step dream runs far off, even off the table. How can both be true? "
        "(Whether your delta model did either, the sentence above says.)",
        {"a": "One step ahead, each prediction starts from the true previous frame; in a dream each step adds its "
              "small error to the sum of all the earlier ones, with no true frame to pull it back, and training "
              "on 16-step clips never penalised what 100 accumulated steps do",
         "b": "The one-step error was measured on the training data",
         "c": "Copy-last is so weak that beating it means the model is wrong"},
        "a", "A one-step test anchors the model to the truth at every step; a dream never does. Summing changes "
             "has nothing that keeps the result inside the arena, while a model that decodes positions is pulled "
             "toward positions it was trained on."),
    "fixed_norm": Question(
        "The loop normalises every round's data with the mean and standard deviation of the EXPERT frames, "
        "fixed, rather than recomputing them on all the data seen so far. Why?",
        {"a": "To save the time it takes to compute a mean",
         "b": "Because the policy's data have the same mean and spread as the expert's",
         "c": "The world model and the actor keep training from last round's weights, which read normalised "
              "inputs: new statistics would change what every input number means under those weights. Fixed, "
              "a number means the same physical state in every round"},
        "c", "Continuing training assumes the inputs keep their meaning. Re-normalising would shift every input "
             "under trained weights at once, and a round's change could then come from the new scale rather "
             "than the new data. (The errors above are in metres either way.)"),
}
