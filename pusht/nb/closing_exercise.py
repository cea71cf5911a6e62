"""Exercise 3 of notebook 06: its options and note, its measured letter (:func:`ex3_verdict`) and
its reconciliation in words, which the notebook and ``python -m pusht.exercise ex3`` print alike.
"""

from __future__ import annotations

import math

from ..env import SUCCESS_POS
from ..metric_keys import RETURN, key
from .closing_changes import COUNT_P, _steps, gap_change, success_rose, successes
from .closing_claims import count_beyond_chance, drift_crossed_zero, ex3_letter_decided, real_below_zero_action
from .closing_words import (_change_words, _halves, _ratio_words, _side_words, _sign_change_words,
                            path_words, policy_specific_words, reopen_words, sides)
from .fmt import num, pm
from .prose import note, options
from .stats import MIN_REWARD_EFFECT, count_rise_p, k_for, margin_words


# --- Exercise 3 ---------------------------------------------------------------------------------
# The words: pusht/nb/text/06_closing_the_gap.md; the note's number, from the constant that decides the verdict.
EX3_OPTIONS = options("06_closing_the_gap", "ex3")


EX3_NOTE = note("06_closing_the_gap", "ex3", min_effect=f"{MIN_REWARD_EFFECT:.2f}",
                tolerance_cm=f"{SUCCESS_POS * 100:.0f}")


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


def reconcile_text(rounds: list) -> str:
    """Exercise 3's measured outcome in words: the gap over the whole evaluation in round 0 and after
    the last round, its change against the noise and the minimum effect, round by round, from which
    world's side it moved, the same at the training horizon, and real success."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), int(last["round"])
    c = gap_change(rounds)
    cl = c.claims()
    lines = [f"The gap over {_steps(last, 'eval_horizon')} (the whole evaluation, {n} starts): round 0 "
             f"{pm(c.first, first['imagination_gap_se_eval_horizon'])}, after round {R} "
             f"{pm(c.last, last['imagination_gap_se_eval_horizon'])} (imagined minus real reward per step)."]
    per_round = ", ".join(f"{m['imagination_gap_eval_horizon']:+.3f}" for m in rounds)
    gap_path = path_words([abs(m["imagination_gap_eval_horizon"]) for m in rounds])
    lines.append(f"Round by round: {per_round}" + (f" (its size {gap_path})" if gap_path and len(rounds) > 2 else "")
                 + ". " + reopen_words(rounds))
    s = (f"The change is {c.diff:+.3f} ± {num(c.se)} ({_ratio_words(c)}; the minimum effect that matters is "
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
                     f"{pm(d0, d0se)} -> {pm(d1, d1se)}, through zero beyond the noise, while the part of the gap "
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
                 f"{pm(ct.first, first['imagination_gap_se_train_horizon'])} -> "
                 f"{pm(ct.last, last['imagination_gap_se_train_horizon'])}: {_change_words(ct, ct.claims())}.")
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
    lines.append(reality_vs_zero_words(rounds, cl["shrank"]))
    lines.append(f"So the measured answer is ({ex3_verdict(rounds)}).")
    return "\n".join(lines)


def reality_vs_zero_words(rounds: list, shrank: bool, span: str = "eval_horizon") -> str:
    """Did the loop make the policy worse in reality than doing nothing? Each round's real reward per
    step against zero actions' from the same starts (claim ``06.real_below_zero_action``; zero actions
    in the real sim are the same in every round). A gap that narrowed while reality fell below zero
    actions narrowed because the dream grew gloomier, not because the policy improved."""
    k = k_for(int(rounds[-1]["eval_episodes"]))
    at = dict(world="real", span=span)
    below = [m["round"] for m in rounds if real_below_zero_action(
        policy=m[key(RETURN, policy="trained", **at)], policy_se=m[key(RETURN, policy="trained", se=True, **at)],
        zero=m[key(RETURN, policy="zero", **at)], zero_se=m[key(RETURN, policy="zero", se=True, **at)],
        k=k, min_effect=MIN_REWARD_EFFECT)]
    last = rounds[-1]
    pol, zero = last[key(RETURN, policy="trained", **at)], last[key(RETURN, policy="zero", **at)]
    nums = (f"after round {last['round']} the policy earns {pol:+.3f} per step in reality, a pusher that never "
            f"moves {zero:+.3f} from the same starts")
    if not below:
        return (f"Against doing nothing: in no round did the policy earn less in reality than a pusher that never "
                f"moves, beyond the noise and the minimum effect ({nums}).")
    which = ("round " if len(below) == 1 else "rounds ") + ", ".join(str(r) for r in below)
    s = (f"Against doing nothing: in {which} the policy earned less in reality than a pusher that never moves, "
         f"beyond the noise and the minimum effect ({nums}).")
    if shrank and below[-1] == last["round"]:
        s += (" So the gap narrowed while, in reality, the policy ended worse than standing still: a narrower gap "
              "here does not mean a better policy.")
    return s
