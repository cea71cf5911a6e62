"""Notebook 06's sentences about the loop's rounds: the gap's sides and halves, the expert
control, the rounds' table, the model's error and the block, each reading guarded by a
registered claim (``closing_claims``).
"""

from __future__ import annotations

import math

import numpy as np

from ..metric_keys import ERROR_SIZE, EXPERT_SIGNAL, RETURN, WM_COPY_ERR, WM_ERR, YAW_MINUS_POSITION, ZERO_BLOCK_MOVED, key
from ..env import SUCCESS_POS
from .closing_changes import (COUNT_P, Change, ERR_RES, _arrow, _dream_key, _gap_keys, _outcome, _real_key,
                              _series, _short, _steps, compare, displacement_se_bound, fix_change,
                              metric_change, successes, toward_outcome, toward_se_bound)
from .closing_claims import (EXPERT_CONTROL, change_down, change_up, count_beyond_chance,
                             dream_fell_for_the_policy, dream_gloomier, dream_penalises_expert,
                             dream_rewards_expert, dream_rosier, gap_reopened, halves_cancel,
                             model_better_on_policy, model_worse_somewhere, position_half_clearly_larger,
                             yaw_half_clearly_larger)
from .fmt import mm, num, pm
from .gap_expert import expert_control_words
from .stats import MIN_REWARD_EFFECT, count_rise_p, k_for


# Two halves of opposite signs "cancel almost exactly" when what is left of them, |position + yaw|,
# is less than a quarter of their sizes added, |position| + |yaw|: three quarters or more of the
# error is hidden from the gap.
CANCEL_SHARE = 0.25


DATA_LABELS = {"policy": "the policy's data", "expert": "held-out expert data"}


def _ratio_words(c: Change) -> str:
    r = "many" if math.isinf(c.ratio) else f"{c.ratio:.1f}"
    return f"{r} standard errors; a change counts beyond {c.k:.2f}"


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
    for world in ("dream", "real"):
        name, se_key = (key(RETURN, policy="trained", world=world, se=se, span=span) for se in (False, True))
        d = float(b[name] - a[name])
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
    return m[key(YAW_MINUS_POSITION, error=what, se=True, span=span)]


def _order(m: dict, span: str = "eval_horizon") -> str:
    p, _, y, _ = _halves(m, span)
    return halves_order(p, y, _diff_se(m, span), int(m["eval_episodes"]))


def error_size(m: dict, span: str = "eval_horizon", what: str = "imagination_gap") -> tuple[float, float]:
    """The size of the dream's error over ``span``, |position half| + |yaw half| of the gap (what a
    gap near zero can hide when the halves cancel; ``what="gap_drift"``: of the drift), and its
    standard error over the starts (``split.size_split``). Where the halves share a sign the size
    is the gap's size and its standard error the gap's: one quantity, one test."""
    return m[key(ERROR_SIZE, error=what, span=span)], m[key(ERROR_SIZE, error=what, se=True, span=span)]


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
    s = (f"{pm(p, pse)} from the block's position and {pm(y, yse)} from its yaw (|yaw| - |position| = "
         f"{abs(y) - abs(p):+.3f} ± {num(dse)}): {ORDER_WORDS[order]}")
    return s + _cancel_words(p, y)


def expert_words(m: dict, span: str = "eval_horizon") -> tuple[str, str]:
    """The expert control in one run: ``(numbers, verdict)``. Does the dream pay the scripted
    expert's actions (which succeed in reality) more than zero actions? Claims
    ``06.dream_rewards_expert`` and ``06.dream_penalises_expert``, read only where the control is
    valid (``06.zero_control_valid``: the zero-action dream leaves the untouched block in place);
    the expert's own gap, dream minus reality, beside it."""
    n = int(m["eval_episodes"])
    k = k_for(n)
    d, dse = m[key(EXPERT_SIGNAL, world="dream", span=span)], m[key(EXPERT_SIGNAL, world="dream", se=True, span=span)]
    r, rse = m[key(EXPERT_SIGNAL, world="real", span=span)], m[key(EXPERT_SIGNAL, world="real", se=True, span=span)]
    nums = f"expert minus zero actions: dream {pm(d, dse)}, reality {pm(r, rse)} per step"
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
    kw = dict(signal=m[key(EXPERT_SIGNAL, world="dream", span=span)],
              se=m[key(EXPERT_SIGNAL, world="dream", se=True, span=span)], k=k,
              min_effect=MIN_REWARD_EFFECT)
    rewards, penalises = dream_rewards_expert(**kw), dream_penalises_expert(**kw)
    moved = m[key(ZERO_BLOCK_MOVED, span=span)]
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
            f"(± {num(se)})")
    if specific:
        return (nums + ", beyond the noise and the minimum effect. The model stopped promising what this policy "
                "does not deliver, which is not the same as the policy delivering more.")
    return (nums + ", not beyond the noise and the minimum effect. The whole dream grew gloomier, standing still "
            "included: that is not the model learning what this particular policy does not deliver.")


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
        at = dict(data="policy", kind=kind, body=part)
        return f"{1000 * m[key(WM_ERR, **at)]:.1f} / {1000 * m[key(WM_COPY_ERR, **at)]:.1f}"

    for m in rounds:
        n = m["eval_episodes"]
        cells = [str(m["round"]), str(m.get("policy_episodes", "")),
                 pm(m["imagination_gap_train_horizon"], m["imagination_gap_se_train_horizon"]),
                 pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
                 f"{m[_dream_key('eval_horizon')]:+.3f}", f"{m[_real_key('eval_horizon')]:+.3f}",
                 f"{successes(m)}/{n}", f"{m['real_episodes_touching_block']}/{n}",
                 f"{m['real_block_displacement']:.3f}", f"{m['real_block_toward_target']:+.3f}",
                 f"{m['real_pusher_at_wall_share']:.0%}",
                 err(m, "one_step", "block"), err(m, "one_step", "pusher"),
                 err(m, "open_loop", "block"), err(m, "open_loop", "pusher")]
        p, pse, y, yse = _halves(m)
        cells += [f"{pm(p, pse)} / {pm(y, yse)}",
                  pm(m["expert_signal_dream_eval_horizon"], m["expert_signal_dream_se_eval_horizon"]),
                  pm(m["expert_signal_real_eval_horizon"], m["expert_signal_real_se_eval_horizon"])]
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
    per_e = "; ".join(f"round {m['round']}: {pm(m['expert_signal_dream_eval_horizon'], m['expert_signal_dream_se_eval_horizon'])}"
                      f" ({short[m['round']]})" for m in rounds)
    reals = [pm(m["expert_signal_real_eval_horizon"], m["expert_signal_real_se_eval_horizon"]) for m in rounds]
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
    head = (f"From round 0 to round {R} the dream's expert signal changed by {c.diff:+.3f} ± {num(c.se)} "
            f"({_ratio_words(c)}; minimum effect {c.min_effect:.2f})" + (f"; {path}" if path else ""))
    if not all(valid):
        g = metric_change(first, last, "expert_gap_eval_horizon", "expert_gap_se_eval_horizon")
        gpath = path_words(_series(rounds, "expert_gap_eval_horizon"))
        lines.append(head + ". That change cannot be read as the loop teaching the model about the expert's pushes: "
                     "in round " + " and ".join(str(m["round"]) for m, v in zip((first, last), valid) if not v)
                     + " the zero-action dream moves the untouched block beyond the success tolerance, so the "
                     "control moves with the model. The expert's own gap, dream minus reality, which needs no such "
                     f"control, went {first['expert_gap_eval_horizon']:+.3f} -> {last['expert_gap_eval_horizon']:+.3f}"
                     f" ({g.diff:+.3f} ± {num(g.se)}: "
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


def model_error_sentence(rounds: list) -> str:
    """Does the world model's one-step error on the policy's data fall every round, and on expert
    data? Names every round's number (mm), the copy-last error on the same data, and the open-loop
    errors' overall direction."""
    R = rounds[-1]["round"]
    idx = [m["round"] for m in rounds[1:]]
    out = [f"Below, an error \"fell\" or \"rose\" when it changed by more than {mm(ERR_RES)}: a resolution, not a "
           "test against the noise (the metrics keep no spread for these errors, each an RMSE over many clips)."]
    for data in ("policy", "expert"):
        parts = []
        for part in ("block", "pusher"):
            v = _series(rounds, key(WM_ERR, data=data, kind="one_step", body=part))
            parts.append(f"the {part}'s {_arrow(v)} ({trend_phrase(v, idx)})")
        where = ("On the policy's data (clips of each round's own real evaluation rollouts, never trained on)"
                 if data == "policy" else "On held-out expert data")
        out.append(f"{where} the world model's one-step error went: " + "; ".join(parts) + ".")
        if data == "policy":
            last = rounds[-1]
            rel = []
            for part in ("block", "pusher"):
                model = last[key(WM_ERR, data="policy", kind="one_step", body=part)]
                copy_ = last[key(WM_COPY_ERR, data="policy", kind="one_step", body=part)]
                if model > copy_ + ERR_RES:
                    rel.append(f"the {part}'s is still {model / copy_:.1f}x copy-last's ({mm(model)} vs {mm(copy_)})"
                               if copy_ > 0 else f"the {part}'s is {mm(model)}, copy-last's 0")
                elif model < copy_ - ERR_RES:
                    rel.append(f"the {part}'s beats copy-last ({mm(model)} vs {mm(copy_)})")
                else:
                    rel.append(f"the {part}'s is within 1 mm of copy-last's ({mm(model)} vs {mm(copy_)})")
            cb = _series(rounds, "wm_policy_one_step_block_copy_err")
            out.append(f"After round {R}, " + " and ".join(rel) + ". The data changed too: each round's policy "
                       f"data comes from that round's policy; copy-last's block error on it went {_arrow(cb)}, "
                       "a measure of how much the block moves in it.")
    ol = []
    for data in ("policy", "expert"):
        for part in ("block", "pusher"):
            v = _series(rounds, key(WM_ERR, data=data, kind="open_loop", body=part))
            d = _outcome(v[-1] - v[0], ERR_RES)
            verb = {"down": "fell overall", "up": "rose overall", "same": "within 1 mm overall"}[d]
            ol.append(f"{DATA_LABELS[data]}, {part}: {_arrow(v)} ({verb}; {trend_phrase(v, idx)})")
    out.append(f"Open-loop (the dream running alone through each clip), round 0 to round {R}: "
               + "; ".join(ol) + ".")

    def ends(key):
        return [rounds[0][key], rounds[-1][key]]

    pol = [ends(key(WM_ERR, data="policy", kind=k, body=p)) for k in ("one_step", "open_loop") for p in ("block", "pusher")]
    exp = [ends(key(WM_ERR, data="expert", kind=k, body=p)) for k in ("one_step", "open_loop") for p in ("block", "pusher")]
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


def _sign_word(v: float, se: float, k: float) -> str:
    """"rosier than reality", "gloomier than reality" or "not told apart from reality": beyond k
    standard errors and the minimum reward effect (claims ``06.dream_rosier``/``06.dream_gloomier``)."""
    kw = dict(value=v, se=se, k=k, min_effect=MIN_REWARD_EFFECT)
    if dream_rosier(**kw):
        return "rosier than reality"
    if dream_gloomier(**kw):
        return "gloomier than reality"
    return "not told apart from reality"
