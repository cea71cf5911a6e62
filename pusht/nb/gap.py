"""Notebook 04's figures, conclusions and self-checks: the imagination gap, taken apart.

Every threshold that decides a sentence here is a multiple of a standard error measured on the
same run (``pusht.analysis``: per-start spread over the evaluation starts, or the training
updates' own spread), never a typed-in amount. The multiple is ``k`` = :func:`k_se`, the two-sided
95% point of Student's t at n - 1 degrees of freedom for n evaluation starts (1.98 for the default 100 starts),
as in notebooks 05 and 06; a difference is also held to the minimum effect that matters
(:data:`~pusht.nb.stats.MIN_REWARD_EFFECT`). Each verdict has four outcomes: beyond k standard
errors and the minimum effect (a change); beyond k standard errors but smaller than the minimum
effect ("detected, but smaller than the minimum effect that matters"); and within the noise.
"""

from __future__ import annotations

import numpy as np

from ..config import Config
from ..env import SUCCESS_ANG, SUCCESS_POS, obs_to_pose
from ..selfcheck import Question
from . import figure
from .claims import claim, finite
from .stats import LEVEL, MIN_REWARD_EFFECT, beyond, count_rise_p, k_for, welch

# The default config's number of held-out starts (cfg.eval_episodes), for metrics that do not say.
DEFAULT_STARTS = Config.eval_episodes


def k_se(n: int | None = None) -> float:
    """k of every verdict here: the two-sided LEVEL point of Student's t at n - 1 degrees of
    freedom, n the number of evaluation starts (DEFAULT_STARTS when not given)."""
    n = DEFAULT_STARTS if n is None else int(n)
    return k_for(max(n, 2))


def _k(m: dict | None = None, n: int | None = None) -> float:
    """k for a run's metrics ``m``: ``n`` if given, else the metrics' ``eval_episodes``."""
    return k_se(n if n is not None else (m or {}).get("eval_episodes"))


K_SE = k_se()                # for the default config's 100 starts (1.98); the functions take n
# 5 mm: the smallest distance difference these sentences read as a difference (a sixth of the
# pusher's radius; the per-start spread of final distances is several centimetres).
NEAR = 0.005
# 10 degrees, the environment's yaw tolerance: the smallest yaw difference read as a difference.
NEAR_DEG = float(np.degrees(SUCCESS_ANG))
COLORS = {"dream": "tab:purple", "real": "tab:orange"}
POLICY_LABELS = {"zero": "zero actions", "untrained": "untrained actor", "trained": "trained actor"}
TERMS = {"drift": "drift (zero actions)", "motion": "untrained actor's motion",
         "training": "training"}
SPANS = {"train_horizon": "training horizon", "eval_horizon": "whole evaluation"}
HALVES = ("position", "yaw")


def test_words(k: float = K_SE) -> str:
    """How a difference is judged, in words (k standard errors, Student's t, and the minimum effect)."""
    return (f"beyond k = {k:.2f} standard errors over the starts (Student's t, {LEVEL:.0%} two-sided) and at "
            f"least the minimum effect that matters, {MIN_REWARD_EFFECT:.2f} per step")


TEST_WORDS = test_words()


# --- the claims this notebook makes about the learner's run -------------------------------------
# Each is a named predicate (pusht.nb.claims): the sentence it guards is printed only when it holds,
# and its true alternative otherwise. A reward-per-step difference counts when it is beyond k
# (k_se: Student's t at the starts' degrees of freedom) standard errors (measured on the same starts) AND at least MIN_REWARD_EFFECT.
def _beyond(value, se, k, min_effect) -> bool:
    return finite(value, se, k, min_effect) and beyond(value, se, k, min_effect, +1)


@claim("04.term_positive", "a term of the gap is clearly positive: beyond k standard errors and the "
       "minimum effect that matters")
def term_positive(*, value, se, k, min_effect, what=""):
    return _beyond(value, se, k, min_effect)


@claim("04.term_negative", "a term of the gap is clearly negative: beyond k standard errors and the "
       "minimum effect that matters")
def term_negative(*, value, se, k, min_effect, what=""):
    return _beyond(-value, se, k, min_effect)


@claim("04.real_success", "the trained policy solved at least one real start on some seed")
def real_success(*, success_rates):
    return any(r > 0 for r in success_rates)


# One-sided bar for a count of real successes against the zero-action control's, as notebook 06's
COUNT_P = (1 - LEVEL) / 2


@claim("04.ex1_letter_decided", "Exercise 1's letter is decided beyond the noise: on every seed compared, the drift is "
       "farther from half the gap than k standard errors of their difference (start by start)", control="zero actions")
def ex1_letter_decided(*, diffs, ses, ks):
    return all(beyond(d, se, kk) for d, se, kk in zip(diffs, ses, ks))


@claim("04.real_success_beyond_chance", "on some seed the trained policy's real successes exceed those of a pusher "
       "that never moves beyond chance (Fisher's exact test, one-sided p below the bar)", control="zero actions")
def real_success_beyond_chance(*, trained, zero, n, bar):
    return any(count_rise_p(int(z), int(t), int(k)) < bar for t, z, k in zip(trained, zero, n))


@claim("04.gap_rosy", "the dream rates the trained policy well above reality (the whole evaluation's "
       "gap beyond k standard errors and the minimum effect)", control="reality")
def gap_rosy(*, gap, se, k, min_effect):
    return _beyond(gap, se, k, min_effect)


@claim("04.drift_half_of_gap", "zero actions are already rated well above reality by the dream, by "
       "at least half of the trained policy's gap", control="zero actions")
def drift_half_of_gap(*, drift, se, gap, k, min_effect):
    return _beyond(drift, se, k, min_effect) and drift >= 0.5 * gap


@claim("04.drift_half_on_means", "averaged over the seeds, the drift is at least half of the gap", control="zero actions")
def drift_half_on_means(*, drifts, gaps):
    return float(np.mean(drifts)) >= 0.5 * float(np.mean(gaps))


@claim("04.dream_reproduces_package", "the learner's dream gives the package's imagined reward "
       "to within 1e-5 per step")
def dream_reproduces_package(*, mismatch):
    return finite(mismatch) and mismatch < 1e-5


@claim("04.training_exploits", "within the actor's training horizon, training made the dream rosier "
       "than it made reality, beyond k standard errors and the minimum effect: exploitation", control="the untrained actor")
def training_exploits(*, value, se, k, min_effect):
    return _beyond(value, se, k, min_effect)


@claim("04.training_exploits_eval", "over the whole evaluation, training made the dream rosier than "
       "it made reality, beyond k standard errors and the minimum effect", control="the untrained actor")
def training_exploits_eval(*, value, se, k, min_effect):
    return _beyond(value, se, k, min_effect)


@claim("04.drift_rosy", "with the pusher standing still, the dream is rosier than reality within "
       "the training horizon, beyond k standard errors and the minimum effect", control="reality")
def drift_rosy(*, value, se, k, min_effect):
    return _beyond(value, se, k, min_effect)


@claim("04.half_dominates", "the named half of the gap is positive and larger than the other half "
       "by more than k standard errors of their difference and the minimum effect")
def half_dominates(*, larger, smaller, se_diff, k, min_effect, which=""):
    return larger > 0 and _beyond(larger - smaller, se_diff, k, min_effect)


@claim("04.term_beyond_noise", "a term of the gap is beyond k standard errors from zero (whatever its size)")
def term_beyond_noise(*, value, se, k, what=""):
    return finite(value, se, k) and beyond(value, se, k)


@claim("04.dream_block_drifts_back", "the trained dream's block comes nearest inside the training "
       "horizon, then ends more than 5 mm farther out", control="zero actions")
def dream_block_drifts_back(*, t_min, horizon_s, d_min, d_end, near):
    return t_min <= horizon_s and d_end > d_min + near


@claim("04.zero_dream_closer", "the zero-action dream gets the block nearer the target (by over 5 mm) "
       "than the trained actor's dream ever does", control="zero actions")
def zero_dream_closer(*, zero_min, trained_min, near):
    return zero_min < trained_min - near


# "Drifts toward" the data's typical pose means covering most of the way there: at least this share of
# the real (unmoved) block's distance to it, and more than the success tolerance. A dream that covers 3 cm
# of 14 moved, but it did not drift toward the typical pose; the sentence then says how far it went.
DRIFT_SHARE = 0.5


@claim("04.dream_drifts_to_data_position", "with zero actions, the dreamed block covers at least half of the "
       "real (unmoved) block's distance to the expert data's mean block position, and more than the 2 cm success "
       "tolerance", control="reality")
def dream_drifts_to_data_position(*, dream_to_mean, real_to_mean, near, share=DRIFT_SHARE):
    covered = real_to_mean - dream_to_mean
    return covered > near and covered >= share * real_to_mean


@claim("04.dream_drifts_to_data_yaw", "with zero actions, the dreamed block's yaw covers at least half of the "
       "real (unmoved) block's angle to the expert data's mean yaw, and more than the 10 degree yaw tolerance",
       control="reality")
def dream_drifts_to_data_yaw(*, dream_to_mean_deg, real_to_mean_deg, near_deg, share=DRIFT_SHARE):
    covered = real_to_mean_deg - dream_to_mean_deg
    return covered > near_deg and covered >= share * real_to_mean_deg


@claim("04.typical_pose_near_target", "the expert data's mean block pose is less than half as far "
       "from the target as the spawned blocks, in distance and in yaw")
def typical_pose_near_target(*, typical_dist, typical_yaw_deg, spawn_dist, spawn_yaw_deg):
    return typical_dist < 0.5 * spawn_dist and typical_yaw_deg < 0.5 * spawn_yaw_deg


@claim("04.reality_pays_expert", "reality pays the scripted expert's pushes more than standing still, "
       "beyond k standard errors and the minimum effect", control="zero actions")
def reality_pays_expert(*, value, se, k, min_effect):
    return _beyond(value, se, k, min_effect)


@claim("04.expert_solves_most", "the scripted expert solves at least half of the starts in reality")
def expert_solves_most(*, success_rate):
    return success_rate >= 0.5


@claim("04.dream_pays_expert", "the dream pays the scripted expert's pushes more than standing still, "
       "beyond k standard errors and the minimum effect: a learnable signal existed", control="zero actions")
def dream_pays_expert(*, value, se, k, min_effect):
    return _beyond(value, se, k, min_effect)


@claim("04.dream_penalises_expert", "the dream pays the scripted expert's pushes less than standing "
       "still, beyond k standard errors and the minimum effect", control="zero actions")
def dream_penalises_expert(*, value, se, k, min_effect):
    return _beyond(-value, se, k, min_effect)


@claim("04.real_beats_zero", "in reality the trained policy earns more per step than zero actions, "
       "beyond k standard errors and the minimum effect", control="zero actions")
def real_beats_zero(*, diff, se, k, min_effect):
    return _beyond(diff, se, k, min_effect)


@claim("04.real_worse_than_zero", "in reality the trained policy earns less per step than zero "
       "actions, beyond k standard errors and the minimum effect", control="zero actions")
def real_worse_than_zero(*, diff, se, k, min_effect):
    return _beyond(-diff, se, k, min_effect)


@claim("04.pusher_tracked_worse", "replaying the policy's real actions, the model's pusher is more "
       "than 5 mm farther off than on held-out expert clips", control="the scripted expert")
def pusher_tracked_worse(*, policy_err, expert_err, near):
    return policy_err > expert_err + near


@claim("04.pusher_tracked_worse_tested", "replaying the policy's real actions, the model's pusher is farther "
       "off than on held-out expert clips by more than k standard errors (Welch's t over the clips) and at "
       "least 5 mm", control="the scripted expert")
def pusher_tracked_worse_tested(*, diff, se, k, min_effect):
    return _beyond(diff, se, k, min_effect)


@claim("04.pusher_tracked_better_tested", "replaying the policy's real actions, the model's pusher is nearer "
       "than on held-out expert clips by more than k standard errors (Welch's t over the clips) and at least 5 mm", control="the scripted expert")
def pusher_tracked_better_tested(*, diff, se, k, min_effect):
    return _beyond(-diff, se, k, min_effect)


@claim("04.dream_ends_collapse", "the dreamed blocks' end points are less spread than the real ones', "
       "by more than 5 mm")
def dream_ends_collapse(*, dream_spread, real_spread, near):
    return dream_spread < real_spread - near


@claim("04.drift_most_every_seed", "on every seed compared, the drift is at least half of the gap", control="zero actions")
def drift_most_every_seed(*, drifts, gaps):
    return all(d >= 0.5 * g for d, g in zip(drifts, gaps))


# --- the expert control, and when it is valid (notebooks 04 and 06 register their own copies) ----------
def register_expert_control(nb: str) -> dict:
    """The claims of the expert control for notebook ``nb`` ("04", "06"): ``valid`` (the zero-action
    dream leaves an untouched block within the success tolerance, so "more than standing still" compares
    the expert with a pusher that stands still in the dream too), and the expert's own gap, which needs no
    zero-action control: ``over`` (the dream pays the expert's pushes more than reality does) and ``under``
    (less), each beyond k standard errors and the minimum effect."""
    def valid(*, moved, tol):
        return finite(moved, tol) and moved <= tol

    def over(*, value, se, k, min_effect):
        return _beyond(value, se, k, min_effect)

    def under(*, value, se, k, min_effect):
        return _beyond(-value, se, k, min_effect)

    for f, tail in ((valid, "zero_control_valid"), (over, "dream_overpays_expert"), (under, "dream_underpays_expert")):
        f.__name__ = f.__qualname__ = f"{tail}_{nb}"
    return {
        "valid": claim(f"{nb}.zero_control_valid", "with zero actions the dream moves the untouched block by at "
                       "most the success tolerance (mean over the starts of its largest displacement in the span): "
                       "the expert-minus-standing-still control is valid", control="zero actions")(valid),
        "over": claim(f"{nb}.dream_overpays_expert", "the dream pays the scripted expert's own pushes more than "
                      "reality pays them, beyond k standard errors and the minimum effect", control="reality")(over),
        "under": claim(f"{nb}.dream_underpays_expert", "the dream pays the scripted expert's own pushes less than "
                       "reality pays them, beyond k standard errors and the minimum effect", control="reality")(under),
    }


EXPERT_CONTROL = register_expert_control("04")
# The span a number was measured over, in words ("within the first 15 steps"), from a run's metrics.
SPAN_WORDS = {"train_horizon": lambda m: (f"within the first {int(m['imag_horizon'])} steps" if "imag_horizon" in m
                                          else "within the actor's training horizon"),
              "eval_horizon": lambda m: (f"over the whole evaluation ({int(m['eval_horizon'])} steps)"
                                         if "eval_horizon" in m else "over the whole evaluation")}


def expert_control_words(m: dict, span: str, k: float, claims: dict = EXPERT_CONTROL) -> tuple[bool, str]:
    """``(valid, words)``: is the expert-minus-zero-actions control valid over ``span`` (claims
    ``*.zero_control_valid``), and, valid or not, the expert's own gap in words (claims
    ``*.dream_overpays_expert``/``_underpays_expert``): the reading that needs no zero-action control. The
    expert's own gap is the drift (what the dream overpays standing still) plus the dream's expert signal
    minus reality's; where those two parts cancel, a gap near zero is said to be a cancellation."""
    where = SPAN_WORDS[span](m)
    moved = m[f"zero_dream_block_moved_{span}"]
    ok = claims["valid"](moved=moved, tol=SUCCESS_POS)
    g, gse = m[f"expert_gap_{span}"], m[f"expert_gap_se_{span}"]
    kw = dict(value=g, se=gse, k=k, min_effect=MIN_REWARD_EFFECT)
    over, under = claims["over"](**kw), claims["under"](**kw)
    head = f"the expert's own gap, what the dream pays its pushes minus what reality pays them {where}, is {g:+.3f} ± {gse:.3f} per step: "
    if over:
        own = head + "the dream pays them more than reality does, beyond the noise and the minimum effect"
    elif under:
        own = head + "the dream pays them less than reality does, beyond the noise and the minimum effect"
    else:
        own = head + "not told apart from what reality pays, by the noise and the minimum effect"
        drift = m.get(f"gap_drift_{span}")
        sig = m[f"expert_signal_dream_{span}"] - m[f"expert_signal_real_{span}"]
        if drift is not None and drift * sig < 0 and min(abs(drift), abs(sig)) >= MIN_REWARD_EFFECT:
            own += (f"; but only because two errors cancel: the dream overpays standing still by {drift:+.3f} and, "
                    f"against standing still, pays the expert's pushes {sig:+.3f} against reality's")
    if ok:
        return True, (f"With zero actions the dream moves the untouched block {moved * 100:.1f} cm at most on average "
                      f"{where} (within the {SUCCESS_POS * 100:.0f} cm success tolerance), so standing still stands "
                      f"still in the dream too and the control is valid. Beside it, {own}.")
    return False, (f"**This control is not valid on this run**: with zero actions the dream carries the untouched "
                   f"block {moved * 100:.1f} cm on average {where} (the largest displacement of each start, averaged), "
                   f"more than the {SUCCESS_POS * 100:.0f} cm success tolerance, where a real untouched block does not "
                   "move. \"More than standing still\" then compares the expert with a block the dream moves by "
                   f"itself, and cannot say whether the dream recognises success. The reading that needs no such "
                   f"control: {own}.")


def _term_args(m: dict, key: str, span: str, half: str = "") -> tuple[float, float]:
    """(value, se) of ``key`` ("imagination_gap" or "gap_<term>") over ``span``, for a half or all."""
    tag = f"_{half}" if half else ""
    return m[f"{key}{tag}_{span}"], m[f"{key}_se{tag}_{span}"]


# --- Exercise 1 ---------------------------------------------------------------------------------
EX1_OPTIONS = {
    "a": "It transfers: real successes appear, more of them than a pusher that never moves gets by chance.",
    "b": "No real success beyond chance, and the dream rates the trained policy well above reality; the rosy "
         "part comes with the actor's actions (a pusher that never moves would be rated about as "
         "reality rates it).",
    "c": "No real success beyond chance, and the dream rates the trained policy well above reality; but it is "
         "rosy even for a pusher that never moves (zero actions already get at least half of the "
         "trained policy's gap).",
    "d": "No real success beyond chance, and the dream is no rosier than reality.",
}


def clearly_positive(value: float, se: float, k: float = K_SE) -> bool:
    """``value`` exceeds ``k`` standard errors (``se`` measured on the same starts) and the minimum
    effect that matters (a registered claim, ``04.term_positive``)."""
    return term_positive(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT)


def reading(value: float, se: float, k: float = K_SE, what: str = "") -> str:
    """"up" or "down" (beyond ``k`` standard errors and at least the minimum effect), "small"
    (beyond k standard errors, but smaller than the minimum effect that matters) or "none" (within
    the noise), decided by registered claims (``04.term_positive``, ``04.term_negative``,
    ``04.term_beyond_noise``)."""
    if term_positive(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT, what=what):
        return "up"
    if term_negative(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT, what=what):
        return "down"
    if term_beyond_noise(value=value, se=se, k=k, what=what):
        return "small"
    return "none"


def _two(ratio: float, k: float) -> tuple[str, str]:
    """``ratio`` and ``k`` printed with the fewest decimals (2 to 4) that keep them apart."""
    for d in (2, 3, 4):
        a, b = f"{ratio:.{d}f}", f"{k:.{d}f}"
        if a != b:
            break
    return a, b


def _ratio(value: float, se: float, k: float = K_SE) -> str:
    """|value| in standard errors, printed so that it never looks equal to ``k``."""
    return _two(abs(value) / se, k)[0] if se > 0 else "many"


def ex1_verdict(metrics: list[dict], n: int | None = None) -> str:
    """Exercise 1's measured outcome (a letter of ``EX1_OPTIONS``) from each seed's evaluation
    metrics (``two_world_eval`` with ``train_horizon``), decided by registered claims. Decided on
    the whole evaluation, the deployed 10 s that the question is about; "well above" means beyond
    k standard errors of the per-start gaps (:func:`k_se`, from ``n`` or each metrics'
    ``eval_episodes``) and at least ``MIN_REWARD_EFFECT``; a mixed result across seeds is decided
    on the seeds' means."""
    # a lone success is an event, not a transfer: (a) needs more real successes than standing still gets,
    # beyond chance, on some seed; the successes are counted either way (and the reconciliation prints them)
    real_success(success_rates=[m["real_success_rate"] for m in metrics])
    ns = [int(m.get("eval_episodes", n or DEFAULT_STARTS)) for m in metrics]
    if real_success_beyond_chance(trained=[round(m["real_success_rate"] * k) for m, k in zip(metrics, ns)],
                                  zero=[round(m["zero_action_real_success_rate"] * k) for m, k in zip(metrics, ns)],
                                  n=ns, bar=COUNT_P):
        return "a"
    if not all([gap_rosy(gap=m["imagination_gap"], se=m["imagination_gap_se_eval_horizon"], k=_k(m, n),
                         min_effect=MIN_REWARD_EFFECT) for m in metrics]):
        return "d"
    zero_rosy = [drift_half_of_gap(drift=m["gap_drift_eval_horizon"], se=m["gap_drift_se_eval_horizon"],
                                   gap=m["imagination_gap"], k=_k(m, n), min_effect=MIN_REWARD_EFFECT)
                 for m in metrics]
    # evaluated on every run (so the claim is recorded), though it decides only a mixed result
    on_means = drift_half_on_means(drifts=[m["gap_drift_eval_horizon"] for m in metrics],
                                   gaps=[m["imagination_gap"] for m in metrics])
    if all(zero_rosy):
        return "c"
    if not any(zero_rosy):
        return "b"
    return "c" if on_means else "b"


def ex1_sentence(seed: int, m: dict, n_eval: int) -> str:
    won, zero = round(m["real_success_rate"] * n_eval), round(m["zero_action_real_success_rate"] * n_eval)
    p = count_rise_p(zero, won, n_eval)
    chance = ("" if won == 0 else f" (a pusher that never moves: {zero}/{n_eval}; Fisher's exact one-sided p = "
              f"{p:.3f}, " + ("beyond chance" if p < COUNT_P else f"not beyond chance at {COUNT_P:.3f}") + ")")
    return (f"Seed {seed}: deployed, the policy earns {m['imagined_return_per_step']:+.3f} per step in the dream "
            f"and {m['real_return_per_step']:+.3f} in reality (gap {m['imagination_gap']:+.3f} ± "
            f"{m['imagination_gap_se_eval_horizon']:.3f}); with zero actions the dream is "
            f"{m['gap_drift_eval_horizon']:+.3f} ± {m['gap_drift_se_eval_horizon']:.3f} rosier than reality; "
            f"{won}/{n_eval} real successes{chance}.")


def ex1_note(n: int | None = None) -> str:
    """What the ± and "well above" of the reconciliation mean."""
    return f"(± is one standard error over the starts; 'well above' means {test_words(k_se(n))}.)"


def ex1_reconciliation(metrics: dict, n_eval: int) -> tuple[str, str]:
    """Exercise 1's reconciliation, ``(measured letter, explanation)``, as notebook 04 hands them to
    ``pusht.predict.reconcile``: from ``{seed: evaluation metrics}`` (``two_world_eval``'s, with
    ``eval_episodes``) for the ``n_eval`` starts. One function, so that the notebook and
    ``python -m pusht.exercise ex1`` print the same words."""
    # the letter turns on "the drift is at least half the gap": its margin, per seed, in the drift's own
    # standard errors (drift minus half the gap, against k)
    diffs = [m["gap_drift_minus_half_gap_eval_horizon"] for m in metrics.values()]
    ses = [m["gap_drift_minus_half_gap_se_eval_horizon"] for m in metrics.values()]
    ks = [_k(m, n_eval) for m in metrics.values()]
    decided = ex1_letter_decided(diffs=diffs, ses=ses, ks=ks)
    margins = "; ".join(f"seed {s}: |t| = {abs(d) / se:.2f} against k = {k:.2f}"
                        for s, d, se, k in zip(metrics, diffs, ses, ks))
    return (ex1_verdict(list(metrics.values())),
            "\n".join(ex1_sentence(s, m, n_eval) for s, m in metrics.items()) + "\n" + ex1_note(n_eval)
            + "\nThe letter's margin (the drift minus half the gap, start by start, in its own standard errors): "
            + margins
            + (": decided beyond the noise on every seed." if decided else
               ": on some seed the drift is within the noise of half the gap, so that seed does not decide the "
               "letter beyond the noise."))


def dream_check_text(mismatch: float) -> str:
    """Does the learner's ``dream`` reproduce the package's imagined reward?"""
    if dream_reproduces_package(mismatch=mismatch):
        return f"Your `dream` reproduces the package's imagined reward per step to within **{mismatch:.1e}**."
    return (f"**Careful:** your `dream` gives imagined rewards that differ from the package's by {mismatch:.3g} "
            "per step; the figures below use yours, so re-check the task above.")


def exploitation_text(metrics: dict, H: int, n: int | None = None) -> str:
    """After the reconciliation: what each seed's run shows about the question "what has the actor
    become good at": the training term within the ``H`` steps its gradient saw (a claim)."""
    lines = []
    k = None
    for seed, m in metrics.items():
        k = _k(m, n)
        v, se = m["gap_training_train_horizon"], m["gap_training_se_train_horizon"]
        if training_exploits(value=v, se=se, k=k, min_effect=MIN_REWARD_EFFECT):
            verdict = ("training made the dream rosier than it made reality: the actor learned something "
                       "only the dream pays for")
        else:
            r = reading(v, se, k, f"training train_horizon seed {seed}")
            verdict = {
                "down": "training made the dream *gloomier* than it made reality, beyond the noise and the "
                        "minimum effect: this actor did not exploit its dream",
                "small": f"that is beyond the noise ({_ratio(v, se, k)} standard errors) but smaller than the minimum "
                         "effect that matters, so it is not read as exploitation: this actor did not measurably "
                         "exploit its dream",
                "none": "that is within the noise: training did not make the dream measurably rosier than "
                        "reality, and this actor did not measurably exploit its dream",
            }["none" if r == "up" else r].replace("this actor did", f"within those {H} steps this actor did")
            ve, vse = m["gap_training_eval_horizon"], m["gap_training_se_eval_horizon"]
            if training_exploits_eval(value=ve, se=vse, k=k, min_effect=MIN_REWARD_EFFECT):
                verdict += (f"; over the whole evaluation, though, training's part is {ve:+.3f} ± {vse:.3f}, clearly "
                            "positive: past the steps its gradient saw, the trained actor's dream is rosier against "
                            "reality than the untrained one's")
        lines.append(f"* seed {seed}: within the first {H} steps, training's part of the gap is "
                     f"**{v:+.3f}** ± {se:.3f} per step; {verdict}.")
    return ("**What your run shows.** Whether the actor exploited its dream is measured by the *training* "
            "term of the gap (taken apart below): what training added in the dream beyond what it added in "
            f"reality, over the {H} steps the actor's gradient saw. It counts when it is "
            f"{test_words(k if k is not None else k_se(n))}.\n\n" + "\n".join(lines))


# --- the headline and one start ------------------------------------------------------------------
def headline_text(m: dict, n_dream_solved: int, n_real_solved: int, n_eval: int, page: dict | None = None) -> str:
    """The two-worlds headline in words (and the chapter page's numbers, quoted, when given)."""
    s = (f"In the dream the policy earns **{m['imagined_return_per_step']:+.3f}** per step; in reality "
         f"**{m['real_return_per_step']:+.3f}**, a gap of **{m['imagination_gap']:+.3f}**. The dream leaves "
         f"the block **{m['imagined_final_tee_dist']:.3f} m** from the target on average, with a yaw error of "
         f"**{m['trained_dream_final_yaw_err_deg']:.0f}°**, and by the environment's own thresholds it would "
         f"call **{n_dream_solved}/{n_eval}** starts solved. In reality the block ends **{m['real_final_tee_dist']:.3f} m** "
         f"away with a yaw error of **{m['trained_real_final_yaw_err_deg']:.0f}°** (it spawned "
         f"**{m['spawn_tee_dist']:.3f} m** away), and **{n_real_solved}/{n_eval}** starts are solved.")
    if page:
        s += (f"\n\nFor comparison, the chapter page reports for its seed 0 an imagined "
              f"{page['imagined_return_per_step']['seed0']:+.3f} against a real {page['real_return_per_step']['seed0']:+.3f} "
              f"per step (gap {page['imagination_gap']['seed0']:+.3f}), a dream block "
              f"{page['imagined_final_tee_dist']['seed0']:.3f} m from the target and a real one "
              f"{page['real_final_tee_dist']['seed0']:.3f} m away, with {page['real_success_rate']['seed0']:.0%} real "
              "success. Those are the page's own numbers, quoted: not reproduced by this notebook.")
    return s


def median_start(dream_roll, real_roll) -> int:
    """The start whose dream-minus-real final distance is the median one: a typical start."""
    d = dream_roll.final_tee_dist - real_roll.final_tee_dist
    return int(np.argsort(d)[len(d) // 2])


def median_start_text(i: int, dream_roll, real_roll) -> str:
    """Where start ``i`` ends in both worlds: distance and yaw error, against where it spawned."""
    _, tee0 = obs_to_pose(real_roll.obs[0, i])
    return (f"Start {i} (the median start): the dream ends with the block **{dream_roll.final_tee_dist[i]:.3f} m** "
            f"from the target at a yaw error of **{dream_roll.final_yaw_err[i]:.0f}°**; reality ends with it "
            f"**{real_roll.final_tee_dist[i]:.3f} m** away at **{real_roll.final_yaw_err[i]:.0f}°** (it spawned "
            f"{np.linalg.norm(tee0[:2]):.3f} m away at {abs(np.degrees(tee0[2])):.0f}°).")


# --- reading the split of the gap ----------------------------------------------------------------
def describe(value: float, se: float, what: str = "", k: float = K_SE) -> str:
    """A term in words, judged against its own standard error and the minimum effect that matters
    (:func:`reading`)."""
    return {"up": "clearly positive", "down": "clearly negative",
            "small": "beyond the noise but smaller than the minimum effect that matters",
            "none": "not told apart from zero"}[reading(value, se, k, what)]


def half_difference_se(rollouts: dict, steps: int | None) -> float:
    """The standard error over the starts of the gap's yaw half minus its position half, over the
    first ``steps`` steps (all for None): both halves are measured on the same starts, so the
    difference is a mean of per-start differences."""
    from ..split import per_start, se

    def half(part):
        return per_start(rollouts["dream_trained"], steps, part) - per_start(rollouts["real_trained"], steps, part)

    x = half("yaw") - half("position")
    return se(x[~np.isnan(x)])


def dominant_half(m: dict, span: str, se_diff: float | None = None, k: float | None = None) -> str | None:
    """"position" or "yaw" when that half of the gap over ``span`` is positive and the larger one by
    more than k standard errors of the two halves' difference, ``se_diff`` (per start,
    :func:`half_difference_se`; without it, the sum of the halves' own standard errors, a
    conservative bound), and the minimum effect; None when neither is (claim ``04.half_dominates``)."""
    (p, pse), (y, yse) = (_term_args(m, "imagination_gap", span, h) for h in HALVES)
    se = pse + yse if se_diff is None else se_diff
    k = _k(m) if k is None else k
    for which, a, b in (("yaw", y, p), ("position", p, y)):
        if a >= b and half_dominates(larger=a, smaller=b, se_diff=se, k=k, min_effect=MIN_REWARD_EFFECT,
                                     which=f"{span} {which}"):
            return which
    return None


def dominance_sentence(m: dict, span: str, se_diff: float | None = None, k: float | None = None) -> str:
    """Which half of the gap is the larger on this run, in words; when neither is, which condition
    failed (the larger half not positive, the difference within the noise, or under the minimum
    effect)."""
    (p, pse), (y, yse) = (_term_args(m, "imagination_gap", span, h) for h in HALVES)
    k = _k(m) if k is None else k
    which = dominant_half(m, span, se_diff, k)
    name = "gap"
    se = pse + yse if se_diff is None else se_diff
    kind = ("its standard error over the starts" if se_diff is not None else
            "a conservative bound on its standard error (the sum of the halves' standard errors)")
    noise = (f"{se:.3f}, its standard error over the starts" if se_diff is not None else
             f"{se:.3f}, the sum of the halves' standard errors, a conservative bound")
    total = m[f"imagination_gap_{span}"]
    shares = (f", that is {p / total:.0%} and {y / total:.0%} of the {name}"
              if p > 0 and y > 0 and total > 0 else "")
    if which is None:
        big, a, b = ("yaw", y, p) if y >= p else ("position", p, y)
        d = a - b
        clear, enough = beyond(d, se, k), d >= MIN_REWARD_EFFECT
        if a <= 0:
            why = f"the larger half, {big}, is not positive"
        elif not clear and not enough:
            why = (f"their difference, {d:.3f}, is neither beyond {k:.2f} times {kind}, {se:.3f}, "
                   f"nor as large as the minimum effect {MIN_REWARD_EFFECT:.2f}")
        elif not clear:
            why = (f"their difference, {d:.3f}, is within the noise: not beyond {k:.2f} times {kind}, "
                   f"{se:.3f}")
        else:
            why = (f"their difference, {d:.3f}, is beyond {k:.2f} times {kind}, {se:.3f}, but "
                   f"smaller than the minimum effect that matters, {MIN_REWARD_EFFECT:.2f}")
        return (f"Neither half of the {name} stands out as the larger, positive part (position {p:+.3f}, yaw "
                f"{y:+.3f}{shares}): {why}.")
    other = "position" if which == "yaw" else "yaw"
    a, b = (y, p) if which == "yaw" else (p, y)
    what = "the block's *orientation* (its yaw)" if which == "yaw" else "the block's *position*"
    return (f"Most of the {name} is in its **{which}** half: {a:+.3f} against {b:+.3f} from {other} "
            f"(the difference is beyond {k:.2f} times {noise}, and at least {MIN_REWARD_EFFECT:.2f}): "
            f"on this run the dream flatters {what} more than its {other}.")


def split_sentence(m: dict, span: str, steps: int, rollouts: dict | None = None, n: int | None = None) -> str:
    """The gap and its three terms over ``span`` ("train_horizon" or "eval_horizon"), each with
    its position and yaw halves, and which half of the gap is the larger (judged on the per-start
    difference of the halves when the run's ``rollouts`` are given)."""
    k = _k(m, n)
    gap, gse = m[f"imagination_gap_{span}"], m[f"imagination_gap_se_{span}"]
    rosy = gap_rosy(gap=gap, se=gse, k=k, min_effect=MIN_REWARD_EFFECT)

    def halves(key):
        (p, _), (y, _) = (_term_args(m, key, span, h) for h in HALVES)
        return f"position {p:+.3f}, yaw {y:+.3f}"

    parts = []
    for term, label in TERMS.items():
        v, se = m[f"gap_{term}_{span}"], m[f"gap_{term}_se_{span}"]
        share = f", {v / gap:.0%} of the gap" if rosy else ""
        parts.append(f"{label} **{v:+.3f}** ± {se:.3f} ({halves(f'gap_{term}')}; "
                     f"{describe(v, se, f'{term} {span}', k)}{share})")
    return (f"Over the first **{steps} steps** ({SPANS[span]}) the gap is **{gap:+.3f}** ± {gse:.3f} per step "
            f"({halves('imagination_gap')}): " + "; ".join(parts) + ". "
            + dominance_sentence(m, span, None if rollouts is None else half_difference_se(
                rollouts, steps if span == "train_horizon" else None), k))


def after_horizon_training(rollouts: dict, H: int) -> tuple[float, float, int]:
    """Training's part of the gap over the steps AFTER the first ``H`` (the ones the actor's gradient
    never saw), per start: (mean, standard error over the starts, number of starts)."""
    def seg(key):
        r = np.asarray(rollouts[key].rewards, dtype=float)[H:]
        return np.nanmean(r, axis=0) if len(r) else np.full(r.shape[1], np.nan)
    x = (seg("dream_trained") - seg("dream_untrained")) - (seg("real_trained") - seg("real_untrained"))
    x = x[~np.isnan(x)]
    se = float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")
    return (float(x.mean()) if len(x) else float("nan")), se, int(len(x))


def split_story(m: dict, H: int, rollouts: dict | None = None, n: int | None = None) -> str:
    """What the two horizons say together about drift and exploitation (registered claims). With
    the run's ``rollouts``, training's part over the steps after the training horizon is measured
    on its own (:func:`after_horizon_training`)."""
    k = _k(m, n)
    words = test_words(k)
    tr_h, tr_e = m["gap_training_train_horizon"], m["gap_training_eval_horizon"]
    se_h, se_e = m["gap_training_se_train_horizon"], m["gap_training_se_eval_horizon"]
    drift_h, drift_se = m["gap_drift_train_horizon"], m["gap_drift_se_train_horizon"]
    s = ""
    exploits_h = training_exploits(value=tr_h, se=se_h, k=k, min_effect=MIN_REWARD_EFFECT)
    if exploits_h:
        gap_h = m["imagination_gap_train_horizon"]
        share = f", {tr_h / gap_h:.0%} of the gap over those steps" if gap_h > 0 else ""
        s += (f"Within the {H} steps its gradient saw, training made the dream rosier than it made reality "
              f"by {tr_h:+.3f} ± {se_h:.3f} per step ({words}{share}): that part the actor "
              "learned and only the dream pays for, which is exploitation. ")
    else:
        r = reading(tr_h, se_h, k, "training train_horizon, story")
        s += f"Within the {H} steps its gradient saw, training's part is {tr_h:+.3f} ± {se_h:.3f} per step: " + {
            "down": "training made the dream *gloomier* than it made reality, beyond the noise and the minimum "
                    "effect, so on this seed the actor did not exploit its dream. ",
            "small": f"beyond the noise ({_ratio(tr_h, se_h, k)} standard errors) but smaller than the minimum effect "
                     f"that matters, so it is not read as exploitation: within those {H} steps the actor did not "
                     "measurably exploit its dream. ",
            "none": f"within the noise (it would count when {words}): training did not make the dream measurably "
                    f"rosier than reality, and within those {H} steps the actor did not measurably exploit its dream. ",
            "up": ""}[r]
    exploits_e = training_exploits_eval(value=tr_e, se=se_e, k=k, min_effect=MIN_REWARD_EFFECT)
    re_ = "up" if exploits_e else reading(tr_e, se_e, k, "training eval_horizon, story")
    whole = f"Over the whole evaluation training's part is {tr_e:+.3f} ± {se_e:.3f}"
    if exploits_h:
        s += whole + {
            "up": ", still clearly positive: the actor's advantage in the dream lasts past its training horizon. ",
            "down": ": that advantage is reversed (clearly negative): over the whole run the trained actor's dream "
                    "is gloomier, against reality, than the untrained one's. ",
            "small": (": that advantage is gone from the whole run's mean, which is beyond the noise but smaller "
                      "than the minimum effect" + (" and below zero. " if tr_e < 0 else ". ")),
            "none": (": that advantage is not told apart from zero over the whole run (within the noise)"
                     + (", though its point value is at least the minimum effect: not resolved, which is not the "
                        "same as gone. " if abs(tr_e) >= MIN_REWARD_EFFECT else
                        ", and smaller than the minimum effect: it does not last. "))}[re_]
    elif exploits_e:
        s += whole + (", clearly positive: the trained actor's dream turns rosy only after the steps its gradient "
                      "saw. ")
    else:
        s += whole + " (" + describe(tr_e, se_e, "training eval_horizon, story (again)", k) + "). "
    if rollouts is not None and len(rollouts["dream_trained"].rewards) > H:
        v, se, _ = after_horizon_training(rollouts, H)
        ra = reading(v, se, k, "training after the training horizon")
        T = len(rollouts["dream_trained"].rewards)
        s += f"Over the steps its gradient never saw (steps {H + 1} to {T}) alone, training's part is {v:+.3f} ± {se:.3f}: " + {
            "up": "clearly positive, so there too the trained actor's dream is rosier, against reality, than the "
                  "untrained one's. ",
            "down": "clearly negative, so past its training horizon the trained actor's dream is *gloomier*, against "
                    "reality, than the untrained one's" + (": the advantage it learned within its horizon is "
                                                           "reversed after it. " if exploits_h else ". "),
            "small": ("beyond the noise but smaller than the minimum effect that matters: past its training horizon "
                      "the trained actor's dream is slightly " + ("gloomier" if v < 0 else "rosier")
                      + ", against reality, than the untrained one's, by less than matters. "),
            "none": "within the noise: past its training horizon this run cannot tell the trained actor's dream, "
                    "against reality, from the untrained one's. "}[ra]
    rd = "up" if drift_rosy(value=drift_h, se=drift_se, k=k, min_effect=MIN_REWARD_EFFECT) else \
        reading(drift_h, drift_se, k, "drift train_horizon, story")
    if rd == "up":
        s += (f"The drift, the model's own optimism with the pusher standing still, is {drift_h:+.3f} ± "
              f"{drift_se:.3f} per step already over the first {H} steps.")
    elif rd == "small":
        s += (f"With the pusher standing still, the dream differs from reality over the first {H} steps by "
              f"{drift_h:+.3f} ± {drift_se:.3f}: beyond the noise, but smaller than the minimum effect that "
              "matters, so it is not measurably rosier than reality over those steps.")
    elif rd == "down":
        s += (f"With the pusher standing still, the dream is *gloomier* than reality over the first {H} steps "
              f"({drift_h:+.3f} ± {drift_se:.3f}), not measurably rosier than reality over those steps.")
    else:
        s += (f"With the pusher standing still, the dream is not measurably rosier than reality over the "
              f"first {H} steps ({drift_h:+.3f} ± {drift_se:.3f}, within the noise).")
    return s


def min_of_mean_distance(rollout, dt: float = 0.1) -> tuple[float, float]:
    """(smallest mean block-to-target distance over time in m, the time in s it happens)."""
    d = np.linalg.norm(rollout.obs[:, :, 2:4], axis=-1).mean(1)
    i = int(np.argmin(d))
    return float(d[i]), i * dt


def typical_pose(data_mean) -> tuple[float, float]:
    """(distance to the target in m, |yaw error| in degrees) of the expert data's mean observation
    (``data.mean``, metres): the block pose a model that has lost track of it decodes nearest to
    (the normalised zero). The yaw is read off the mean (sin, cos) as the reward reads it."""
    data_mean = np.asarray(data_mean, dtype=float)
    return (float(np.linalg.norm(data_mean[2:4])),
            float(abs(np.degrees(np.arctan2(data_mean[4], data_mean[5])))))


def _yaw_deg(obs) -> np.ndarray:
    _, tee = obs_to_pose(obs)
    return np.degrees(tee[..., 2])


def dip_sentence(rollouts: dict, H: int, data_mean=None, dt: float = 0.1) -> str:
    """Read the over-time panels: where and when the trained dream's block comes closest, and
    whether, with nobody pushing, the dreamed block drifts toward the expert data's typical pose
    (in position and in yaw), and whether that pose is near the target (registered claims).

    Notebooks of an older release call it without ``data_mean``: they get the first part only."""
    d_min, t_min = min_of_mean_distance(rollouts["dream_trained"], dt)
    z_min, z_t = min_of_mean_distance(rollouts["dream_zero"], dt)
    end = float(np.linalg.norm(rollouts["dream_trained"].obs[-1, :, 2:4], axis=-1).mean())
    where = (f"inside the {H * dt:.1f} s the actor trained on" if t_min <= H * dt
             else f"after the {H * dt:.1f} s the actor trained on")
    s = (f"In the trained actor's dream the mean block distance is smallest, **{d_min:.3f} m**, at "
         f"**{t_min:.1f} s** ({where}), and ends the evaluation at **{end:.3f} m**; the zero-action "
         f"dream's smallest is {z_min:.3f} m at {z_t:.1f} s. ")
    if dream_block_drifts_back(t_min=t_min, horizon_s=H * dt, d_min=d_min, d_end=end, near=NEAR):
        s += "After its best moment the trained dream's block drifts back out. "
    if zero_dream_closer(zero_min=z_min, trained_min=d_min, near=NEAR):
        yt = float(np.abs(_yaw_deg(rollouts["dream_trained"].obs[-1])).mean())
        yz = float(np.abs(_yaw_deg(rollouts["dream_zero"].obs[-1])).mean())
        s += ("In distance, a pusher that never moves gets the dreamed block closer to the target than the trained "
              "actor does: the model's drift, not the actor, brings the dreamed block nearest the target's place. "
              f"Distance is half the reward: at the end the trained dream's T is {yt:.0f}° off the target angle, "
              f"the zero-action dream's {yz:.0f}°. ")
    if data_mean is None:
        return s
    # where does a dream with nobody pushing take the block? Toward the data's typical pose?
    data_mean = np.asarray(data_mean, dtype=float)
    t_dist, t_yaw = typical_pose(data_mean)
    mean_yaw = float(np.degrees(np.arctan2(data_mean[4], data_mean[5])))
    dz, rz = rollouts["dream_zero"].obs[-1], rollouts["real_zero"].obs[-1]
    dream_to = float(np.linalg.norm(dz[:, 2:4] - data_mean[2:4], axis=-1).mean())
    real_to = float(np.linalg.norm(rz[:, 2:4] - data_mean[2:4], axis=-1).mean())
    wrap = lambda a: np.abs((a - mean_yaw + 180.0) % 360.0 - 180.0)  # noqa: E731
    dream_yaw_to, real_yaw_to = float(wrap(_yaw_deg(dz)).mean()), float(wrap(_yaw_deg(rz)).mean())
    dz_err, rz_err = float(np.abs(_yaw_deg(dz)).mean()), float(np.abs(_yaw_deg(rz)).mean())
    s += (f"The expert data's mean block pose sits **{t_dist:.3f} m** from the target with a yaw error of "
          f"**{t_yaw:.0f}°**. With zero actions the real block stays where it spawned, "
          f"{float(rollouts['real_zero'].final_tee_dist.mean()):.3f} m from the target at {rz_err:.0f}° (means "
          f"over the starts); the dreamed one ends {float(rollouts['dream_zero'].final_tee_dist.mean()):.3f} m "
          f"away at {dz_err:.0f}°. ")
    pos = dream_drifts_to_data_position(dream_to_mean=dream_to, real_to_mean=real_to, near=SUCCESS_POS)
    yaw = dream_drifts_to_data_yaw(dream_to_mean_deg=dream_yaw_to, real_to_mean_deg=real_yaw_to, near_deg=NEAR_DEG)
    share = lambda a, b: f"{max(0.0, 1 - a / b):.0%} of the way" if b > 0 else "all the way"  # noqa: E731
    where_pos = (f"its position ends {dream_to:.3f} m from the data's mean block position, against "
                 f"{real_to:.3f} m for the real block ({share(dream_to, real_to)})")
    where_yaw = (f"its yaw ends {dream_yaw_to:.0f}° from the data's mean yaw, against {real_yaw_to:.0f}° "
                 f"for the real block ({share(dream_yaw_to, real_yaw_to)})")
    rule = (f"\"toward\" meaning at least {DRIFT_SHARE:.0%} of the way and more than the "
            f"{SUCCESS_POS * 100:.0f} cm / {NEAR_DEG:.0f}° success tolerances")
    if pos and yaw:
        s += (f"Left alone, the dreamed block drifts toward the data's typical pose, in position and in yaw ({rule}): "
              f"{where_pos}, and {where_yaw}. A model that loses track of the block decodes it somewhere typical. ")
    elif pos or yaw:
        moved, stayed = ("position", "yaw") if pos else ("yaw", "position")
        s += (f"Left alone, the dreamed block drifts toward the data's typical {moved} "
              f"({where_pos if pos else where_yaw}) but not toward its typical {stayed} "
              f"({where_yaw if pos else where_pos}; {rule}). ")
    else:
        s += (f"The dreamed block does not drift toward the data's typical pose ({rule}): {where_pos}, and "
              f"{where_yaw}; its drift goes somewhere else. ")
    if pos or yaw:
        spawn_dist = float(rollouts["real_zero"].final_tee_dist.mean())
        if typical_pose_near_target(typical_dist=t_dist, typical_yaw_deg=t_yaw, spawn_dist=spawn_dist,
                                    spawn_yaw_deg=rz_err):
            s += ("And that typical pose is near the target (less than half as far as the spawned blocks, "
                  "in distance and in yaw), so a drift toward it reads as progress in the dream.")
        else:
            s += ("That typical pose is not near the target by this measure (less than half as far as the "
                  "spawned blocks, in distance and in yaw), so the drift toward it is not, by itself, why "
                  "the dream is rosy.")
    return s


# --- the expert control ---------------------------------------------------------------------------
def expert_text(m: dict, steps: dict, n: int | None = None) -> str:
    """Could the dream recognise success? The scripted expert's pushes against zero actions, in each
    world, over both spans (registered claims); the actor's question is decided on the training
    horizon, the dreams its gradient saw."""
    k = _k(m, n)

    def sig(world, span, half=""):
        tag = f"_{half}" if half else ""
        return m[f"expert_signal{tag}_{world}_{span}"], m[f"expert_signal{tag}_{world}_se_{span}"]

    H = steps["train_horizon"]
    solves = expert_solves_most(success_rate=m["expert_real_success_rate"])
    pushes = "the pushes that solve the task" if solves else "the expert's pushes"
    s = (f"The scripted expert solves **{m['expert_real_success_rate']:.0%}** of these starts in reality"
         + ("" if solves else " (fewer than half: on this evaluation its pushes are not, mostly, solutions)")
         + ". Its pushes against a pusher that never moves, per step (± one standard error over the starts):\n\n")
    for span in SPANS:
        (rv, rse), (dv, dse) = sig("real", span), sig("dream", span)
        s += (f"* first {steps[span]} steps ({SPANS[span]}): reality pays them **{rv:+.3f}** ± {rse:.3f} "
              f"(position {sig('real', span, 'position')[0]:+.3f}, yaw {sig('real', span, 'yaw')[0]:+.3f}); the dream, "
              f"replaying the very same actions from the same starts, **{dv:+.3f}** ± {dse:.3f} (position "
              f"{sig('dream', span, 'position')[0]:+.3f}, yaw {sig('dream', span, 'yaw')[0]:+.3f}).\n")
    rv, rse = sig("real", "train_horizon")
    dv, dse = sig("dream", "train_horizon")
    s += "\n"
    if reality_pays_expert(value=rv, se=rse, k=k, min_effect=MIN_REWARD_EFFECT):
        s += f"Within the first {H} steps reality rewards {pushes} over standing still. "
    elif reading(rv, rse, k, "expert real train_horizon") == "small":
        s += (f"Within the first {H} steps reality's difference is beyond the noise but smaller than the minimum "
              "effect that matters: even reality does not reward the expert's pushes over standing still by "
              "enough to count; those steps are too few to tell success apart. ")
    else:
        s += (f"Within the first {H} steps even reality does not reward the expert's pushes over standing still "
              "beyond the noise and the minimum effect: those steps are too few to tell success apart. ")
    valid, control = expert_control_words(m, "train_horizon", k)
    pays = dream_pays_expert(value=dv, se=dse, k=k, min_effect=MIN_REWARD_EFFECT)
    penalises = dream_penalises_expert(value=dv, se=dse, k=k, min_effect=MIN_REWARD_EFFECT)
    small = not pays and not penalises and reading(dv, dse, k, "expert dream train_horizon") == "small"
    if not valid:
        s += (f"In the dream the expert's pushes minus zero actions read {dv:+.3f} ± {dse:.3f} per step over the "
              f"first {H} steps. {control}")
    elif pays:
        s += ("**The dream does too**" + (": it can recognise success." if solves else ".")
              + " An actor that pushed the way the expert pushes would have been paid for it in its training "
              f"dreams: a learnable signal existed. {control}")
    elif penalises:
        s += ("**The dream pays the expert's pushes less than standing still.** An actor that copied the expert "
              "exactly would have scored *worse* in its training dreams than one that never moved: the dream's "
              f"reward did not lead toward {pushes}, so imitating the expert was never what it asked for. {control}")
    elif small:
        s += ("**The dream does not tell the expert's pushes apart from standing still by enough to matter**: its "
              f"difference is beyond the noise, but {'above' if dv > 0 else 'below'} zero by less than the minimum "
              f"effect that matters. The signal an actor would need to learn the task is too small to count. {control}")
    else:
        s += ("**The dream does not tell the expert's pushes apart from standing still** (within the noise): "
              f"the signal an actor would need to learn the task is not there. {control}")
    s += f" (Each verdict: {test_words(k)}.)"
    return s


# --- what the policy did in reality ---------------------------------------------------------------
def real_vs_zero(rollouts: dict) -> tuple[float, float]:
    """(mean, standard error) over the starts of the trained policy's real reward per step minus
    that of zero actions, on the same starts."""
    x = rollouts["real_trained"].return_per_step - rollouts["real_zero"].return_per_step
    x = x[~np.isnan(x)]
    return float(x.mean()), float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")


def pusher_paths_text(m: dict, rollouts: dict, n_eval: int, touch_tol: float) -> str:
    """What the policy did to the real block: its reward against zero actions (claims: clearly
    better, clearly worse, beyond the noise but under the minimum effect, within the noise), contact,
    and how far the block moved."""
    diff, se = real_vs_zero(rollouts)
    x = rollouts["real_trained"].return_per_step - rollouts["real_zero"].return_per_step
    k = k_se(int(np.sum(~np.isnan(x))))
    r_t = float(np.nanmean(rollouts["real_trained"].return_per_step))
    r_z = float(np.nanmean(rollouts["real_zero"].return_per_step))
    s = (f"In reality the trained policy earns **{r_t:+.3f}** per step; a pusher that never moves earns "
         f"**{r_z:+.3f}** from the same starts (difference {diff:+.3f} ± {se:.3f}"
         + (f", {_ratio(diff, se, k)} standard errors). " if se > 0 else "). "))
    if real_beats_zero(diff=diff, se=se, k=k, min_effect=MIN_REWARD_EFFECT):
        s += "So the trained policy does clearly better in reality than standing still. "
    elif real_worse_than_zero(diff=diff, se=se, k=k, min_effect=MIN_REWARD_EFFECT):
        s += "So the trained policy does clearly *worse* in reality than standing still: its pushes cost reward. "
    elif term_beyond_noise(value=diff, se=se, k=k, what="real trained minus zero actions"):
        s += (f"The noise does not explain that difference (it is beyond k = {_two(abs(diff) / se, k)[1]} standard "
              "errors), but it is smaller "
              f"than the minimum effect that matters, {MIN_REWARD_EFFECT:.2f} per step: the trained policy earns "
              f"slightly {'more' if diff > 0 else 'less'} than standing still, by less than the reward of holding the "
              "block 2 cm nearer the target. Detected, but too small to count as doing "
              f"{'better' if diff > 0 else 'worse'}. ")
    else:
        s += ("That is within the noise: in reality this run cannot tell the trained policy from standing still, "
              "by the reward's account. ")
    s += (f"(A difference counts when it is {test_words(k)}.) The pusher's rim came within {100 * touch_tol:.1f} cm "
          f"of the block in **{m['real_episodes_touching_block']}/{n_eval}** starts; on average its closest approach "
          f"was **{100 * m['real_pusher_min_gap']:.1f} cm**, and the real block moved **{m['real_block_displacement']:.3f} m** "
          f"on average (at most {m['real_block_displacement_max']:.3f} m).")
    return s


def company_text(m: dict, H: int, n: int | None = None) -> str:
    """After "good company": whether this run's gap is exploitation or the dream's own drift."""
    k = _k(m, n)
    tr, tse = m["gap_training_train_horizon"], m["gap_training_se_train_horizon"]
    dr, dse = m["gap_drift_train_horizon"], m["gap_drift_se_train_horizon"]
    if training_exploits(value=tr, se=tse, k=k, min_effect=MIN_REWARD_EFFECT):
        s = (f"**On your run** the actor did exploit its dream: within the {H} steps its gradient saw, training "
             f"made the dream rosier than reality by {tr:+.3f} ± {tse:.3f} per step. ")
    else:
        r = reading(tr, tse, k, "training train_horizon, company")
        s = (f"**On your run**, within the {H} steps its gradient saw, the gap is not the actor's exploitation: "
             f"training's part is {tr:+.3f} ± {tse:.3f} per step, " + {
                 "down": "clearly negative. ",
                 "small": "beyond the noise but smaller than the minimum effect that matters. ",
                 "none": "within the noise. ", "up": ""}[r]
             + f"(It would count when {test_words(k)}.) ")
        te, tese = m["gap_training_eval_horizon"], m["gap_training_se_eval_horizon"]
        if training_exploits_eval(value=te, se=tese, k=k, min_effect=MIN_REWARD_EFFECT):
            s += (f"Over the whole evaluation, though, training's part is {te:+.3f} ± {tese:.3f}, clearly positive: "
                  "past the steps its gradient saw, the trained actor's dream is rosier against reality than the "
                  "untrained one's, so part of the headline gap is training's. ")
    if drift_rosy(value=dr, se=dse, k=k, min_effect=MIN_REWARD_EFFECT):
        s += (f"The dream is rosy even with nobody pushing ({dr:+.3f} ± {dse:.3f} over the same steps): an actor "
              "trained in it is graded on a model that flatters doing nothing, and the remedies above are about "
              "that too, since both give the model data or doubt where it is wrong.")
    else:
        r = reading(dr, dse, k, "drift train_horizon, company")
        s += (f"With nobody pushing, the dream is not measurably rosier than reality over those steps "
              f"({dr:+.3f} ± {dse:.3f}" + {"down": ", clearly gloomier", "none": ", within the noise",
                                          "small": ", beyond the noise but under the minimum effect",
                                          "up": ""}[r] + ").")
    return s


# --- distribution shift ---------------------------------------------------------------------------
def replay_test(replay: dict, expert_replay: dict, H: int):
    """Welch's t-test of the model's pusher error ``H`` steps into a replay (or at the last step of
    a shorter one): the policy's real actions (``replay["pusher"]``, (T, B)) minus held-out expert
    clips (``expert_replay["pusher"]``), per clip, with the minimum effect NEAR (5 mm)."""
    a, b = np.asarray(replay["pusher"], float), np.asarray(expert_replay["pusher"], float)
    i = min(H, len(a), len(b)) - 1
    pa, pb = a[i][~np.isnan(a[i])], b[i][~np.isnan(b[i])]
    return welch(pb, pa, min_effect=NEAR), float(pa.mean()), float(pb.mean())


def shift_sentence(m: dict, dt: float = 0.1, replay: dict | None = None, expert_replay: dict | None = None) -> str:
    """Distribution shift, in words, from the metrics of ``analysis.shift_metrics`` (claims). With
    the per-clip replay errors of ``analysis.replay_error`` and ``expert_replay_error`` ((T, B)
    arrays), the pusher's two errors are compared by Welch's t-test; without them, by the 5 mm
    resolution alone (no noise estimate), which the sentence says."""
    H = m["imag_horizon"]
    s = (f"The expert data has the pusher against a wall in **{m['expert_pusher_at_wall_share']:.0%}** of its "
         f"steps; the deployed policy in **{m['real_pusher_at_wall_share']:.0%}** of its real steps. ")
    pol, exp = m["replay_pusher_err_train_horizon"], m["expert_replay_pusher_err_train_horizon"]
    test = None
    if replay is not None and expert_replay is not None:
        test, pol, exp = replay_test(replay, expert_replay, H)
    s += (f"Replaying the policy's own real actions, the model's pusher is **{100 * pol:.1f} cm** "
          f"off after {H * dt:.1f} s, against {100 * exp:.1f} cm on held-out expert clips; its block is "
          f"{100 * m['replay_block_err_train_horizon']:.1f} cm off (expert clips: "
          f"{100 * m['expert_replay_block_err_train_horizon']:.1f} cm). ")
    # the 5 mm resolution alone, evaluated on every run (so the claim is recorded); it decides the
    # sentence only when the per-clip errors are not given
    worse_by_resolution = pusher_tracked_worse(policy_err=pol, expert_err=exp, near=NEAR)
    if test is not None:
        worse = pusher_tracked_worse_tested(diff=test.diff, se=test.se, k=test.k, min_effect=NEAR)
        better = pusher_tracked_better_tested(diff=test.diff, se=test.se, k=test.k, min_effect=NEAR)
        s += f"The difference, {100 * test.diff:+.1f} ± {100 * test.se:.1f} cm ({test.why().replace('0.005', '0.005 m')}), "
        if worse:
            s += ("is beyond the noise and at least 5 mm: the model tracks the pusher worse on the policy's data "
                  "than on the expert's, so the policy has left the data the model knows. ")
        elif better:
            s += "is beyond the noise and at least 5 mm the other way: the model tracks the policy's pusher *better*. "
        elif test.detected:
            s += ("is beyond the noise but under 5 mm: on the pusher, the model tracks the policy's data about as "
                  "well as the expert's. ")
        else:
            s += ("is within the noise: on the pusher, this run cannot tell how the model tracks the policy's data "
                  "from how it tracks the expert's. ")
    else:
        worse = worse_by_resolution
        s += ("The model's pusher is more than 5 mm farther off on the policy's data than on the expert's (5 mm "
              "is a resolution, not a test: these metrics keep no per-clip errors to give the difference a "
              "standard error), a sign that the policy has left the data the model knows. " if worse else
              "On the pusher, the model tracks the policy's data about as well as the expert's (within 5 mm, a "
              "resolution, not a test: these metrics keep no per-clip errors). ")
    s += (f"The evaluation dream runs **{m['dream_steps_per_train_clip']:.2f}x** longer than the "
          f"{m['train_clip_steps']}-step clips the model trained on. The dreamed blocks end a mean "
          f"**{m['dream_final_block_spread']:.3f} m** from their common centre, the real ones "
          f"{m['real_final_block_spread']:.3f} m (they spawned {m['spawn_block_spread']:.3f} m apart, measured "
          "the same way)")
    if dream_ends_collapse(dream_spread=m["dream_final_block_spread"], real_spread=m["real_final_block_spread"],
                           near=NEAR):
        s += ": the dream's end points collapse toward one place, whatever the start."
    else:
        s += (": the dream's end points are not more than 5 mm less spread than the real ones (5 mm is a "
              "resolution, not a test).")
    return s


# --- across seeds --------------------------------------------------------------------------------
SEED_COLUMNS = [("imagination_gap", "gap", "+.3f"),
                ("imagination_gap_position_eval_horizon", "gap: position", "+.3f"),
                ("imagination_gap_yaw_eval_horizon", "gap: yaw", "+.3f"),
                ("imagination_gap_train_horizon", "gap, training horizon", "+.3f"),
                ("gap_drift_eval_horizon", "drift", "+.3f"), ("gap_training_eval_horizon", "training", "+.3f"),
                ("gap_training_train_horizon", "training, training horizon", "+.3f"),
                ("expert_signal_dream_train_horizon", "dream pays the expert, training horizon", "+.3f"),
                ("zero_dream_block_moved_train_horizon", "zero-action dream moves the block (m), training horizon",
                 ".3f"),
                ("expert_gap_train_horizon", "expert's own gap, training horizon", "+.3f"),
                ("real_pusher_at_wall_share", "real steps at a wall", ".0%"),
                ("real_final_tee_dist", "real tee-dist (m)", ".3f"), ("spawn_tee_dist", "spawn (m)", ".3f"),
                ("real_success_rate", "real success", ".0%")]


def seeds_table(metrics: dict) -> str:
    """The seeds side by side, a markdown table (columns ``SEED_COLUMNS``; the whole evaluation
    unless the column says otherwise; the expert column is expert minus zero actions per step)."""
    rows = ["| seed | " + " | ".join(c[1] for c in SEED_COLUMNS) + " |", "|---|" + "---|" * len(SEED_COLUMNS)]
    def cell(m, k, f):
        v = format(m[k], f)
        if k == "expert_signal_dream_train_horizon" and m["zero_dream_block_moved_train_horizon"] > SUCCESS_POS:
            v += " (invalid)"                 # the zero-action dream moves the untouched block beyond 2 cm
        return v

    rows += [f"| {s} | " + " | ".join(cell(m, k, f) for k, _, f in SEED_COLUMNS) + " |" for s, m in metrics.items()]
    return "\n".join(rows) + ("\n\n(invalid): the zero-action dream moves the untouched block more than the "
                              f"{SUCCESS_POS * 100:.0f} cm success tolerance on that seed, so \"more than standing "
                              "still\" is not a test of recognising success there; the expert's own gap is.")


def seeds_sentence(metrics: dict, rollouts: dict | None = None) -> str:
    """Seeds side by side: the range of the gap, what the largest one is made of, which half of
    the gap dominates on each seed (per-start noise when each seed's ``rollouts`` are given), and
    whether the drift is most of the gap on every seed."""
    gaps = {s: m["imagination_gap"] for s, m in metrics.items()}
    lo, hi = min(gaps.values()), max(gaps.values())
    big = max(gaps, key=gaps.get)
    mb = metrics[big]
    s = (f"Across seeds {', '.join(map(str, metrics))} the gap runs from **{lo:+.3f}** to **{hi:+.3f}** per step "
         f"and real success is zero on **{sum(m['real_success_rate'] == 0 for m in metrics.values())}/"
         f"{len(metrics)}** seeds. The largest gap is seed {big}'s: over the whole evaluation its drift is "
         f"{mb['gap_drift_eval_horizon']:+.3f} and training's part is {mb['gap_training_eval_horizon']:+.3f} "
         f"(± {mb['gap_training_se_eval_horizon']:.3f}); over the training horizon training's part is "
         f"{mb['gap_training_train_horizon']:+.3f} (± {mb['gap_training_se_train_horizon']:.3f}). ")
    halves = {s: dominant_half(m, "eval_horizon", None if rollouts is None else
                               half_difference_se(rollouts[s], None)) for s, m in metrics.items()}
    by = {h: [str(s) for s, v in halves.items() if v == h] for h in ("yaw", "position", None)}
    said = [f"yaw on seed{'s' * (len(by['yaw']) > 1)} {', '.join(by['yaw'])}" if by["yaw"] else "",
            f"position on seed{'s' * (len(by['position']) > 1)} {', '.join(by['position'])}" if by["position"] else "",
            f"neither, beyond the noise and the minimum effect, on seed{'s' * (len(by[None]) > 1)} "
            f"{', '.join(by[None])}" if by[None] else ""]
    s += ("Over the whole evaluation, the larger half of the gap (beyond k standard errors, Student's t, and the "
          "minimum effect) is " + "; ".join(x for x in said if x) + ". ")
    drifts = [m["gap_drift_eval_horizon"] for m in metrics.values()]
    s += (f"The drift alone ranges from {min(drifts):+.3f} to {max(drifts):+.3f}: "
          + ("on every seed it is at least half of the gap." if drift_most_every_seed(drifts=drifts, gaps=list(gaps.values()))
             else "on some seeds it is less than half of the gap."))
    return s


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
            ax.bar(x + dx, [m[f"{p}_{world}_return_per_step_{span}"] for p in POLICY_LABELS], 0.4,
                   color=COLORS[world], alpha=0.85, label="in the dream" if world == "dream" else "in reality")
        ax.set_xticks(x, list(POLICY_LABELS.values()))
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("mean reward per step")
        ax.set_title(f"First {steps[span]} steps ({SPANS[span]})")
    lo = min(m[f"{p}_{w}_return_per_step_{s}"] for p in POLICY_LABELS for w in ("dream", "real") for s in SPANS)
    for ax in axes[:2]:
        ax.set_ylim(1.3 * lo, 0)
    ax = axes[2]
    width = 0.18
    for j, span in enumerate(SPANS):
        keys = ["imagination_gap", *(f"gap_{t}" for t in TERMS)]
        vals = [m[f"{k}_{span}"] for k in keys]
        errs = [kk * m[f"{k}_se_{span}"] for k in keys]
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
    for key, ls, color, label in curves:
        if key in rollouts:
            ax.plot(t, dist(rollouts[key]), ls=ls, color=color, label=label)
            ay.plot(t, yaw(rollouts[key]), ls=ls, color=color)
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
            keys = [f"expert_signal{tag}_{world}" for tag in ("", "_position", "_yaw")]
            ax.bar(x + dx, [m[f"{k}_{span}"] for k in keys], 0.4,
                   yerr=[kk * m[f"{k}_se_{span}"] for k in keys], capsize=3, color=COLORS[world], alpha=0.85,
                   label="in the dream (the expert's actions replayed)" if world == "dream" else "in reality")
        ax.axhspan(-MIN_REWARD_EFFECT, MIN_REWARD_EFFECT, color="0.85", zorder=0,
                   label=f"smaller than the minimum effect (±{MIN_REWARD_EFFECT:.2f})")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, ["whole reward", "position term", "yaw term"])
        moved = m.get(f"zero_dream_block_moved_{span}")
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
    for key, color in (("pusher", "tab:blue"), ("block", "tab:red")):
        e = replay[key]
        t = (np.arange(len(e)) + 1) * dt
        ax.plot(t, e.mean(1), color=color, lw=2, label=f"{key}, replaying the policy's real actions")
        ex = expert_replay[key]
        ax.plot((np.arange(len(ex)) + 1) * dt, ex.mean(1), color=color, ls="--", lw=1.5,
                label=f"{key}, replaying held-out expert clips")
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
SELF_CHECKS = {
    "zero_control": Question(
        "Why does the zero-action control need to be run in reality too, not only in the dream?",
        {"a": "It does not: in reality a pusher that never moves changes nothing",
         "b": "Because only the difference between the two worlds, for the same policy and the same "
              "starts, says how rosy the dream is; the real run gives the reward of the spawn pose",
         "c": "To check that pymunk is deterministic"},
        "b", "Drift is defined as dream minus reality for the same policy; with zero actions, "
             "reality is the spawn pose's reward, the baseline the dream is judged against."),
    "two_horizons": Question(
        "Training's share of the gap can differ between the actor's training horizon and the whole "
        "evaluation. Why measure it at the training horizon at all?",
        {"a": "Because the actor's gradient only ever saw dreams of that length: exploitation, if "
              "any, must show up there first",
         "b": "Because the evaluation is too noisy over its whole length",
         "c": "Because the real simulator cannot run longer than that"},
        "a", "The actor optimised the lambda-return of its training dreams; whatever it learned to "
             "exploit, if anything, pays off within them. Past that horizon the model drifts on its own, "
             "and the training term there mixes exploitation with what the actor does to a dream it "
             "was never trained on."),
    "shift": Question(
        "A world model can predict its own kind of data well (notebook 01 measured it on held-out "
        "expert clips). Why is that not enough to trust it on the deployed policy's data?",
        {"a": "It is enough: the pusher's kinematics do not depend on who commands it",
         "b": "Because a policy can visit states the training data never shows (for example the "
              "pusher pinned against a wall), and a model is only measured where its data was",
         "c": "Because the policy's actions are larger than the expert's"},
        "b", "A model is fitted, and tested, where its data was. If the policy drives the pusher where "
             "the expert never went (into a wall that stops it, say), the model never saw what happens "
             "there. The replay error above measures what that costs on this run."),
}
