"""Notebook 07's claims about the learner's run: registered predicates (``pusht.nb.claims``) on the
numbers of its gates, its ladder of world models, its planner and its actor.

Changing a claim's name, sentence, control or keyword inputs invalidates ``benchmarks/claims.json``:
run ``make claims`` again (``tests/test_claims.py`` re-evaluates every recorded claim).
"""

from __future__ import annotations

from .claims import claim
from .stats import beyond


@claim("07.gate_passes", "the dream ranks the expert's real pushes above zero actions, as reality does: the dream's "
       "expert signal (expert minus zero actions, reward per step, over the planner's horizon) is positive beyond "
       "k standard errors and by at least the minimum effect", control="the scripted expert")
def gate_passes(*, signal, se, k, min_effect, quantity):
    return beyond(signal, se, k, min_effect, +1)


@claim("07.zero_only_on_target", "every zero action in the training data comes with the block already on the "
       "target (the padding after an early success): nowhere in the data does a zero action meet a block that "
       "must stay off the target")
def zero_only_on_target(*, zero, zero_off_target):
    return zero > 0 and zero_off_target == 0


@claim("07.drift_toward_target", "in the dream, a block nobody touches ends nearer the target than it started, "
       "beyond k standard errors over the starts and by at least the success tolerance", control="reality")
def drift_toward_target(*, value, se, k, tolerance, quantity):
    return beyond(value, se, k, tolerance, +1)


@claim("07.change_raised_signal", "the change raised the dream's expert signal, paired over the same starts, beyond "
       "k standard errors and by at least the minimum effect", control="the model without the change")
def change_raised_signal(*, diff, se, k, min_effect, quantity):
    return beyond(diff, se, k, min_effect, +1)


@claim("07.change_lowered_signal", "the change lowered the dream's expert signal, paired over the same starts, "
       "beyond k standard errors and by at least the minimum effect", control="the model without the change")
def change_lowered_signal(*, diff, se, k, min_effect, quantity):
    return beyond(diff, se, k, min_effect, -1)


@claim("07.succeeds_in_reality", "the policy solves at least one held-out start in reality AND earns more per step "
       "than zero actions from the same starts, beyond k standard errors and by at least the minimum effect",
       control="zero actions")
def succeeds_in_reality(*, successes, diff, se, k, min_effect, quantity):
    return successes >= 1 and beyond(diff, se, k, min_effect, +1)


@claim("07.below_zero_action", "the policy earns less per step in reality than zero actions from the same starts, "
       "beyond k standard errors and by at least the minimum effect", control="zero actions")
def below_zero_action(*, diff, se, k, min_effect, quantity):
    return beyond(diff, se, k, min_effect, -1)


@claim("07.actor_exploits", "the actor's dream rates it above what reality pays it from the same starts, paired, "
       "beyond k standard errors and by at least the minimum effect", control="reality")
def actor_exploits(*, gap, se, k, min_effect, quantity):
    return beyond(gap, se, k, min_effect, +1)


@claim("07.actor_below_zero_in_dream", "the actor's own dream of the evaluation rates it below the same dream's "
       "zero actions from the same starts, paired, beyond k standard errors and by at least the minimum effect: "
       "it did not learn a good policy even in the model", control="zero actions")
def actor_below_zero_in_dream(*, diff, se, k, min_effect, quantity):
    return beyond(diff, se, k, min_effect, -1)


@claim("07.gate_predicted", "for every world model the planner ran in, the gate's verdict, read before planning, "
       "matched the planner's outcome in reality: passed where the planner succeeded, failed where it did not")
def gate_predicted(*, passed, succeeded):
    return len(passed) == len(succeeded) > 0 and all(bool(p) == bool(s) for p, s in zip(passed, succeeded))
