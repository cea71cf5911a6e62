"""Notebook 06's claims about the learner's loop and fixes: registered predicates
(``pusht.nb.claims``) on the runs' numbers, the expert control's claims under the prefix 06.

Changing a claim's name, sentence, control or keyword inputs invalidates ``benchmarks/claims.json``:
run ``make claims`` again (``tests/test_claims.py`` re-evaluates every recorded claim).
"""

from __future__ import annotations

import math

import numpy as np

from .claims import claim
from .gap_claims import register_expert_control
from .stats import THIN_MARGIN, beyond, clear_of_threshold


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


@claim("06.real_below_zero_action", "the policy earns less per step in reality than a pusher that never moves, from "
       "the same starts, beyond k standard errors (the two per-start standard errors in quadrature, which is "
       "conservative) and by at least the minimum effect", control="zero actions")
def real_below_zero_action(*, policy, policy_se, zero, zero_se, k, min_effect):
    return beyond(policy - zero, math.hypot(policy_se, zero_se), k, min_effect, -1)


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
    return beyond(diff, se, k, min_effect, +1)


@claim("06.change_down", "the quantity fell beyond k standard errors and by at least the minimum effect", control="round 0")
def change_down(*, diff, se, k, min_effect, quantity=""):
    return beyond(diff, se, k, min_effect, -1)


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


@claim("06.count_change_beyond_chance", "a change of a count is beyond chance: Fisher's exact one-sided p below "
       "the bar")
def count_beyond_chance(*, p, bar):
    return p < bar


@claim("06.ex3_letter_decided", "Exercise 3's letter is decided beyond the noise: the gap's size changed by well under "
       "the minimum effect, or its change's |t| is more than 10% away from k", control="round 0")
def ex3_letter_decided(*, first, first_se, last, last_se, k, min_effect):
    drop = abs(first) - abs(last)
    se = math.hypot(first_se, last_se)
    return abs(drop) < (1 - THIN_MARGIN) * min_effect or clear_of_threshold(abs(drop) / se if se > 0 else math.inf, k)


EXPERT_CONTROL = register_expert_control("06")


@claim("06.dream_fell_for_the_policy", "the dream's rating of the policy fell by more than its rating of a pusher "
       "that never moves, beyond k standard errors of the difference and the minimum effect: the model learned "
       "something about this policy, not only grew gloomier everywhere", control="zero actions")
def dream_fell_for_the_policy(*, diff, se, k, min_effect):
    return beyond(diff, se, k, min_effect, -1)


@claim("06.model_better_on_policy_data", "from round 0 to the last round every error of the model on the policy's "
       "data (one-step and open-loop, block and pusher) fell by more than 1 mm", control="round 0")
def model_better_on_policy(*, firsts, lasts, res):
    return all(b < a - res for a, b in zip(firsts, lasts))


@claim("06.model_worse_somewhere", "from round 0 to the last round at least one of these errors of the model rose by "
       "more than 1 mm", control="round 0")
def model_worse_somewhere(*, firsts, lasts, res):
    return any(b > a + res for a, b in zip(firsts, lasts))


@claim("06.block_closer", "on average the real block ends nearer the target than it spawned, beyond k bounds on its "
       "standard error and at least 5 mm")
def block_closer(*, toward, bar):
    return toward > bar


@claim("06.block_farther", "on average the real block ends farther from the target than it spawned, beyond k bounds "
       "on its standard error and at least 5 mm")
def block_farther(*, toward, bar):
    return toward < -bar


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


@claim("06.shared_bias", "the ensemble members disagree less (the larger disagreement figure) than their mean dream "
       "errs from reality (the smaller error figure)")
def shared_bias(*, disagreement, error):
    return disagreement < error
