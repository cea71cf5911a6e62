"""Notebook 03's claims about the learner's run: each a registered predicate (``pusht.nb.claims``)
on the run's numbers, and :func:`verdict`, which reads a measured change through its three claims.

Changing a claim's name, sentence, control or keyword inputs invalidates ``benchmarks/claims.json``:
run ``make claims`` again (``tests/test_claims.py`` re-evaluates every recorded claim).
"""

from __future__ import annotations

from .claims import claim
from .stats import Test, beyond


@claim("03.critic_reaches_your_actor", "changing the critic's weights changes the actor gradient of "
       "the learner's losses (the critic's slope reaches the actor, Dreamer's wiring)")
def critic_reaches_your_actor(*, change):
    return change > 0


@claim("03.critic_spares_page_actor", "changing the critic's weights leaves the actor gradient of "
       "the page's losses bit-identical")
def critic_spares_page_actor(*, change):
    return change == 0


@claim("03.states_detach_idle_under_set_gradients", "with set_gradients, a critic loss that reads "
       "the states undetached gives bit-identical gradients to the actor's and the critic's weights")
def states_detach_idle_under_set_gradients(*, actor_diff, critic_diff):
    return actor_diff == 0 and critic_diff == 0


@claim("03.states_detach_needed_in_summed_backward", "with one summed backward(), a critic loss that "
       "reads the states undetached changes the actor's gradient")
def states_detach_needed_in_summed_backward(*, actor_diff):
    return actor_diff > 0


@claim("03.target_detach_needed", "with set_gradients, a critic target that keeps its gradient "
       "changes the critic's gradient")
def target_detach_needed(*, critic_diff):
    return critic_diff > 0


def _change_claims(name: str, what: str, control: str | None = None):
    """Three registered claims on one measured change ``what`` (keyword inputs diff, se, k,
    min_effect): it rose, it fell (beyond k SE and by at least the minimum effect), it was detected
    (beyond k SE, whatever its size)."""
    @claim(f"03.{name}_rose", f"{what} rose beyond k standard errors and by at least the minimum effect",
           control=control)
    def rose(*, diff, se, k, min_effect):
        return beyond(diff, se, k, min_effect, +1)

    @claim(f"03.{name}_fell", f"{what} fell beyond k standard errors and by at least the minimum effect",
           control=control)
    def fell(*, diff, se, k, min_effect):
        return beyond(diff, se, k, min_effect, -1)

    @claim(f"03.{name}_detected", f"{what} changed beyond k standard errors (whatever its size)")
    def detected(*, diff, se, k, min_effect):
        return beyond(diff, se, k)

    return rose, fell, detected


IMAGINED = _change_claims("imagined", "the imagined reward per step (last 20 updates minus first 20)")


REAL_FLOOR = _change_claims("real_floor", "the real floor (final policy minus untrained, on the monitor's starts)",
                            "the untrained actor")


WIRING_RISE = _change_claims("wiring_rise", "the imagined rise with Dreamer's wiring minus the rise with the page's",
                             "the page's wiring")


WIRING_FLOOR = _change_claims("wiring_floor", "the real floor's change with Dreamer's wiring minus the change with "
                              "the page's (per start, on the monitor's starts)", "the page's wiring")


OBJECTIVE = _change_claims("objective", "the mean lambda-return the actor maximises (last 20 updates minus first 20)")


def verdict(test: Test, claims) -> str:
    """"up", "down", "small" (beyond the noise but under the minimum effect) or "same", decided by
    the three registered ``claims`` of :func:`_change_claims` on ``test`` (each evaluated)."""
    inputs = dict(diff=test.diff, se=test.se, k=test.k, min_effect=test.min_effect)
    up, down, seen = (c(**inputs) for c in claims)    # all three, so every run records each one
    return "up" if up else "down" if down else "small" if seen else "same"


@claim("03.floor_changes_spread", "the real floor's per-start changes differ between starts (a "
       "standard error above 0)")
def floor_changes_spread(*, se):
    return se > 0


@claim("03.floor_most_starts_unchanged", "on most of the monitor's starts the real reward per step is "
       "exactly the same before and after training")
def floor_most_starts_unchanged(*, n_changed, n):
    return n_changed < n / 2


@claim("03.critic_loss_fell", "the critic's loss is lower over the last 20 updates than over the first 20")
def critic_loss_fell(*, first, last):
    return last < first


@claim("03.unchanged_starts_untouched", "on every monitor start whose real reward did not change, neither "
       "the untrained nor the trained policy moved the block (by more than 1 micrometre)")
def unchanged_starts_untouched(*, moved):
    return all(x <= 1e-6 for x in moved)


@claim("03.floor_reproduces_monitor", "re-running the untrained and the trained policy on the monitor's "
       "starts reproduces the monitor's first and last means (to 1e-6 per step)")
def floor_reproduces_monitor(*, rerun, monitor):
    return all(abs(a - b) <= 1e-6 for a, b in zip(rerun, monitor))


@claim("03.curve_identical", "the learner's training curve is identical to the package's run")
def curve_identical(*, max_diff):
    return max_diff == 0


@claim("03.small_lam_higher", "with the untrained critic, the lam = 0 returns come out higher than "
       "the lam = 1 returns (mean over the dreamed steps)")
def small_lam_higher(*, mean_lam0, mean_lam1):
    return mean_lam0 > mean_lam1


@claim("03.untrained_values_optimistic", "the untrained critic's mean value of the first dreamed state "
       "is above the mean discounted sum of the dreamed rewards over the horizon (an upper bound on the "
       "dream's return from that state: every reward is at most 0)")
def untrained_values_optimistic(*, mean_value, mean_partial_return):
    return mean_value > mean_partial_return


@claim("03.your_actor_reaches_states", "the learner's actor loss sends gradient into the states through "
       "the critic's values")
def your_actor_reaches_states(*, norm):
    return norm > 0


@claim("03.your_actor_reaches_critic_weights", "the learner's actor loss has a gradient on the critic's weights")
def your_actor_reaches_critic_weights(*, norm):
    return norm > 0


@claim("03.your_critic_spares_states", "the learner's critic loss sends no gradient into the states")
def your_critic_spares_states(*, norm):
    return norm == 0


@claim("03.page_actor_spares_states", "the page's actor loss sends no gradient into the states through "
       "the values")
def page_actor_spares_states(*, norm):
    return norm == 0
