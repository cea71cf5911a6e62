"""Exercise 1 of notebook 04: its options, its measured letter (:func:`ex1_verdict`) and its
reconciliation in words, which the notebook and ``python -m pusht.exercise ex1`` print alike.
"""

from __future__ import annotations

from .gap_claims import (COUNT_P, drift_half_of_gap, drift_half_on_means, ex1_letter_decided, gap_rosy,
                         real_success, real_success_beyond_chance)
from .gap_words import DEFAULT_STARTS, _k, k_se, test_words
from .prose import options
from .stats import MIN_REWARD_EFFECT, count_rise_p


# --- Exercise 1 ---------------------------------------------------------------------------------
EX1_OPTIONS = options("04_imagination_gap", "ex1")  # the words: pusht/nb/text/04_imagination_gap.md


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
