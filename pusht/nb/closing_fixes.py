"""Notebook 06's fixes in words: the delta model and the ensemble against the state model, and
the table of fixes.
"""

from __future__ import annotations

import math

import numpy as np

from ..metric_keys import GAP, key
from ..env import ARENA_HALF, CONTROL_DT, OBS_NAMES, SUCCESS_POS
from .closing_changes import SPAN_KEYS, _real_key, _short, _steps, expert_ratio, fix_change, successes
from .closing_claims import (EXPERT_CONTROL, beats_copy_last_everywhere, drift_crossed_zero,
                             error_accumulates, error_size_shrank, fix_closed_gap,
                             model_moves_untouched_block, pusher_left_table, shared_bias,
                             untouched_block_on_table)
from .closing_words import (_change_words, _halves, _order, _ratio_words, _sign_word, error_size,
                            expert_words, halves_rule, halves_words, sides, yaw_share)
from .fmt import num, pm
from .gap_words import NEAR
from .stats import MIN_REWARD_EFFECT, k_for


# The arena is 2 * ARENA_HALF = 1 m wide: a dreamed pusher more than that away from the real one
# can no longer be anywhere on the table.
ARENA = 2 * ARENA_HALF


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
        parts.append(f"over {_steps(fix, span)} {c.first:+.3f} -> {c.last:+.3f} ± {num(c.last_se)} "
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
             + f" the {ARENA_HALF:.1f} m to the nearest wall); its drift went {pm(d0, d0se)} -> {pm(d1, d1se)}"
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
        g, se = delta_m[key(GAP, span=span)], delta_m[key(GAP, se=True, span=span)]
        gs = state_m[key(GAP, span=span)]
        words[span] = _sign_word(g, se, k)
        s += (f"Over {_steps(delta_m, span)} its gap is {pm(g, se)} ({words[span]}; the state model "
              f"{gs:+.3f}). ")
    s += f"Over the whole evaluation its gap is {halves_words(delta_m)}. {halves_rule(n, short=True)} "
    mood = {"rosier than reality": "rosy", "gloomier than reality": "gloomy"}
    w_tr, w_ev = words["train_horizon"], words["eval_horizon"]
    if {w_tr, w_ev} == set(mood):
        s += (f"Its dream is {mood[w_tr]} over the span the actor trained on and {mood[w_ev]} over the whole "
              "evaluation: it changed sign on the way. ")
    d, dse = delta_m["gap_drift_eval_horizon"], delta_m["gap_drift_se_eval_horizon"]
    zd, spawn = delta_m["zero_action_dream_final_tee_dist"], delta_m["spawn_tee_dist"]
    s += (f"With zero actions its dream is {pm(d, dse)} per step against reality ({_sign_word(d, dse, k)}; the "
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
        s += (f"Over {_steps(ens_m, span)} the ensemble's gap is {pm(c.last, ens_m[key(GAP, se=True, span=span)])} "
              f"against the single model's {pm(c.first, single_m[key(GAP, se=True, span=span)])}: "
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
    return (pm(m["expert_signal_dream_eval_horizon"], m["expert_signal_dream_se_eval_horizon"])
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
            name, pm(m["imagination_gap_train_horizon"], m["imagination_gap_se_train_horizon"]),
            pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
            f"{p:+.3f} / {y:+.3f}", _share_cell(m),
            pm(m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]),
            f"{m['zero_action_dream_final_tee_dist']:.3f}", _expert_cell(m),
            f"{successes(m)}/{int(m['eval_episodes'])}"]) + " |")
    rows.append("")
    rows.append("Reward per step, ± one standard error over the evaluation starts. Yaw share: |yaw half| / "
                "(|position half| + |yaw half|) of the gap over the whole evaluation. The untouched block: with "
                f"zero actions, where the dreamed block ends (the walls are {ARENA_HALF:.1f} m from the target; a "
                "real untouched block stays where it spawned). Expert signal: the scripted expert's actions minus "
                "zero actions, in the dream.")
    return "\n".join(rows)
