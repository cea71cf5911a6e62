"""Notebook 04's claims about the learner's run: registered predicates (``pusht.nb.claims``) on the
run's numbers, and :func:`register_expert_control`, the expert control's claims, which notebooks
04 and 06 each register under their own prefix.

Changing a claim's name, sentence, control or keyword inputs invalidates ``benchmarks/claims.json``:
run ``make claims`` again (``tests/test_claims.py`` re-evaluates every recorded claim).
"""

from __future__ import annotations

import numpy as np

from .claims import claim, finite
from .stats import LEVEL, beyond, count_rise_p


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
