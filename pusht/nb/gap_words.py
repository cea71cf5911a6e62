"""Notebook 04's sentences: the k of every verdict (:func:`k_se`), the headline, what training
exploited, the gap's split into terms and halves, the block's dip and the seeds' table, each
reading guarded by a registered claim (``gap_claims``).
"""

from __future__ import annotations

import numpy as np

from ..metric_keys import GAP, GAP_TERM, key
from ..config import Config
from ..env import SUCCESS_ANG, SUCCESS_POS, obs_to_pose
from .fmt import apart
from .gap_claims import (DRIFT_SHARE, dream_block_drifts_back, dream_drifts_to_data_position,
                         dream_drifts_to_data_yaw, dream_reproduces_package, drift_most_every_seed,
                         drift_rosy, gap_rosy, half_dominates, term_beyond_noise, term_negative,
                         term_positive, training_exploits, training_exploits_eval, typical_pose_near_target,
                         zero_dream_closer)
from .stats import LEVEL, MIN_REWARD_EFFECT, beyond, k_for


# The default config's number of held-out starts (cfg.eval_episodes), for metrics that do not say.
DEFAULT_STARTS = Config.eval_episodes


def k_se(n: int | None = None) -> float:
    """k of every verdict here: the two-sided LEVEL point of Student's t at n - 1 degrees of
    freedom, n the number of evaluation starts (DEFAULT_STARTS when not given)."""
    n = DEFAULT_STARTS if n is None else int(n)
    return k_for(max(n, 2))


def _k(m: dict | None = None, n: int | None = None) -> float:
    """k for a run's metrics ``m``: ``n`` if given, else the metrics' ``eval_episodes``."""
    return k_se(n if n is not None else (m or {}).get("eval_episodes"))


K_SE = k_se()                # for the default config's 100 starts (1.98); the functions take n


# 5 mm: the smallest distance difference these sentences read as a difference (a sixth of the
# pusher's radius; the per-start spread of final distances is several centimetres).
NEAR = 0.005


# 10 degrees, the environment's yaw tolerance: the smallest yaw difference read as a difference.
NEAR_DEG = float(np.degrees(SUCCESS_ANG))


TERMS = {"drift": "drift (zero actions)", "motion": "untrained actor's motion",
         "training": "training"}


SPANS = {"train_horizon": "training horizon", "eval_horizon": "whole evaluation"}


HALVES = ("position", "yaw")


def test_words(k: float = K_SE) -> str:
    """How a difference is judged, in words (k standard errors, Student's t, and the minimum effect)."""
    return (f"beyond k = {k:.2f} standard errors over the starts (Student's t, {LEVEL:.0%} two-sided) and at "
            f"least the minimum effect that matters, {MIN_REWARD_EFFECT:.2f} per step")


TEST_WORDS = test_words()


def _term_args(m: dict, term: str | None, span: str, half: str = "") -> tuple[float, float]:
    """(value, se) of the gap (``term`` None) or of one of its terms over ``span``, for a half or all."""
    template, at = (GAP, {}) if term is None else (GAP_TERM, {"term": term})
    at.update(part=half or None, span=span)
    return m[key(template, **at)], m[key(template, se=True, **at)]


def clearly_positive(value: float, se: float, k: float = K_SE) -> bool:
    """``value`` exceeds ``k`` standard errors (``se`` measured on the same starts) and the minimum
    effect that matters (a registered claim, ``04.term_positive``)."""
    return term_positive(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT)


def reading(value: float, se: float, k: float = K_SE, what: str = "") -> str:
    """"up" or "down" (beyond ``k`` standard errors and at least the minimum effect), "small"
    (beyond k standard errors, but smaller than the minimum effect that matters) or "none" (within
    the noise), decided by registered claims (``04.term_positive``, ``04.term_negative``,
    ``04.term_beyond_noise``)."""
    if term_positive(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT, what=what):
        return "up"
    if term_negative(value=value, se=se, k=k, min_effect=MIN_REWARD_EFFECT, what=what):
        return "down"
    if term_beyond_noise(value=value, se=se, k=k, what=what):
        return "small"
    return "none"


def _ratio(value: float, se: float, k: float = K_SE) -> str:
    """|value| in standard errors, printed so that it never looks equal to ``k``."""
    return apart(abs(value) / se, k)[0] if se > 0 else "many"


def dream_check_text(mismatch: float) -> str:
    """Does the learner's ``dream`` reproduce the package's imagined reward?"""
    if dream_reproduces_package(mismatch=mismatch):
        return f"Your `dream` reproduces the package's imagined reward per step to within **{mismatch:.1e}**."
    return (f"**Careful:** your `dream` gives imagined rewards that differ from the package's by {mismatch:.3g} "
            "per step; the figures below use yours, so re-check the task above.")


def exploitation_text(metrics: dict, H: int, n: int | None = None) -> str:
    """After the reconciliation: what each seed's run shows about the question "what has the actor
    become good at": the training term within the ``H`` steps its gradient saw (a claim)."""
    lines = []
    k = None
    for seed, m in metrics.items():
        k = _k(m, n)
        v, se = m["gap_training_train_horizon"], m["gap_training_se_train_horizon"]
        if training_exploits(value=v, se=se, k=k, min_effect=MIN_REWARD_EFFECT):
            verdict = ("training made the dream rosier than it made reality: the actor learned something "
                       "only the dream pays for")
        else:
            r = reading(v, se, k, f"training train_horizon seed {seed}")
            verdict = {
                "down": "training made the dream *gloomier* than it made reality, beyond the noise and the "
                        "minimum effect: this actor did not exploit its dream",
                "small": f"that is beyond the noise ({_ratio(v, se, k)} standard errors) but smaller than the minimum "
                         "effect that matters, so it is not read as exploitation: this actor did not measurably "
                         "exploit its dream",
                "none": "that is within the noise: training did not make the dream measurably rosier than "
                        "reality, and this actor did not measurably exploit its dream",
            }["none" if r == "up" else r].replace("this actor did", f"within those {H} steps this actor did")
            ve, vse = m["gap_training_eval_horizon"], m["gap_training_se_eval_horizon"]
            if training_exploits_eval(value=ve, se=vse, k=k, min_effect=MIN_REWARD_EFFECT):
                verdict += (f"; over the whole evaluation, though, training's part is {ve:+.3f} ± {vse:.3f}, clearly "
                            "positive: past the steps its gradient saw, the trained actor's dream is rosier against "
                            "reality than the untrained one's")
        lines.append(f"* seed {seed}: within the first {H} steps, training's part of the gap is "
                     f"**{v:+.3f}** ± {se:.3f} per step; {verdict}.")
    return ("**What your run shows.** Whether the actor exploited its dream is measured by the *training* "
            "term of the gap (taken apart below): what training added in the dream beyond what it added in "
            f"reality, over the {H} steps the actor's gradient saw. It counts when it is "
            f"{test_words(k if k is not None else k_se(n))}.\n\n" + "\n".join(lines))


# --- the headline and one start ------------------------------------------------------------------
def headline_text(m: dict, n_dream_solved: int, n_real_solved: int, n_eval: int, page: dict | None = None) -> str:
    """The two-worlds headline in words (and the chapter page's numbers, quoted, when given)."""
    s = (f"In the dream the policy earns **{m['imagined_return_per_step']:+.3f}** per step; in reality "
         f"**{m['real_return_per_step']:+.3f}**, a gap of **{m['imagination_gap']:+.3f}**. The dream leaves "
         f"the block **{m['imagined_final_tee_dist']:.3f} m** from the target on average, with a yaw error of "
         f"**{m['trained_dream_final_yaw_err_deg']:.0f}°**, and by the environment's own thresholds it would "
         f"call **{n_dream_solved}/{n_eval}** starts solved. In reality the block ends **{m['real_final_tee_dist']:.3f} m** "
         f"away with a yaw error of **{m['trained_real_final_yaw_err_deg']:.0f}°** (it spawned "
         f"**{m['spawn_tee_dist']:.3f} m** away), and **{n_real_solved}/{n_eval}** starts are solved.")
    if page:
        s += (f"\n\nFor comparison, the chapter page reports for its seed 0 an imagined "
              f"{page['imagined_return_per_step']['seed0']:+.3f} against a real {page['real_return_per_step']['seed0']:+.3f} "
              f"per step (gap {page['imagination_gap']['seed0']:+.3f}), a dream block "
              f"{page['imagined_final_tee_dist']['seed0']:.3f} m from the target and a real one "
              f"{page['real_final_tee_dist']['seed0']:.3f} m away, with {page['real_success_rate']['seed0']:.0%} real "
              "success. Those are the page's own numbers, quoted: not reproduced by this notebook.")
    return s


def median_start(dream_roll, real_roll) -> int:
    """The start whose dream-minus-real final distance is the median one: a typical start."""
    d = dream_roll.final_tee_dist - real_roll.final_tee_dist
    return int(np.argsort(d)[len(d) // 2])


def median_start_text(i: int, dream_roll, real_roll) -> str:
    """Where start ``i`` ends in both worlds: distance and yaw error, against where it spawned."""
    _, tee0 = obs_to_pose(real_roll.obs[0, i])
    return (f"Start {i} (the median start): the dream ends with the block **{dream_roll.final_tee_dist[i]:.3f} m** "
            f"from the target at a yaw error of **{dream_roll.final_yaw_err[i]:.0f}°**; reality ends with it "
            f"**{real_roll.final_tee_dist[i]:.3f} m** away at **{real_roll.final_yaw_err[i]:.0f}°** (it spawned "
            f"{np.linalg.norm(tee0[:2]):.3f} m away at {abs(np.degrees(tee0[2])):.0f}°).")


# --- reading the split of the gap ----------------------------------------------------------------
def describe(value: float, se: float, what: str = "", k: float = K_SE) -> str:
    """A term in words, judged against its own standard error and the minimum effect that matters
    (:func:`reading`)."""
    return {"up": "clearly positive", "down": "clearly negative",
            "small": "beyond the noise but smaller than the minimum effect that matters",
            "none": "not told apart from zero"}[reading(value, se, k, what)]


def half_difference_se(rollouts: dict, steps: int | None) -> float:
    """The standard error over the starts of the gap's yaw half minus its position half, over the
    first ``steps`` steps (all for None): both halves are measured on the same starts, so the
    difference is a mean of per-start differences."""
    from ..split import per_start, se

    def half(part):
        return per_start(rollouts["dream_trained"], steps, part) - per_start(rollouts["real_trained"], steps, part)

    x = half("yaw") - half("position")
    return se(x[~np.isnan(x)])


def dominant_half(m: dict, span: str, se_diff: float | None = None, k: float | None = None) -> str | None:
    """"position" or "yaw" when that half of the gap over ``span`` is positive and the larger one by
    more than k standard errors of the two halves' difference, ``se_diff`` (per start,
    :func:`half_difference_se`; without it, the sum of the halves' own standard errors, a
    conservative bound), and the minimum effect; None when neither is (claim ``04.half_dominates``)."""
    (p, pse), (y, yse) = (_term_args(m, None, span, h) for h in HALVES)
    se = pse + yse if se_diff is None else se_diff
    k = _k(m) if k is None else k
    for which, a, b in (("yaw", y, p), ("position", p, y)):
        if a >= b and half_dominates(larger=a, smaller=b, se_diff=se, k=k, min_effect=MIN_REWARD_EFFECT,
                                     which=f"{span} {which}"):
            return which
    return None


def dominance_sentence(m: dict, span: str, se_diff: float | None = None, k: float | None = None) -> str:
    """Which half of the gap is the larger on this run, in words; when neither is, which condition
    failed (the larger half not positive, the difference within the noise, or under the minimum
    effect)."""
    (p, pse), (y, yse) = (_term_args(m, None, span, h) for h in HALVES)
    k = _k(m) if k is None else k
    which = dominant_half(m, span, se_diff, k)
    name = "gap"
    se = pse + yse if se_diff is None else se_diff
    kind = ("its standard error over the starts" if se_diff is not None else
            "a conservative bound on its standard error (the sum of the halves' standard errors)")
    noise = (f"{se:.3f}, its standard error over the starts" if se_diff is not None else
             f"{se:.3f}, the sum of the halves' standard errors, a conservative bound")
    total = m[key(GAP, span=span)]
    shares = (f", that is {p / total:.0%} and {y / total:.0%} of the {name}"
              if p > 0 and y > 0 and total > 0 else "")
    if which is None:
        big, a, b = ("yaw", y, p) if y >= p else ("position", p, y)
        d = a - b
        clear, enough = beyond(d, se, k), d >= MIN_REWARD_EFFECT
        if a <= 0:
            why = f"the larger half, {big}, is not positive"
        elif not clear and not enough:
            why = (f"their difference, {d:.3f}, is neither beyond {k:.2f} times {kind}, {se:.3f}, "
                   f"nor as large as the minimum effect {MIN_REWARD_EFFECT:.2f}")
        elif not clear:
            why = (f"their difference, {d:.3f}, is within the noise: not beyond {k:.2f} times {kind}, "
                   f"{se:.3f}")
        else:
            why = (f"their difference, {d:.3f}, is beyond {k:.2f} times {kind}, {se:.3f}, but "
                   f"smaller than the minimum effect that matters, {MIN_REWARD_EFFECT:.2f}")
        return (f"Neither half of the {name} stands out as the larger, positive part (position {p:+.3f}, yaw "
                f"{y:+.3f}{shares}): {why}.")
    other = "position" if which == "yaw" else "yaw"
    a, b = (y, p) if which == "yaw" else (p, y)
    what = "the block's *orientation* (its yaw)" if which == "yaw" else "the block's *position*"
    return (f"Most of the {name} is in its **{which}** half: {a:+.3f} against {b:+.3f} from {other} "
            f"(the difference is beyond {k:.2f} times {noise}, and at least {MIN_REWARD_EFFECT:.2f}): "
            f"on this run the dream flatters {what} more than its {other}.")


def split_sentence(m: dict, span: str, steps: int, rollouts: dict | None = None, n: int | None = None) -> str:
    """The gap and its three terms over ``span`` ("train_horizon" or "eval_horizon"), each with
    its position and yaw halves, and which half of the gap is the larger (judged on the per-start
    difference of the halves when the run's ``rollouts`` are given)."""
    k = _k(m, n)
    gap, gse = m[key(GAP, span=span)], m[key(GAP, se=True, span=span)]
    rosy = gap_rosy(gap=gap, se=gse, k=k, min_effect=MIN_REWARD_EFFECT)

    def halves(term):
        (p, _), (y, _) = (_term_args(m, term, span, h) for h in HALVES)
        return f"position {p:+.3f}, yaw {y:+.3f}"

    parts = []
    for term, label in TERMS.items():
        v, se = _term_args(m, term, span)
        share = f", {v / gap:.0%} of the gap" if rosy else ""
        parts.append(f"{label} **{v:+.3f}** ± {se:.3f} ({halves(term)}; "
                     f"{describe(v, se, f'{term} {span}', k)}{share})")
    return (f"Over the first **{steps} steps** ({SPANS[span]}) the gap is **{gap:+.3f}** ± {gse:.3f} per step "
            f"({halves(None)}): " + "; ".join(parts) + ". "
            + dominance_sentence(m, span, None if rollouts is None else half_difference_se(
                rollouts, steps if span == "train_horizon" else None), k))


def after_horizon_training(rollouts: dict, H: int) -> tuple[float, float, int]:
    """Training's part of the gap over the steps AFTER the first ``H`` (the ones the actor's gradient
    never saw), per start: (mean, standard error over the starts, number of starts)."""
    def seg(key):
        r = np.asarray(rollouts[key].rewards, dtype=float)[H:]
        return np.nanmean(r, axis=0) if len(r) else np.full(r.shape[1], np.nan)
    x = (seg("dream_trained") - seg("dream_untrained")) - (seg("real_trained") - seg("real_untrained"))
    x = x[~np.isnan(x)]
    se = float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")
    return (float(x.mean()) if len(x) else float("nan")), se, int(len(x))


def split_story(m: dict, H: int, rollouts: dict | None = None, n: int | None = None) -> str:
    """What the two horizons say together about drift and exploitation (registered claims). With
    the run's ``rollouts``, training's part over the steps after the training horizon is measured
    on its own (:func:`after_horizon_training`)."""
    k = _k(m, n)
    words = test_words(k)
    tr_h, tr_e = m["gap_training_train_horizon"], m["gap_training_eval_horizon"]
    se_h, se_e = m["gap_training_se_train_horizon"], m["gap_training_se_eval_horizon"]
    drift_h, drift_se = m["gap_drift_train_horizon"], m["gap_drift_se_train_horizon"]
    s = ""
    exploits_h = training_exploits(value=tr_h, se=se_h, k=k, min_effect=MIN_REWARD_EFFECT)
    if exploits_h:
        gap_h = m["imagination_gap_train_horizon"]
        share = f", {tr_h / gap_h:.0%} of the gap over those steps" if gap_h > 0 else ""
        s += (f"Within the {H} steps its gradient saw, training made the dream rosier than it made reality "
              f"by {tr_h:+.3f} ± {se_h:.3f} per step ({words}{share}): that part the actor "
              "learned and only the dream pays for, which is exploitation. ")
    else:
        r = reading(tr_h, se_h, k, "training train_horizon, story")
        s += f"Within the {H} steps its gradient saw, training's part is {tr_h:+.3f} ± {se_h:.3f} per step: " + {
            "down": "training made the dream *gloomier* than it made reality, beyond the noise and the minimum "
                    "effect, so on this seed the actor did not exploit its dream. ",
            "small": f"beyond the noise ({_ratio(tr_h, se_h, k)} standard errors) but smaller than the minimum effect "
                     f"that matters, so it is not read as exploitation: within those {H} steps the actor did not "
                     "measurably exploit its dream. ",
            "none": f"within the noise (it would count when {words}): training did not make the dream measurably "
                    f"rosier than reality, and within those {H} steps the actor did not measurably exploit its dream. ",
            "up": ""}[r]
    exploits_e = training_exploits_eval(value=tr_e, se=se_e, k=k, min_effect=MIN_REWARD_EFFECT)
    re_ = "up" if exploits_e else reading(tr_e, se_e, k, "training eval_horizon, story")
    whole = f"Over the whole evaluation training's part is {tr_e:+.3f} ± {se_e:.3f}"
    if exploits_h:
        s += whole + {
            "up": ", still clearly positive: the actor's advantage in the dream lasts past its training horizon. ",
            "down": ": that advantage is reversed (clearly negative): over the whole run the trained actor's dream "
                    "is gloomier, against reality, than the untrained one's. ",
            "small": (": that advantage is gone from the whole run's mean, which is beyond the noise but smaller "
                      "than the minimum effect" + (" and below zero. " if tr_e < 0 else ". ")),
            "none": (": that advantage is not told apart from zero over the whole run (within the noise)"
                     + (", though its point value is at least the minimum effect: not resolved, which is not the "
                        "same as gone. " if abs(tr_e) >= MIN_REWARD_EFFECT else
                        ", and smaller than the minimum effect: it does not last. "))}[re_]
    elif exploits_e:
        s += whole + (", clearly positive: the trained actor's dream turns rosy only after the steps its gradient "
                      "saw. ")
    else:
        s += whole + " (" + describe(tr_e, se_e, "training eval_horizon, story (again)", k) + "). "
    if rollouts is not None and len(rollouts["dream_trained"].rewards) > H:
        v, se, _ = after_horizon_training(rollouts, H)
        ra = reading(v, se, k, "training after the training horizon")
        T = len(rollouts["dream_trained"].rewards)
        s += f"Over the steps its gradient never saw (steps {H + 1} to {T}) alone, training's part is {v:+.3f} ± {se:.3f}: " + {
            "up": "clearly positive, so there too the trained actor's dream is rosier, against reality, than the "
                  "untrained one's. ",
            "down": "clearly negative, so past its training horizon the trained actor's dream is *gloomier*, against "
                    "reality, than the untrained one's" + (": the advantage it learned within its horizon is "
                                                           "reversed after it. " if exploits_h else ". "),
            "small": ("beyond the noise but smaller than the minimum effect that matters: past its training horizon "
                      "the trained actor's dream is slightly " + ("gloomier" if v < 0 else "rosier")
                      + ", against reality, than the untrained one's, by less than matters. "),
            "none": "within the noise: past its training horizon this run cannot tell the trained actor's dream, "
                    "against reality, from the untrained one's. "}[ra]
    rd = "up" if drift_rosy(value=drift_h, se=drift_se, k=k, min_effect=MIN_REWARD_EFFECT) else \
        reading(drift_h, drift_se, k, "drift train_horizon, story")
    if rd == "up":
        s += (f"The drift, the model's own optimism with the pusher standing still, is {drift_h:+.3f} ± "
              f"{drift_se:.3f} per step already over the first {H} steps.")
    elif rd == "small":
        s += (f"With the pusher standing still, the dream differs from reality over the first {H} steps by "
              f"{drift_h:+.3f} ± {drift_se:.3f}: beyond the noise, but smaller than the minimum effect that "
              "matters, so it is not measurably rosier than reality over those steps.")
    elif rd == "down":
        s += (f"With the pusher standing still, the dream is *gloomier* than reality over the first {H} steps "
              f"({drift_h:+.3f} ± {drift_se:.3f}), not measurably rosier than reality over those steps.")
    else:
        s += (f"With the pusher standing still, the dream is not measurably rosier than reality over the "
              f"first {H} steps ({drift_h:+.3f} ± {drift_se:.3f}, within the noise).")
    return s


def min_of_mean_distance(rollout, dt: float = 0.1) -> tuple[float, float]:
    """(smallest mean block-to-target distance over time in m, the time in s it happens)."""
    d = np.linalg.norm(rollout.obs[:, :, 2:4], axis=-1).mean(1)
    i = int(np.argmin(d))
    return float(d[i]), i * dt


def typical_pose(data_mean) -> tuple[float, float]:
    """(distance to the target in m, |yaw error| in degrees) of the expert data's mean observation
    (``data.mean``, metres): the block pose a model that has lost track of it decodes nearest to
    (the normalised zero). The yaw is read off the mean (sin, cos) as the reward reads it."""
    data_mean = np.asarray(data_mean, dtype=float)
    return (float(np.linalg.norm(data_mean[2:4])),
            float(abs(np.degrees(np.arctan2(data_mean[4], data_mean[5])))))


def _yaw_deg(obs) -> np.ndarray:
    _, tee = obs_to_pose(obs)
    return np.degrees(tee[..., 2])


def dip_sentence(rollouts: dict, H: int, data_mean=None, dt: float = 0.1) -> str:
    """Read the over-time panels: where and when the trained dream's block comes closest, and
    whether, with nobody pushing, the dreamed block drifts toward the expert data's typical pose
    (in position and in yaw), and whether that pose is near the target (registered claims).

    Notebooks of an older release call it without ``data_mean``: they get the first part only."""
    d_min, t_min = min_of_mean_distance(rollouts["dream_trained"], dt)
    z_min, z_t = min_of_mean_distance(rollouts["dream_zero"], dt)
    end = float(np.linalg.norm(rollouts["dream_trained"].obs[-1, :, 2:4], axis=-1).mean())
    where = (f"inside the {H * dt:.1f} s the actor trained on" if t_min <= H * dt
             else f"after the {H * dt:.1f} s the actor trained on")
    s = (f"In the trained actor's dream the mean block distance is smallest, **{d_min:.3f} m**, at "
         f"**{t_min:.1f} s** ({where}), and ends the evaluation at **{end:.3f} m**; the zero-action "
         f"dream's smallest is {z_min:.3f} m at {z_t:.1f} s. ")
    if dream_block_drifts_back(t_min=t_min, horizon_s=H * dt, d_min=d_min, d_end=end, near=NEAR):
        s += "After its best moment the trained dream's block drifts back out. "
    if zero_dream_closer(zero_min=z_min, trained_min=d_min, near=NEAR):
        yt = float(np.abs(_yaw_deg(rollouts["dream_trained"].obs[-1])).mean())
        yz = float(np.abs(_yaw_deg(rollouts["dream_zero"].obs[-1])).mean())
        s += ("In distance, a pusher that never moves gets the dreamed block closer to the target than the trained "
              "actor does: the model's drift, not the actor, brings the dreamed block nearest the target's place. "
              f"Distance is half the reward: at the end the trained dream's T is {yt:.0f}° off the target angle, "
              f"the zero-action dream's {yz:.0f}°. ")
    if data_mean is None:
        return s
    # where does a dream with nobody pushing take the block? Toward the data's typical pose?
    data_mean = np.asarray(data_mean, dtype=float)
    t_dist, t_yaw = typical_pose(data_mean)
    mean_yaw = float(np.degrees(np.arctan2(data_mean[4], data_mean[5])))
    dz, rz = rollouts["dream_zero"].obs[-1], rollouts["real_zero"].obs[-1]
    dream_to = float(np.linalg.norm(dz[:, 2:4] - data_mean[2:4], axis=-1).mean())
    real_to = float(np.linalg.norm(rz[:, 2:4] - data_mean[2:4], axis=-1).mean())
    wrap = lambda a: np.abs((a - mean_yaw + 180.0) % 360.0 - 180.0)  # noqa: E731
    dream_yaw_to, real_yaw_to = float(wrap(_yaw_deg(dz)).mean()), float(wrap(_yaw_deg(rz)).mean())
    dz_err, rz_err = float(np.abs(_yaw_deg(dz)).mean()), float(np.abs(_yaw_deg(rz)).mean())
    s += (f"The expert data's mean block pose sits **{t_dist:.3f} m** from the target with a yaw error of "
          f"**{t_yaw:.0f}°**. With zero actions the real block stays where it spawned, "
          f"{float(rollouts['real_zero'].final_tee_dist.mean()):.3f} m from the target at {rz_err:.0f}° (means "
          f"over the starts); the dreamed one ends {float(rollouts['dream_zero'].final_tee_dist.mean()):.3f} m "
          f"away at {dz_err:.0f}°. ")
    pos = dream_drifts_to_data_position(dream_to_mean=dream_to, real_to_mean=real_to, near=SUCCESS_POS)
    yaw = dream_drifts_to_data_yaw(dream_to_mean_deg=dream_yaw_to, real_to_mean_deg=real_yaw_to, near_deg=NEAR_DEG)
    share = lambda a, b: f"{max(0.0, 1 - a / b):.0%} of the way" if b > 0 else "all the way"  # noqa: E731
    where_pos = (f"its position ends {dream_to:.3f} m from the data's mean block position, against "
                 f"{real_to:.3f} m for the real block ({share(dream_to, real_to)})")
    where_yaw = (f"its yaw ends {dream_yaw_to:.0f}° from the data's mean yaw, against {real_yaw_to:.0f}° "
                 f"for the real block ({share(dream_yaw_to, real_yaw_to)})")
    rule = (f"\"toward\" meaning at least {DRIFT_SHARE:.0%} of the way and more than the "
            f"{SUCCESS_POS * 100:.0f} cm / {NEAR_DEG:.0f}° success tolerances")
    if pos and yaw:
        s += (f"Left alone, the dreamed block drifts toward the data's typical pose, in position and in yaw ({rule}): "
              f"{where_pos}, and {where_yaw}. A model that loses track of the block decodes it somewhere typical. ")
    elif pos or yaw:
        moved, stayed = ("position", "yaw") if pos else ("yaw", "position")
        s += (f"Left alone, the dreamed block drifts toward the data's typical {moved} "
              f"({where_pos if pos else where_yaw}) but not toward its typical {stayed} "
              f"({where_yaw if pos else where_pos}; {rule}). ")
    else:
        s += (f"The dreamed block does not drift toward the data's typical pose ({rule}): {where_pos}, and "
              f"{where_yaw}; its drift goes somewhere else. ")
    if pos or yaw:
        spawn_dist = float(rollouts["real_zero"].final_tee_dist.mean())
        if typical_pose_near_target(typical_dist=t_dist, typical_yaw_deg=t_yaw, spawn_dist=spawn_dist,
                                    spawn_yaw_deg=rz_err):
            s += ("And that typical pose is near the target (less than half as far as the spawned blocks, "
                  "in distance and in yaw), so a drift toward it reads as progress in the dream.")
        else:
            s += ("That typical pose is not near the target by this measure (less than half as far as the "
                  "spawned blocks, in distance and in yaw), so the drift toward it is not, by itself, why "
                  "the dream is rosy.")
    return s


# --- across seeds --------------------------------------------------------------------------------
SEED_COLUMNS = [("imagination_gap", "gap", "+.3f"),
                ("imagination_gap_position_eval_horizon", "gap: position", "+.3f"),
                ("imagination_gap_yaw_eval_horizon", "gap: yaw", "+.3f"),
                ("imagination_gap_train_horizon", "gap, training horizon", "+.3f"),
                ("gap_drift_eval_horizon", "drift", "+.3f"), ("gap_training_eval_horizon", "training", "+.3f"),
                ("gap_training_train_horizon", "training, training horizon", "+.3f"),
                ("expert_signal_dream_train_horizon", "dream pays the expert, training horizon", "+.3f"),
                ("zero_dream_block_moved_train_horizon", "zero-action dream moves the block (m), training horizon",
                 ".3f"),
                ("expert_gap_train_horizon", "expert's own gap, training horizon", "+.3f"),
                ("real_pusher_at_wall_share", "real steps at a wall", ".0%"),
                ("real_final_tee_dist", "real tee-dist (m)", ".3f"), ("spawn_tee_dist", "spawn (m)", ".3f"),
                ("real_success_rate", "real success", ".0%")]


def seeds_table(metrics: dict) -> str:
    """The seeds side by side, a markdown table (columns ``SEED_COLUMNS``; the whole evaluation
    unless the column says otherwise; the expert column is expert minus zero actions per step)."""
    rows = ["| seed | " + " | ".join(c[1] for c in SEED_COLUMNS) + " |", "|---|" + "---|" * len(SEED_COLUMNS)]
    def cell(m, k, f):
        v = format(m[k], f)
        if k == "expert_signal_dream_train_horizon" and m["zero_dream_block_moved_train_horizon"] > SUCCESS_POS:
            v += " (invalid)"                 # the zero-action dream moves the untouched block beyond 2 cm
        return v

    rows += [f"| {s} | " + " | ".join(cell(m, k, f) for k, _, f in SEED_COLUMNS) + " |" for s, m in metrics.items()]
    return "\n".join(rows) + ("\n\n(invalid): the zero-action dream moves the untouched block more than the "
                              f"{SUCCESS_POS * 100:.0f} cm success tolerance on that seed, so \"more than standing "
                              "still\" is not a test of recognising success there; the expert's own gap is.")


def seeds_sentence(metrics: dict, rollouts: dict | None = None) -> str:
    """Seeds side by side: the range of the gap, what the largest one is made of, which half of
    the gap dominates on each seed (per-start noise when each seed's ``rollouts`` are given), and
    whether the drift is most of the gap on every seed."""
    gaps = {s: m["imagination_gap"] for s, m in metrics.items()}
    lo, hi = min(gaps.values()), max(gaps.values())
    big = max(gaps, key=gaps.get)
    mb = metrics[big]
    s = (f"Across seeds {', '.join(map(str, metrics))} the gap runs from **{lo:+.3f}** to **{hi:+.3f}** per step "
         f"and real success is zero on **{sum(m['real_success_rate'] == 0 for m in metrics.values())}/"
         f"{len(metrics)}** seeds. The largest gap is seed {big}'s: over the whole evaluation its drift is "
         f"{mb['gap_drift_eval_horizon']:+.3f} and training's part is {mb['gap_training_eval_horizon']:+.3f} "
         f"(± {mb['gap_training_se_eval_horizon']:.3f}); over the training horizon training's part is "
         f"{mb['gap_training_train_horizon']:+.3f} (± {mb['gap_training_se_train_horizon']:.3f}). ")
    halves = {s: dominant_half(m, "eval_horizon", None if rollouts is None else
                               half_difference_se(rollouts[s], None)) for s, m in metrics.items()}
    by = {h: [str(s) for s, v in halves.items() if v == h] for h in ("yaw", "position", None)}
    said = [f"yaw on seed{'s' * (len(by['yaw']) > 1)} {', '.join(by['yaw'])}" if by["yaw"] else "",
            f"position on seed{'s' * (len(by['position']) > 1)} {', '.join(by['position'])}" if by["position"] else "",
            f"neither, beyond the noise and the minimum effect, on seed{'s' * (len(by[None]) > 1)} "
            f"{', '.join(by[None])}" if by[None] else ""]
    s += ("Over the whole evaluation, the larger half of the gap (beyond k standard errors, Student's t, and the "
          "minimum effect) is " + "; ".join(x for x in said if x) + ". ")
    drifts = [m["gap_drift_eval_horizon"] for m in metrics.values()]
    s += (f"The drift alone ranges from {min(drifts):+.3f} to {max(drifts):+.3f}: "
          + ("on every seed it is at least half of the gap." if drift_most_every_seed(drifts=drifts, gaps=list(gaps.values()))
             else "on some seeds it is less than half of the gap."))
    return s
