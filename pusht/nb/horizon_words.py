"""Notebook 05's sentences and Exercise 2's options, verdict and reconciliation: what the sweep's
numbers say, each reading guarded by a registered claim (``horizon_claims``).
"""

from __future__ import annotations

import math

import numpy as np

from ..env import SUCCESS_ANG, SUCCESS_POS
from .fmt import num, pm_bold, tk
from .horizon_claims import (_plain_list, dream_block_ends_further, dream_block_ends_nearer,
                             dream_pushing_beats_zero, dream_turns_untouched_block,
                             dream_turns_untouched_block_away, drift_same_every_run, judge_change,
                             judge_sign, motion_same_every_horizon, real_block_ends_further,
                             real_block_ends_nearer, same_rows, seed_spread_matters)
from .prose import note
from .stats import LEVEL, MIN_REWARD_EFFECT, Test, clear_of_threshold, t_quantile


DT = 0.1                     # s per control step


SUCCESS_ANG_DEG = math.degrees(SUCCESS_ANG)


MIN_DIST_EFFECT = SUCCESS_POS   # m: a block distance moves by at least the success tolerance to count


# --- sentences ----------------------------------------------------------------------------------
SIGN_WORDS = {"up": "clearly positive", "down": "clearly negative",
              "small": "told apart from zero, but smaller than the minimum effect that matters",
              "unresolved": "at least the minimum effect in size, but not told apart from zero by the spread "
                            "across actor seeds",
              "same": "not told apart from zero"}


CHANGE_WORDS = {"up": "rose", "down": "fell",
                "small": "moved by less than the minimum effect that matters (beyond the noise, too small to count)",
                "unresolved": "moved by at least the minimum effect that matters, but not beyond the spread across "
                              "actor seeds: not resolved",
                "same": "did not change beyond the spread across actor seeds, and moved by less than the minimum "
                        "effect that matters"}


ERROR_BAR_SCOPE = note("05_horizon", "error_bar_scope")  # fixed words: pusht/nb/text/05_horizon.md


def rule_text(n_seeds: int, min_effect: float = MIN_REWARD_EFFECT, unit: str = "reward per step") -> str:
    """The rule behind every '±' verdict, generated from the number of actor seeds."""
    k1 = t_quantile(n_seeds - 1) if n_seeds > 1 else math.inf
    return (f"Each value is the mean ± standard error over {n_seeds} actor seeds. {ERROR_BAR_SCOPE} "
            "\"Clearly positive\" or "
            f"\"clearly negative\" means a one-sample t-test puts it beyond k = {k1:.2f} standard errors "
            f"(Student's t, {LEVEL:.0%} two-sided, {n_seeds - 1} degrees of freedom) and it is at least "
            f"{min_effect:.3f} {unit}, the minimum effect that matters.")


def interval_note(n_seeds: int) -> str:
    """What the 95% interval of the figure asks for, with this many actor seeds."""
    if n_seeds < 2:
        return "With one actor seed per horizon there is no spread to measure: the figure draws the values alone."
    k = t_quantile(n_seeds - 1)
    return (f"With {n_seeds} actor seeds per horizon the black bar reaches k = {k:.2f} standard errors either "
            f"side of the mean (Student's t at {n_seeds - 1} degrees of freedom), against 1.96 for a large "
            "sample: the fewer the seeds, the wider the interval, which is the honest price of few seeds.")


def horizon_line(h: int, values, what: str = "gap", q: str = "gap") -> str:
    t, kind = judge_sign(q, values)
    return f"{h} steps: {what} {pm_bold(t)} ({SIGN_WORDS[kind]}; {tk(t)})"


def change_phrase(t: Test, kind: str, long: bool = True) -> str:
    """'rose (+0.369 per step; paired t-test over actor seeds: |t| = 14.10 ...)' and the like."""
    why = t.why() if long else tk(t)
    return f"{CHANGE_WORDS[kind]} ({t.diff:+.3f} per step; {why})"


def same_at_every_horizon(values: dict, tol: float = 1e-9) -> bool:
    """True if ``{horizon: [value per actor seed]}`` holds the same list at every horizon (a term
    that, by construction, no horizon can change: the drift, the untrained actor's motion)."""
    return same_rows(list(values.values()), tol)


def _drift_same(drift: dict) -> bool:
    return drift_same_every_run(values=_plain_list(np.concatenate([drift[h] for h in sorted(drift)])))


def _motion_same(motion: dict) -> bool:
    return motion_same_every_horizon(rows=[_plain_list(motion[h]) for h in sorted(motion)])


def terms_sentence(terms: dict, imagined: dict, untrained: dict) -> str:
    """The gap's three terms over the whole evaluation, across horizons. ``terms``:
    ``{"drift"|"motion"|"training": {horizon: [value per actor seed]}}`` (``pusht.analysis``);
    ``imagined`` and ``untrained``: the dream's reward per step for the trained and the untrained
    actor, ``{horizon: [...]}``."""
    hs = sorted(terms["drift"])
    drift = np.concatenate([terms["drift"][h] for h in hs])
    motion = np.concatenate([terms["motion"][h] for h in hs])
    if _drift_same(terms["drift"]):
        mood = "optimism" if drift[0] > 0 else "pessimism"
        s = (f"The drift, the dream's {mood} with a pusher that never moves, is **{drift[0]:+.3f}** per step "
             f"in every run: no actor is involved in it, so no horizon can change it. ")
    else:
        s = f"The drift ranges from {drift.min():+.3f} to {drift.max():+.3f} per step across runs. "
    s += f"The untrained actor's motion term runs from {motion.min():+.3f} to {motion.max():+.3f}"
    s += (" and is the same at every horizon for each actor seed (the untrained actor depends on the seed "
          "only). " if _motion_same(terms["motion"]) else ". ")
    s += ("The training term: " + "; ".join(horizon_line(h, terms["training"][h], "training", "training")
                                             for h in hs) + ". ")
    t, kind = judge_change("training", terms["training"][hs[0]], terms["training"][hs[-1]])
    s += f"From {hs[0]} to {hs[-1]} steps it {change_phrase(t, kind, long=False)}. "
    lo = hs[0]
    _, sign = judge_sign("training", terms["training"][lo])
    if sign == "down":
        s += ("Negative means that, from the untrained to the trained actor, the dream's rating fell further "
              "(or rose less) than reality's. ")
    elif sign == "up":
        s += ("Positive means that, from the untrained to the trained actor, the dream's rating rose further "
              "than reality's. ")
    te, worse = judge_change("dream_training_effect", untrained[lo], imagined[lo])
    n = len(_plain_list(imagined[lo]))
    s += (f"In the dream, over the whole evaluation, the actor trained on {lo}-step dreams earns "
          f"**{np.mean(imagined[lo]):+.3f}** per step and the untrained one {np.mean(untrained[lo]):+.3f}, "
          f"a difference of {te.diff:+.3f}")
    if worse == "down":
        s += (": training made the policy worse in the very world model it was trained in, once the dream runs "
              f"the full evaluation (paired t-test over {n} actor seeds, {tk(te)}; beyond the minimum effect "
              f"{MIN_REWARD_EFFECT:.3f}). ")
    elif worse == "up":
        s += (f": in the dream that trained it, training paid off (paired t-test over {n} actor seeds, {tk(te)}; "
              f"beyond the minimum effect {MIN_REWARD_EFFECT:.3f}). ")
    elif worse == "small":
        s += (f": detected beyond the spread across {n} actor seeds ({tk(te)}), but smaller than the minimum effect "
              f"that matters ({MIN_REWARD_EFFECT:.3f}), so in the dream training changed the policy's rating too "
              "little to count. ")
    elif worse == "unresolved":
        s += (f": at least the minimum effect that matters ({MIN_REWARD_EFFECT:.3f}) in size, but not told apart from "
              f"no change by the spread across {n} actor seeds (paired t-test, {tk(te)}): whether training changed "
              "the policy's rating in the dream is not resolved on this run. ")
    else:
        s += (f": neither beyond the spread across {n} actor seeds (paired t-test, {tk(te)}) nor as large as the "
              f"minimum effect that matters ({MIN_REWARD_EFFECT:.3f}), so no change of the dream's rating by training "
              "is seen. ")
    t_lo, _ = judge_sign("training", terms["training"][lo])
    s += (f"(That difference is the dream's side alone; the {lo}-step training term above is it minus reality's side, "
          "a different quantity with its own spread across seeds.")
    thin = [name for name, x in ((f"the {lo}-step training term", t_lo), ("the dream's side", te))
            if not clear_of_threshold(x.ratio, x.k)]
    if thin:
        s += (f" The verdict on {' and on '.join(thin)} sits within 10% of its threshold (|t| against k): a rerun "
              "with other actor seeds could read it either way.")
    return s + ") "


def halves_sentence(gap_position: dict, gap_yaw: dict, drift_position: dict, drift_yaw: dict,
                    zero_yaw_deg: tuple[float, float] | None = None) -> str:
    """The gap split by the reward's two terms, per horizon (each ``{horizon: [per actor seed]}``):
    the position half (how far the block is from the target) and the yaw half (how far it is
    turned), which half is the larger (claim ``05.yaw_minus_position_*``: a one-sample t-test on
    the per-seed |yaw| - |position|, at least the minimum effect), and the drift's halves.
    ``zero_yaw_deg``: (dream, real) final yaw error of the zero-action rollouts, in degrees."""
    hs = sorted(gap_position)
    s = ("The reward is a position term (how far the block is from the target) plus a yaw term (how far it is "
         "turned from the target angle), so the gap splits exactly into a position half and a yaw half. "
         "Whole evaluation, mean over actor seeds: "
         + "; ".join(f"{h} steps: {np.mean(gap_position[h]) + np.mean(gap_yaw[h]):+.3f} = "
                     f"{np.mean(gap_position[h]):+.3f} position + **{np.mean(gap_yaw[h]):+.3f}** yaw"
                     for h in hs) + ". ")
    larger, tests = {}, {}
    for h in hs:
        d = np.abs(np.asarray(gap_yaw[h], dtype=float)) - np.abs(np.asarray(gap_position[h], dtype=float))
        tests[h], larger[h] = judge_sign("yaw_minus_position", d)
    yaw = [h for h in hs if larger[h] == "up"]
    pos = [h for h in hs if larger[h] == "down"]
    rest = [h for h in hs if h not in yaw and h not in pos]
    rule = ("one-sample t-test on each seed's |yaw| minus |position|, and at least the minimum effect; the noise here is "
            "the spread across actor seeds on the same starts, so notebooks 04 and 06, which judge one run against the "
            "spread across its starts, may judge the same model's halves differently")
    if len(yaw) == len(hs):
        s += f"At every horizon the yaw half is the larger ({rule}): most of the gap is about how the block is turned, not where it is. "
    elif len(pos) == len(hs):
        s += f"At every horizon the position half is the larger ({rule}): most of the gap is about where the block is. "
    else:
        if yaw and pos:                       # the test resolves opposite answers at different horizons
            s += (f"Which half dominates depends on the horizon: the yaw half is the larger at "
                  f"{', '.join(map(str, yaw))} steps, the position half at {', '.join(map(str, pos))} steps ({rule}). ")
        elif yaw:
            s += f"The yaw half is the larger at {', '.join(map(str, yaw))} steps ({rule}). "
        elif pos:
            s += f"The position half is the larger at {', '.join(map(str, pos))} steps ({rule}). "
        else:
            s += f"At no horizon is either half clearly the larger ({rule}). "
        s += ("Where the test names no larger half: " + "; ".join(
            f"at {h} steps, |yaw| minus |position| is {tests[h].diff:+.3f} ± {num(tests[h].se)} "
            f"({SIGN_WORDS[larger[h]]}; {tk(tests[h])})" for h in rest) + ". ")
    dp = np.concatenate([drift_position[h] for h in hs])
    dy = np.concatenate([drift_yaw[h] for h in hs])
    s += (f"The drift, with nobody touching the block, splits into {dp.mean():+.3f} position and "
          f"{dy.mean():+.3f} yaw per step")
    if zero_yaw_deg is not None:
        dream_deg, real_deg = (float(x) for x in zero_yaw_deg)
        s += (f"; with zero actions the T ends {dream_deg:.0f}° from the target angle in the dream and "
              f"{real_deg:.0f}° in reality (mean over the starts)")
        toward = dream_turns_untouched_block(dream_deg=dream_deg, real_deg=real_deg, tol_deg=SUCCESS_ANG_DEG)
        away = dream_turns_untouched_block_away(dream_deg=dream_deg, real_deg=real_deg, tol_deg=SUCCESS_ANG_DEG)
        if toward:
            s += (f": the dreamed T, which nobody touches, ends nearer the target angle than the real one, by more "
                  f"than the {SUCCESS_ANG_DEG:.0f}° success tolerance")
        elif away:
            s += (f": the dreamed T, which nobody touches, ends further from the target angle than the real one, by "
                  f"more than the {SUCCESS_ANG_DEG:.0f}° success tolerance")
        else:
            s += f": within the {SUCCESS_ANG_DEG:.0f}° success tolerance of each other"
    return s + "."


def own_horizon_sentence(own: dict) -> str:
    """The gap over each run's OWN training horizon (its first H evaluation steps, the span its
    gradient saw): ``{horizon: [value per actor seed]}``."""
    hs = sorted(own)
    kinds = {}
    lines = []
    for h in hs:
        t, kinds[h] = judge_sign("own_gap", own[h])
        lines.append(f"{h} steps: gap {pm_bold(t)} ({SIGN_WORDS[kinds[h]]}; {tk(t)})")
    s = "Over each run's own first H steps, the span its training dreams covered, the gap is: " + "; ".join(lines) + ". "
    above = [h for h in hs if kinds[h] == "up"]
    below = [h for h in hs if kinds[h] == "down"]
    if len(above) == len(hs):
        s += "At every horizon, over the span it was trained on, the dream rates the policy above reality. "
    elif len(below) == len(hs):
        s += "At every horizon, over the span it was trained on, the dream rates the policy below reality. "
    else:
        if above:
            s += f"Over that span the dream clearly rates the policy above reality at {', '.join(map(str, above))} steps. "
        if below:
            s += f"Over that span it clearly rates it below reality at {', '.join(map(str, below))} steps. "
        if not above and not below:
            s += "At no horizon is that gap clearly different from zero by the minimum effect that matters. "
    return s


def closest_approach(curve, dt: float = DT) -> tuple[float, float]:
    """(smallest value of a (T+1,) mean block-distance curve in m, the time in s it happens)."""
    c = np.asarray(curve, dtype=float)
    i = int(np.argmin(c))
    return float(c[i]), i * dt


def block_sentence(dream_final: dict, real_final: dict, spawn: float, curves: dict | None = None,
                   dt: float = DT, zero_final: float | None = None) -> str:
    """Where the block ends (m) at the end of the evaluation, per horizon (``{h: [per seed]}``),
    and, given the curves of :func:`fig_block_over_time`, when the dreamed block came closest.
    "Further than it spawned" needs at least ``MIN_DIST_EFFECT`` (the 2 cm success tolerance: a
    smaller move does not change whether the task is solved) beyond k standard errors.

    ``zero_final``: where the zero-action dream ends the block (m, mean over the starts): the
    control for "the pushing brought the block in". A dreamed block that ends nearer than it spawned
    was brought in by the pushing only if it also ends nearer than the block nobody pushes
    (claim ``05.dream_pushing_beats_zero``): notebook 04 showed the dream carrying an untouched
    block in on its own."""
    hs = sorted(dream_final)
    s = ("At the end of the evaluation the dreamed block sits "
         + ", ".join(f"**{np.mean(dream_final[h]):.3f} m** ({h} steps)" for h in hs)
         + " from the target, the real block "
         + ", ".join(f"{np.mean(real_final[h]):.3f} m" for h in hs)
         + f" (mean over actor seeds; it spawned {spawn:.3f} m away on average"
         + ("" if zero_final is None else
            f", and in the dream of a pusher that never moves it ends {zero_final:.3f} m away")
         + "). ")
    far_d = [h for h in hs if dream_block_ends_further(final=_plain_list(dream_final[h]), spawn=float(spawn),
                                                       min_effect=MIN_DIST_EFFECT)]
    far_r = [h for h in hs if real_block_ends_further(final=_plain_list(real_final[h]), spawn=float(spawn),
                                                      min_effect=MIN_DIST_EFFECT)]
    bar = (f"by at least the {MIN_DIST_EFFECT * 100:.0f} cm success tolerance and beyond k standard errors of a "
           "one-sample t-test over actor seeds")
    if far_d:
        s += (f"After training with {' and '.join(map(str, far_d))}-step dreams, the dream ends with the block "
              f"further from the target than where it spawned, {bar}. ")
    if far_r:
        s += (f"In reality, the actors trained with {' and '.join(map(str, far_r))}-step dreams pushed the block "
              f"further from the target than where it spawned, {bar}. ")
    if not far_d and not far_r:
        s += f"In neither world does the block end clearly further from the target than it spawned (clearly: {bar}). "
    near_d = [h for h in hs if dream_block_ends_nearer(final=_plain_list(dream_final[h]), spawn=float(spawn),
                                                       min_effect=MIN_DIST_EFFECT)]
    near_r = [h for h in hs if real_block_ends_nearer(final=_plain_list(real_final[h]), spawn=float(spawn),
                                                      min_effect=MIN_DIST_EFFECT)]
    steps = lambda hl: f"{' and '.join(map(str, hl))}-step"      # noqa: E731
    if near_d and not near_r:
        s += (f"The contrast: after training with {steps(near_d)} dreams the dream ends with the block clearly nearer "
              f"the target than where it spawned ({bar}), while in reality the block ends clearly nearer at no "
              "horizon. ")
    elif near_d and near_r:
        s += (f"The block ends clearly nearer the target than where it spawned ({bar}) in the dream after training "
              f"with {steps(near_d)} dreams, and in reality after training with {steps(near_r)} dreams. ")
    elif near_r:
        s += (f"In reality the actors trained with {steps(near_r)} dreams brought the block clearly nearer the target "
              f"than where it spawned ({bar}); the dream shows that at no horizon. ")
    else:
        s += f"In neither world does the block end clearly nearer the target than it spawned (clearly: {bar}). "
    if near_d and zero_final is not None:
        # the cause: was it the pushing? Only against the control that isolates it, the pusher that never moves
        pushed = [h for h in near_d if dream_pushing_beats_zero(final=_plain_list(dream_final[h]),
                                                                zero=float(zero_final), min_effect=MIN_DIST_EFFECT)]
        rest = [h for h in near_d if h not in pushed]
        if pushed:
            s += (f"After training with {steps(pushed)} dreams the dreamed block also ends nearer than the block of a "
                  f"pusher that never moves ({zero_final:.3f} m; {bar}): there the dream shows the pushing "
                  "bringing the block in. ")
        if rest:
            s += (f"{'After' if not pushed else 'But after'} training with {steps(rest)} dreams the dreamed block "
                  f"does not end clearly nearer than the block of a pusher that never moves, which the dream "
                  f"carries to {zero_final:.3f} m from the target by itself ({bar}): "
                  + ("in distance to the target the block comes in on its own, by the model's drift (notebook "
                     "04), not by the pushing (how the block is turned, the reward's other half, is a separate "
                     "matter). " if zero_final < spawn - MIN_DIST_EFFECT else
                     "the pushing is not what brought it in. "))
    if curves:
        best = {h: closest_approach(np.mean(curves[h]["dream"], axis=0), dt) for h in hs}
        s += ("In the dream (mean over seeds) the block comes closest to the target at "
              + ", ".join(f"{t:.1f} s ({d:.3f} m) after {h}-step training, whose dreams lasted {h * dt:.1f} s"
                          for h, (d, t) in best.items()) + ". ")
    return s


def conclusion(gaps: dict, real: dict, terms: dict) -> str:
    """The closing paragraph, branched on what the sweep measured (all ``{horizon: [...]}``;
    ``terms`` as in :func:`terms_sentence`)."""
    hs = sorted(gaps)
    lo, hi = hs[0], hs[-1]
    g, kg = judge_change("gap", gaps[lo], gaps[hi])
    r, kr = judge_change("real_rating", real[lo], real[hi])
    rule = f"minimum effect that matters {MIN_REWARD_EFFECT:.3f} per step"
    if kr in ("up", "down"):
        s = (f"**Reality's pay changed with the horizon**: its reward per step {CHANGE_WORDS[kr]} by {r.diff:+.3f} "
             f"from {lo} to {hi} steps ({r.why()}). Read the table before trusting it: at the 95% level, a sweep "
             "in which reality's pay did not depend on the horizon would still pass this test about one time in "
             "20. ")
    elif kr == "small":
        s = (f"**Reality pays about the same however far the actor dreamed**: its reward per step moved by "
             f"{r.diff:+.3f} from {lo} to {hi} steps, beyond the seed-to-seed noise but smaller than the {rule} "
             f"({tk(r)}). ")
    elif kr == "unresolved":
        s = (f"**Whether reality's pay changed with the horizon is not resolved**: its reward per step moved by "
             f"{r.diff:+.3f} from {lo} to {hi} steps, at least the {rule}, but the seed-to-seed spread does not tell "
             f"that apart from no change ({tk(r)}). ")
    else:
        s = (f"**Reality's pay did not change detectably with the horizon**: its reward per step moved by "
             f"{r.diff:+.3f} from {lo} to {hi} steps, which the seed-to-seed spread does not tell apart from no "
             f"change ({tk(r)}), and by less than the minimum effect that matters ({MIN_REWARD_EFFECT:.3f} per step). ")
    if kg in ("up", "down"):
        s += (f"**The gap did move** ({g.diff:+.3f} per step from {lo} to {hi} steps; {g.why()}), on one and the "
              "same frozen world model. So the gap is not a fixed property of the model: it is the model's error "
              "seen through one particular policy, and the horizon changes the policy. ")
        if _drift_same(terms["drift"]) and _motion_same(terms["motion"]):
            s += ("Since the drift and the motion terms are the same at every horizon, all of that change is in "
                  "the training term: what the actor learned from its dreams, and what it then does in the "
                  "steps of the evaluation dream its training never reached. ")
    elif kg == "small":
        s += (f"The gap moved by {g.diff:+.3f} per step from {lo} to {hi} steps: beyond the seed-to-seed noise, but "
              f"smaller than the {rule}, so on this model the horizon changed the gap too little to matter. ")
    elif kg == "unresolved":
        s += (f"The gap moved by {g.diff:+.3f} per step from {lo} to {hi} steps: at least the {rule}, but the "
              f"seed-to-seed spread does not tell it apart from no change ({tk(g)}). So between {lo} and {hi} steps, "
              "with these seeds, this sweep cannot say whether the horizon moved the gap: it did not resolve the "
              "change, which is not the same as finding none. ")
    else:
        s += (f"The gap moved by {g.diff:+.3f} per step from {lo} to {hi} steps, which the seed-to-seed spread does "
              f"not tell apart from no change ({tk(g)}), and by less than the minimum effect that matters ({MIN_REWARD_EFFECT:.3f} per step): between {lo} and {hi} steps, "
              "with these seeds, the horizon's effect on the gap is not told apart from seed luck. ")
    if len(hs) > 2:
        steps = [(a, b, *judge_change("gap_step", gaps[a], gaps[b])) for a, b in zip(hs, hs[1:])]
        other = [(a, b, t, k) for a, b, t, k in steps if k in ("up", "down") and k != kg]
        if other:
            s += ("Between neighbouring horizons the tests say something else: "
                  + "; ".join(f"from {a} to {b} steps the gap {CHANGE_WORDS[k]} ({t.diff:+.3f} per step; {tk(t)})"
                              for a, b, t, k in other)
                  + f". The exercise's letter compares only {lo} with {hi} steps; each step between neighbours is a "
                  "separate test on the same runs. ")
    s += ("The model itself, and every error it makes, is the same in every run; the horizon only decides "
          "which policy those errors are seen through.")
    return s


def takeaway(gaps: dict) -> str:
    """The closing advice, with the reason read off this run's spread across actor seeds."""
    ranges = {h: float(np.ptp(np.asarray(v, dtype=float))) for h, v in gaps.items() if len(v) > 1}
    s = ("What you can take away: before trusting a policy trained in imagination, run it in both worlds, as you "
         "did here, and measure the gap; and measure it for more than one seed")
    if not ranges:
        return s + ": a single seed cannot tell you how far its gap moves on luck alone."
    h, largest = max(ranges.items(), key=lambda kv: kv[1])
    if seed_spread_matters(largest_range=largest, min_effect=MIN_REWARD_EFFECT):
        return s + (f": on this run, at {h} steps, the gap differed by {largest:.3f} per step between actor seeds "
                    "trained on the same model with the same horizon, more than the minimum effect that matters "
                    f"({MIN_REWARD_EFFECT:.3f}): one run's gap can move that far on seed luck alone.")
    return s + (f": on this run the actor seeds at one horizon agreed within {largest:.3f} per step, less than the "
                f"minimum effect that matters ({MIN_REWARD_EFFECT:.3f}), but only measuring several seeds tells you so.")


def sweep_table(M: dict, n_eval: int) -> str:
    """The sweep as a markdown table, one row per (horizon, actor seed) of ``M``
    (``{(h, a): metrics}``), the gap split into its position and yaw halves."""
    rows = ["| horizon | actor seed | gap, whole evaluation (± SE over starts) | of which position | of which yaw "
            "| gap over its own first H steps | imagined reward/step | real reward/step "
            "| block-to-target at the end, dream (m) | block-to-target at the end, real (m) "
            "| real successes | real steps with the pusher against a wall |", "|---" * 12 + "|"]
    for (h, a), m in M.items():
        rows.append(f"| {h} | {a} | {m['imagination_gap']:+.3f} ± {m['imagination_gap_se_eval_horizon']:.3f} "
                    f"| {m['imagination_gap_position_eval_horizon']:+.3f} | {m['imagination_gap_yaw_eval_horizon']:+.3f} "
                    f"| {m['imagination_gap_train_horizon']:+.3f} | {m['imagined_return_per_step']:+.3f} "
                    f"| {m['real_return_per_step']:+.3f} | {m['imagined_final_tee_dist']:.3f} "
                    f"| {m['real_final_tee_dist']:.3f} "
                    f"| {round(m['real_success_rate'] * n_eval)}/{n_eval} | {m['real_pusher_at_wall_share']:.0%} |")
    return "\n".join(rows)
