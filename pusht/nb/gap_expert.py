"""Notebook 04's controls in words: the scripted expert (and when its zero-action control is
valid), the pusher's real paths replayed in the dream, and the distribution shift between the
expert's data and the policy's.
"""

from __future__ import annotations

import numpy as np

from ..metric_keys import EXPERT_GAP, EXPERT_SIGNAL, GAP_TERM, ZERO_BLOCK_MOVED, key
from ..env import SUCCESS_POS
from .fmt import apart
from .gap_claims import (EXPERT_CONTROL, dream_ends_collapse, dream_pays_expert, dream_penalises_expert,
                         drift_rosy, expert_solves_most, pusher_tracked_better_tested, pusher_tracked_worse,
                         pusher_tracked_worse_tested, real_beats_zero, real_worse_than_zero,
                         reality_pays_expert, term_beyond_noise, training_exploits, training_exploits_eval)
from .gap_words import NEAR, SPANS, _k, _ratio, k_se, reading, test_words
from .stats import MIN_REWARD_EFFECT, welch


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
    moved = m[key(ZERO_BLOCK_MOVED, span=span)]
    ok = claims["valid"](moved=moved, tol=SUCCESS_POS)
    g, gse = m[key(EXPERT_GAP, span=span)], m[key(EXPERT_GAP, se=True, span=span)]
    kw = dict(value=g, se=gse, k=k, min_effect=MIN_REWARD_EFFECT)
    over, under = claims["over"](**kw), claims["under"](**kw)
    head = f"the expert's own gap, what the dream pays its pushes minus what reality pays them {where}, is {g:+.3f} ± {gse:.3f} per step: "
    if over:
        own = head + "the dream pays them more than reality does, beyond the noise and the minimum effect"
    elif under:
        own = head + "the dream pays them less than reality does, beyond the noise and the minimum effect"
    else:
        own = head + "not told apart from what reality pays, by the noise and the minimum effect"
        drift = m.get(key(GAP_TERM, term="drift", span=span))
        sig = m[key(EXPERT_SIGNAL, world="dream", span=span)] - m[key(EXPERT_SIGNAL, world="real", span=span)]
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


# --- the expert control ---------------------------------------------------------------------------
def expert_text(m: dict, steps: dict, n: int | None = None) -> str:
    """Could the dream recognise success? The scripted expert's pushes against zero actions, in each
    world, over both spans (registered claims); the actor's question is decided on the training
    horizon, the dreams its gradient saw."""
    k = _k(m, n)

    def sig(world, span, half=""):
        at = dict(part=half or None, world=world, span=span)
        return m[key(EXPERT_SIGNAL, **at)], m[key(EXPERT_SIGNAL, se=True, **at)]

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
        s += (f"The noise does not explain that difference (it is beyond k = {apart(abs(diff) / se, k)[1]} standard "
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
