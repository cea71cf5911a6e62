"""Notebook 06's figures, conclusions and self-checks: closing the gap with real data, and two fixes.

What comes in. ``rounds`` is ``pusht.loop``'s list of per-round metrics, in order (``loop.json``):
round 0 is the offline chapter run, each later round has collected real episodes with the current
policy plus exploration noise, trained the world model further on all data and the actor further
in it, and measured both worlds on the chapter's evaluation starts again. The two other fixes are
single offline runs, each a ``metrics.json`` dict: a world model that predicts changes
(``wm_predicts="delta"``) and an ensemble with MOPO's disagreement penalty. Their reference is the
chapter's single state model, which is also the loop's round 0.

Where every threshold comes from (no tolerance is typed in; the two physical constants below say
why they are what they are):

* **A gap, and a change of it.** Every gap carries its standard error over the evaluation starts
  (``imagination_gap_se_<span>``, from ``pusht.analysis.gap_split``). A change between two runs
  (round 0 and the last round, or a fix against the single model) is judged against
  sqrt(se_1^2 + se_2^2), the standard error of a difference of two independent means. The two runs
  use the SAME starts, and a start that is hard for one is likely hard for the other: the per-start
  gaps are positively correlated, the true standard error of the difference is smaller, and this
  test is conservative (it calls fewer changes than the paired test would; the metrics do not keep
  the per-start values that test needs). A change counts beyond ``k`` standard errors, k the
  two-sided 95% point of Student's t at eval_episodes - 1 degrees of freedom
  (:func:`pusht.nb.horizon.t_quantile`: 2.05 for 30 starts). A difference that large would turn up
  by chance, in a run that changed nothing, in about one comparison in 20 or fewer.
* **Which world moved the gap.** The dream's and reality's ratings (reward per step) carry no
  standard error of their own in the metrics. Their changes are compared with the same yardstick,
  k standard errors of the gap's change: a noise scale measured on these starts, not a test of
  either rating on its own; the sentences always state both numbers, so the reader can judge.
* **Counts** (real successes, episodes touching the block, out of the evaluation starts). A success
  is an event, not an estimate: one is enough to leave 0%, which is what Exercise 3 asks. Whether a
  rise could be luck is Fisher's exact test on the two counts (:func:`count_rise_p`), one-sided,
  against 2.5%, the same bar as one side of the two-sided 95% tests.
* **Where the block goes** (mean over starts of how far it moved, and of spawn distance minus final
  distance). The metrics keep no per-start spread, but they keep the largest displacement, and each
  start's values are bounded by it: a displacement lies in [0, max], and a start's change of
  distance to the target is at most its displacement (triangle inequality). That bounds their
  standard errors (:func:`displacement_se_bound`, :func:`toward_se_bound`); a change counts beyond
  k of these bounds. Conservative again: a real change may go uncalled, a called one is real.
* **The world model's errors** (RMSE in metres over many clips) carry no standard error either.
  ``ERR_RES``: a change of an error counts when it exceeds 1 mm.
* ``ARENA``: a dreamed pusher farther from the real one than the arena is wide is off the table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..env import ARENA_HALF, CONTROL_DT, OBS_NAMES, SUCCESS_POS
from ..selfcheck import Question
from .gap import NEAR
from .stats import LEVEL, Test, t_quantile
from . import figure

# 1 mm: the resolution at which the model's errors are read as changed. Physically: a thirtieth of
# the pusher's radius (3 cm), a twentieth of the success radius (2 cm); it is also the package's
# threshold for "the block moved" (``prediction_error_vs_copy_last``'s ``block_moving_fraction``).
# Errors are RMSEs over hundreds of clips, but the metrics keep no spread for them.
ERR_RES = 1e-3
# The arena is 2 * ARENA_HALF = 1 m wide: a dreamed pusher more than that away from the real one
# can no longer be anywhere on the table.
ARENA = 2 * ARENA_HALF
COUNT_P = (1 - LEVEL) / 2          # one-sided bar for a count's rise (see the module doc)
WORLD_COLORS = {"dream": "tab:purple", "real": "tab:orange"}
DATA_COLORS = {"policy": "tab:red", "expert": "tab:blue"}
DATA_LABELS = {"policy": "the policy's data", "expert": "held-out expert data"}
SPAN_KEYS = ("train_horizon", "eval_horizon")


# --- Exercise 3 ---------------------------------------------------------------------------------
EX3_OPTIONS = {
    "a": "The gap **shrinks** and real success **rises above 0%**: after the last round at least one "
         "real evaluation episode succeeds.",
    "b": "The gap **shrinks**, but real success **stays at 0%**: no real evaluation episode succeeds "
         "after the last round either.",
    "c": "The gap **does not shrink** beyond the noise (it stays within what the evaluation starts "
         "can tell apart, or it grows), and real success **stays at 0%**.",
    "d": "The gap **does not shrink** beyond the noise, yet real success **rises above 0%**.",
}
EX3_NOTE = ("\"Shrinks\" means: the gap's size |imagined minus real reward per step| over the whole "
            "evaluation is smaller after the last round than in round 0, by more than the noise of the "
            "two measurements allows (k standard errors of the change, k from Student's t over the "
            "evaluation starts). A gap that changes sign and ends larger than it started has not shrunk.")


@lru_cache(maxsize=None)
def k_for(n_starts: int, level: float = LEVEL) -> float:
    """The threshold in standard errors for a mean over ``n_starts`` evaluation starts: Student's t,
    two-sided ``level``, at n_starts - 1 degrees of freedom."""
    return t_quantile(n_starts - 1, level)


@dataclass(frozen=True)
class Change(Test):
    """One quantity, measured twice: horizon's ``Test`` (``diff`` = last minus first, its standard
    error ``se`` = sqrt of the sum of the two squared standard errors, the degrees of freedom, the
    threshold ``k`` and the ``outcome`` "up", "down" or "same", within k standard errors) plus the
    two values themselves, ``first`` and ``last``."""

    first: float = math.nan
    last: float = math.nan

    @property
    def shrank(self) -> bool:
        """The size |value| fell by more than k standard errors (toward zero, not through it)."""
        return abs(self.first) - abs(self.last) > self.k * self.se

    @property
    def grew(self) -> bool:
        """The size |value| rose by more than k standard errors."""
        return abs(self.last) - abs(self.first) > self.k * self.se


def _outcome(diff: float, bar: float) -> str:
    if abs(diff) > bar and diff != 0:
        return "up" if diff > 0 else "down"
    return "same"


def compare(first: float, first_se: float, last: float, last_se: float, n_starts: int,
            level: float = LEVEL) -> Change:
    """Did a mean over ``n_starts`` evaluation starts change from ``first`` to ``last``, given each
    one's standard error? (See the module doc for why this is conservative on shared starts.)"""
    se = float(math.sqrt(first_se ** 2 + last_se ** 2))
    k = k_for(int(n_starts), level)
    diff = float(last - first)
    return Change(diff=diff, se=se, df=float(n_starts - 1), k=k, outcome=_outcome(diff, k * se),
                  first=float(first), last=float(last))


def metric_change(a: dict, b: dict, key: str, se_key: str, level: float = LEVEL) -> Change:
    """``compare`` of ``a[key]`` (± ``a[se_key]``) and ``b[key]``, on ``b``'s evaluation starts."""
    return compare(a[key], a[se_key], b[key], b[se_key], int(b["eval_episodes"]), level)


def _gap_keys(span: str) -> tuple[str, str]:
    if span not in SPAN_KEYS:
        raise ValueError(f"span must be one of {SPAN_KEYS}, got {span!r}")
    return f"imagination_gap_{span}", f"imagination_gap_se_{span}"


def gap_change(rounds: list, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap's change from round 0 to the last round (last minus round 0), over ``span``
    ("eval_horizon": the whole evaluation, ``imagination_gap``; or "train_horizon")."""
    if len(rounds) < 2:
        raise ValueError(f"need round 0 and at least one later round, got {len(rounds)} round(s)")
    return metric_change(rounds[0], rounds[-1], *_gap_keys(span), level=level)


def fix_change(ref: dict, fix: dict, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap of a fix (``fix``'s metrics) against the reference run ``ref``, over ``span``."""
    return metric_change(ref, fix, *_gap_keys(span), level=level)


def successes(m: dict) -> int:
    """Real successes out of the evaluation starts."""
    return int(round(m["real_success_rate"] * m["eval_episodes"]))


def count_rise_p(before: int, after: int, n: int) -> float:
    """Fisher's exact test, one-sided: the chance of ``after`` or more out of ``n`` if both rounds
    had the same rate, given ``before + after`` events in all (hypergeometric tail)."""
    total = before + after
    denom = math.comb(2 * n, n)
    return float(sum(math.comb(total, x) * math.comb(2 * n - total, n - x)
                     for x in range(after, min(total, n) + 1)) / denom)


def success_rose(rounds: list) -> bool:
    """Exercise 3's "real success rises above 0%": more real successes after the last round than in
    round 0 (a success is an event: one counts, see the module doc)."""
    return successes(rounds[-1]) > successes(rounds[0])


def ex3_verdict(rounds: list) -> str:
    """Exercise 3's measured outcome, a letter of ``EX3_OPTIONS``: does the gap over the whole
    evaluation shrink beyond the noise (:attr:`Change.shrank` of :func:`gap_change`), and does real
    success rise?"""
    shrank, rose = gap_change(rounds).shrank, success_rose(rounds)
    return {(True, True): "a", (True, False): "b", (False, False): "c", (False, True): "d"}[(shrank, rose)]


# --- formatting ---------------------------------------------------------------------------------
def _se(se: float) -> str:
    return f"{se:.3f}" if se >= 0.001 or se == 0 else f"{se:.1e}"


def _pm(v: float, se: float) -> str:
    return f"{v:+.3f} ± {_se(se)}"


def _mm(x: float) -> str:
    return f"{1000 * x:.1f} mm"


def _ratio_words(c: Change) -> str:
    r = "many" if math.isinf(c.ratio) else f"{c.ratio:.1f}"
    return f"{r} standard errors; a change counts beyond {c.k:.2f}"


def _steps(m: dict, span: str) -> str:
    """'the first 15 steps' / 'all 100 steps', or 'the training horizon' where the metrics do not
    say how long it is (loop rounds do not carry ``imag_horizon``)."""
    if span == "eval_horizon":
        return f"all {m['eval_horizon']} steps"
    return f"the first {m['imag_horizon']} steps" if "imag_horizon" in m else "the training horizon"


def _short(m: dict, span: str) -> str:
    if span == "eval_horizon":
        return f"{m['eval_horizon']} steps"
    return f"{m['imag_horizon']} steps" if "imag_horizon" in m else "training horizon"


def _dream_key(span: str) -> str:
    return f"trained_dream_return_per_step_{span}"


def _real_key(span: str) -> str:
    return f"trained_real_return_per_step_{span}"


def sides(a: dict, b: dict, span: str = "eval_horizon") -> dict:
    """How each world's rating of the trained policy moved from run ``a`` to run ``b`` over ``span``.

    The gap is the dream's rating minus reality's, so ``gap_diff == dream - real`` exactly. A side
    counts as moved when its change exceeds ``yardstick``, k standard errors of the gap's change
    (the module doc says why that scale). Returns the changes, the yardstick and ``moved``, a dict
    ``{"dream": "up"|"down"|"same", "real": ...}``."""
    c = fix_change(a, b, span)
    d_dream = float(b[_dream_key(span)] - a[_dream_key(span)])
    d_real = float(b[_real_key(span)] - a[_real_key(span)])
    bar = c.k * c.se
    return {"dream": d_dream, "real": d_real, "gap": c.diff, "yardstick": bar,
            "moved": {"dream": _outcome(d_dream, bar), "real": _outcome(d_real, bar)}}


def _side_words(s: dict, a_name: str, b_name: str, a: dict, b: dict, span: str) -> str:
    """The sentence saying which world moved, with both numbers."""
    dk, rk = _dream_key(span), _real_key(span)
    text = (f"The dream's rating of the policy went from {a[dk]:+.3f} to {b[dk]:+.3f} per step ({s['dream']:+.3f}), "
            f"reality's from {a[rk]:+.3f} to {b[rk]:+.3f} ({s['real']:+.3f}), {a_name} to {b_name} "
            f"(yardstick for either: {s['yardstick']:.3f}, k standard errors of the gap's change). ")
    dream, real = s["moved"]["dream"], s["moved"]["real"]
    word = {"up": "rose", "down": "came down"}
    if dream != "same" and real == "same":
        text += (f"So the gap moved from the dream's side: the dream's rating {word[dream]}, reality's stayed "
                 "within the noise. ")
    elif dream == "same" and real != "same":
        text += (f"So the gap moved from reality's side: what the policy really earns "
                 f"{'rose' if real == 'up' else 'fell'}, the dream's rating stayed within the noise. ")
    elif dream != "same":
        same_way = dream == real
        text += ("Both worlds' ratings moved, " + ("in the same direction, so part of each cancels in the gap. "
                                                   if same_way else "in opposite directions. "))
    else:
        text += "Neither rating alone moved beyond that yardstick. "
    return text


# --- Exercise 3's reconciliation ------------------------------------------------------------------
def reconcile_text(rounds: list) -> str:
    """Exercise 3's measured outcome in words: the gap over the whole evaluation in round 0 and after
    the last round, its change against the noise, from which world's side it moved, the same at the
    training horizon, and real success."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), int(last["round"])
    c = gap_change(rounds)
    lines = [f"The gap over {_steps(last, 'eval_horizon')} (the whole evaluation, {n} starts): round 0 "
             f"{_pm(c.first, first['imagination_gap_se_eval_horizon'])}, after round {R} "
             f"{_pm(c.last, last['imagination_gap_se_eval_horizon'])} (imagined minus real reward per step)."]
    per_round = ", ".join(f"{m['imagination_gap']:+.3f}" for m in rounds)
    lines.append(f"Round by round: {per_round}.")
    s = (f"The change is {c.diff:+.3f} ± {_se(c.se)} ({_ratio_words(c)}). The standard error adds the two "
         "rounds' per-start standard errors in quadrature, as if the rounds had used independent starts; "
         "they used the same ones, so this is conservative. ")
    if c.shrank:
        s += f"The gap shrank: its size fell from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise."
    elif c.grew:
        s += f"The gap grew: its size rose from {abs(c.first):.3f} to {abs(c.last):.3f}, beyond the noise."
    elif c.outcome != "same":
        s += ("The gap moved beyond the noise, but through zero: its size did not fall by more than the noise "
              "allows, so it did not shrink.")
    else:
        s += "The gap did not change beyond the noise: it did not shrink."
    if np.sign(c.first) != np.sign(c.last) and c.outcome != "same":
        s += (f" It changed sign: in round 0 the dream rated the policy {'above' if c.first > 0 else 'below'} "
              f"reality, after round {R} {'above' if c.last > 0 else 'below'} it.")
    lines.append(s)
    lines.append(_side_words(sides(first, last), "round 0", f"round {R}", first, last, "eval_horizon").strip())
    if c.shrank and sides(first, last)["moved"] == {"dream": "down", "real": "same"}:
        lines.append("The dream came down to meet reality; reality did not rise to meet the dream. The model "
                     "stopped promising what this policy does not deliver, which is not the same as the policy "
                     "delivering more.")
    elif c.shrank and sides(first, last)["moved"] == {"dream": "same", "real": "up"}:
        lines.append("Reality rose to meet the dream: the policy earns more in the real world, and the model's "
                     "rating of it did not move.")
    ct = gap_change(rounds, "train_horizon")
    lines.append(f"Over {_steps(last, 'train_horizon')} (what the actor's gradient sees) the gap went "
                 f"{_pm(ct.first, first['imagination_gap_se_train_horizon'])} -> "
                 f"{_pm(ct.last, last['imagination_gap_se_train_horizon'])}: "
                 + ("it shrank beyond the noise." if ct.shrank else "it grew beyond the noise." if ct.grew
                    else "its size did not fall beyond the noise."))
    s0, s1 = successes(first), successes(last)
    succ = f"Real successes: {', '.join(f'{successes(m)}/{n}' for m in rounds)} (round 0 to round {R}). "
    if s1 > s0:
        p = count_rise_p(s0, s1, n)
        succ += ("Real success rose" + (" above 0%" if s0 == 0 else "") + f" (Fisher's exact test, one-sided p = "
                 f"{p:.3f}: " + ("beyond chance)." if p < COUNT_P else "with this few, it could be luck; rerun "
                                 "another seed before believing it)."))
    elif s0 == 0:
        succ += "Real success stayed at 0%."
    else:
        succ += (f"Real success did not rise (the options assume 0% in round 0; here round 0 already had "
                 f"{s0}/{n}).")
    lines.append(succ)
    lines.append(f"So the measured answer is ({ex3_verdict(rounds)}).")
    return "\n".join(lines)


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
            "open-loop block (mm)", "open-loop pusher (mm)"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def err(m, kind, part):
        return (f"{1000 * m[f'wm_policy_{kind}_{part}_err']:.1f} / "
                f"{1000 * m[f'wm_policy_{kind}_{part}_copy_err']:.1f}")

    for m in rounds:
        n = m["eval_episodes"]
        cells = [str(m["round"]), str(m.get("policy_episodes", "")),
                 _pm(m["imagination_gap_train_horizon"], m["imagination_gap_se_train_horizon"]),
                 _pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
                 f"{m['imagined_return_per_step']:+.3f}", f"{m['real_return_per_step']:+.3f}",
                 f"{successes(m)}/{n}", f"{m['real_episodes_touching_block']}/{n}",
                 f"{m['real_block_displacement']:.3f}", f"{m['real_block_toward_target']:+.3f}",
                 f"{m['real_pusher_at_wall_share']:.0%}",
                 err(m, "one_step", "block"), err(m, "one_step", "pusher"),
                 err(m, "open_loop", "block"), err(m, "open_loop", "pusher")]
        rows.append("| " + " | ".join(cells) + " |")
    rows.append("")
    rows.append("Gaps are imagined minus real reward per step, ± one standard error over the evaluation starts; "
                "dream and real are reward per step over the whole evaluation; the last four columns are the "
                "world model's RMSE on the policy's data (clips of that round's real evaluation rollouts, never "
                "trained on) against copying the last frame.")
    return "\n".join(rows)


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


def _series(rounds, key) -> list[float]:
    return [float(m[key]) for m in rounds]


def _arrow(values) -> str:
    return " -> ".join(f"{1000 * v:.1f}" for v in values) + " mm"


def model_error_sentence(rounds: list) -> str:
    """Does the world model's one-step error on the policy's data fall every round, and on expert
    data? Names every round's number (mm), the copy-last error on the same data, and the open-loop
    errors' overall direction."""
    R = rounds[-1]["round"]
    idx = [m["round"] for m in rounds[1:]]
    out = []
    for data in ("policy", "expert"):
        parts = []
        for part in ("block", "pusher"):
            v = _series(rounds, f"wm_{data}_one_step_{part}_err")
            parts.append(f"the {part}'s {_arrow(v)} ({trend_phrase(v, idx)})")
        where = ("On the policy's data (clips of each round's own real evaluation rollouts, never trained on)"
                 if data == "policy" else "On held-out expert data")
        out.append(f"{where} the world model's one-step error went: " + "; ".join(parts) + ".")
        if data == "policy":
            last = rounds[-1]
            rel = []
            for part in ("block", "pusher"):
                model, copy_ = last[f"wm_policy_one_step_{part}_err"], last[f"wm_policy_one_step_{part}_copy_err"]
                if model > copy_ + ERR_RES:
                    rel.append(f"the {part}'s is still {model / copy_:.1f}x copy-last's ({_mm(model)} vs {_mm(copy_)})"
                               if copy_ > 0 else f"the {part}'s is {_mm(model)}, copy-last's 0")
                elif model < copy_ - ERR_RES:
                    rel.append(f"the {part}'s beats copy-last ({_mm(model)} vs {_mm(copy_)})")
                else:
                    rel.append(f"the {part}'s is within 1 mm of copy-last's ({_mm(model)} vs {_mm(copy_)})")
            cb = _series(rounds, "wm_policy_one_step_block_copy_err")
            out.append(f"After round {R}, " + " and ".join(rel) + ". The data changed too: each round's policy "
                       f"data comes from that round's policy; copy-last's block error on it went {_arrow(cb)}, "
                       "a measure of how much the block moves in it.")
    ol = []
    for data in ("policy", "expert"):
        for part in ("block", "pusher"):
            v = _series(rounds, f"wm_{data}_open_loop_{part}_err")
            d = _outcome(v[-1] - v[0], ERR_RES)
            verb = {"down": "fell", "up": "rose", "same": "within 1 mm"}[d]
            ol.append(f"{DATA_LABELS[data]}, {part}: {_arrow([v[0], v[-1]])} ({verb})")
    out.append(f"Open-loop (the dream running alone through each clip), from round 0 to round {R}: "
               + "; ".join(ol) + ".")
    pol = [_outcome(rounds[-1][f"wm_policy_one_step_{p}_err"] - rounds[0][f"wm_policy_one_step_{p}_err"], ERR_RES)
           for p in ("block", "pusher")]
    exp = [_outcome(rounds[-1][f"wm_expert_{k}_{p}_err"] - rounds[0][f"wm_expert_{k}_{p}_err"], ERR_RES)
           for k in ("one_step", "open_loop") for p in ("block", "pusher")]
    share = ""
    if "train_clips" in rounds[0] and rounds[-1]["train_clips"] > 0:
        share = (f" (after round {R}, {1 - rounds[0]['train_clips'] / rounds[-1]['train_clips']:.0%} of its "
                 f"{rounds[-1]['train_clips']} training clips are the policy's)")
    if all(p == "down" for p in pol) and "up" in exp:
        out.append("So the model got better where the policy goes and worse, on some measures, where the expert "
                   f"went: its training data moved toward the policy's{share}.")
    elif all(p == "down" for p in pol):
        out.append("So the model got better where the policy goes, without losing ground on the expert's data.")
    elif "up" in pol:
        out.append("So more data of the policy's own did not make the model better on it at every measure.")
    return " ".join(out)


def displacement_se_bound(m: dict) -> float:
    """An upper bound on the standard error of ``real_block_displacement`` (a mean over the starts):
    each displacement lies in [0, max], so their variance is at most mean * (max - mean)
    (Bhatia-Davis), sample variance n / (n - 1) times that."""
    n, mu, top = m["eval_episodes"], m["real_block_displacement"], m["real_block_displacement_max"]
    return float(math.sqrt(max(mu * (top - mu), 0.0) / (n - 1)))


def toward_se_bound(m: dict) -> float:
    """An upper bound on the standard error of ``real_block_toward_target`` (a mean over the starts).

    Each start's spawn distance minus final distance is at most its displacement d_i (triangle
    inequality), so its mean square is at most mean(d^2) <= mean(d) * max(d); minus the squared
    mean, n / (n - 1) times, over n."""
    n, mu, top = m["eval_episodes"], m["real_block_displacement"], m["real_block_displacement_max"]
    t = m["real_block_toward_target"]
    return float(math.sqrt(max(mu * top - t ** 2, 0.0) / (n - 1)))


def toward_outcome(m: dict) -> str:
    """"closer", "farther" or "same": where the real block ends relative to where it spawned, on
    average, judged against k times :func:`toward_se_bound` (and at least ``NEAR``, 5 mm)."""
    bar = max(k_for(int(m["eval_episodes"])) * toward_se_bound(m), NEAR)
    t = m["real_block_toward_target"]
    return "closer" if t > bar else "farther" if t < -bar else "same"


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
    if t1 > t0:
        p = count_rise_p(t0, t1, n)
        s += f" (a rise {'beyond chance' if p < COUNT_P else 'that could be chance'}: Fisher's one-sided p = {p:.3f}). "
    elif t1 < t0:
        p = count_rise_p(t1, t0, n)
        s += f" (a fall {'beyond chance' if p < COUNT_P else 'that could be chance'}: Fisher's one-sided p = {p:.3f}). "
    else:
        s += ". "
    c = compare(first["real_block_displacement"], displacement_se_bound(first), last["real_block_displacement"],
                displacement_se_bound(last), n)
    s += (f"The block moved a mean {first['real_block_displacement']:.3f} m in round 0 and "
          f"{last['real_block_displacement']:.3f} m after round {R} (at most "
          f"{last['real_block_displacement_max']:.3f} m): "
          + {"up": "more, beyond the noise. ", "down": "less, beyond the noise. ",
             "same": "not told apart by these starts. "}[c.outcome])
    t = last["real_block_toward_target"]
    bound = toward_se_bound(last)
    out = toward_outcome(last)
    s += (f"After round {R} the block ends on average {abs(t):.3f} m {'closer to' if t >= 0 else 'farther from'} "
          f"the target than it spawned (standard error at most {bound:.3f} m): ")
    s += {"closer": "closer, beyond the noise. ", "farther": "farther, beyond the noise. ",
          "same": "not told apart from where it spawned. "}[out]
    s += (f"It ends {last['real_final_tee_dist']:.3f} m from the target on average; a success needs "
          f"{SUCCESS_POS:.2f} m. ")
    if c.outcome == "up" and out != "closer":
        s += ("The policy moves the block more, but not toward the target: touching the block is not yet "
              "pushing it where it should go.")
    elif out == "closer":
        s += "The policy pushes the block toward the target, measurably."
    return s.strip()


# --- the other two fixes --------------------------------------------------------------------------
def expert_ratio(m: dict, kind: str, dim: str) -> float:
    """The model's error over copy-last's on held-out expert data, ``kind`` "one_step" or
    "open_loop", for one observation dimension (``metrics.json`` or a loop round)."""
    for key in (f"wm_{kind}_ratio_{dim}", f"wm_expert_{kind}_ratio_{dim}"):
        if key in m:
            return float(m[key])
    raise KeyError(f"no {kind} copy-last ratio for {dim} in these metrics")


def _sign_word(v: float, se: float, k: float) -> str:
    return "rosier than reality" if v > k * se else "gloomier than reality" if v < -k * se \
        else "not told apart from reality"


def delta_sentence(state_m: dict, delta_m: dict) -> str:
    """The delta model against the state model: copy-last ratios on the block (one-step and
    open-loop, expert data), the gap at the training horizon and over the whole evaluation, the
    zero-action dream, and the pusher's replay error at the end of the evaluation."""
    n = int(delta_m["eval_episodes"])
    k = k_for(n)
    pos = ("tee_x", "tee_y")
    r = {name: {kind: [expert_ratio(m, kind, d) for d in pos] for kind in ("one_step", "open_loop")}
         for name, m in (("state", state_m), ("delta", delta_m))}
    all_dims = [expert_ratio(delta_m, "one_step", d) for d in OBS_NAMES]
    # a ratio of 1 is copy-last itself: the baseline, not a tolerance
    beats = all(np.isfinite(x) and x < 1 for x in all_dims)
    fmt = lambda xs: "/".join(f"{x:.2f}" for x in xs)        # noqa: E731
    s = (f"On held-out expert data, the delta model's block position error is {fmt(r['delta']['one_step'])} (x/y) "
         f"of copy-last's one step ahead and {fmt(r['delta']['open_loop'])} open-loop; the state model's "
         f"{fmt(r['state']['one_step'])} and {fmt(r['state']['open_loop'])}. ")
    s += ("One step ahead it beats copy-last on every dimension. " if beats else
          f"One step ahead it beats copy-last on {sum(np.isfinite(x) and x < 1 for x in all_dims)} of "
          f"{len(all_dims)} dimensions. ")
    gaps = []
    for span in SPAN_KEYS:
        g, se = delta_m[f"imagination_gap_{span}"], delta_m[f"imagination_gap_se_{span}"]
        gs = state_m[f"imagination_gap_{span}"]
        gaps.append((span, g, se))
        s += (f"Over {_steps(delta_m, span)} its gap is {_pm(g, se)} ({_sign_word(g, se, k)}; the state model "
              f"{gs:+.3f}). ")
    (_, g_tr, se_tr), (_, g_ev, se_ev) = gaps
    mood = {"rosier than reality": "rosy", "gloomier than reality": "gloomy"}
    w_tr, w_ev = _sign_word(g_tr, se_tr, k), _sign_word(g_ev, se_ev, k)
    if {w_tr, w_ev} == set(mood):
        s += (f"Its dream is {mood[w_tr]} over the span the actor trained on and {mood[w_ev]} over the whole "
              "evaluation: it changed sign on the way. ")
    d, dse = delta_m["gap_drift_eval_horizon"], delta_m["gap_drift_se_eval_horizon"]
    zd, spawn = delta_m["zero_action_dream_final_tee_dist"], delta_m["spawn_tee_dist"]
    s += (f"With zero actions its dream is {_pm(d, dse)} per step against reality ({_sign_word(d, dse, k)}; the "
          f"state model {state_m['gap_drift_eval_horizon']:+.3f}), and the untouched dreamed block ends "
          f"{zd:.3f} m from the target on average, where it spawned {spawn:.3f} m away")
    # NEAR (5 mm): an untouched real block does not move at all, so a dreamed one that ends more
    # than that away from its spawn distance was moved by the model alone
    s += (": the model moves a block nobody touches. " if abs(zd - spawn) > NEAR else ". ")
    e_tr, e_ev = delta_m["replay_pusher_err_train_horizon"], delta_m["replay_pusher_err_eval_horizon"]
    H = delta_m.get("imag_horizon")
    at_tr = f"after {H * CONTROL_DT:.1f} s" if H else "at the training horizon"
    secs = delta_m["eval_horizon"] * CONTROL_DT
    s += (f"Replaying the policy's real actions, its dreamed pusher is {e_tr:.3f} m off {at_tr} and "
          f"{e_ev:.3f} m off after {secs:.0f} s (state model: {state_m['replay_pusher_err_train_horizon']:.3f} "
          f"and {state_m['replay_pusher_err_eval_horizon']:.3f} m). ")
    if e_ev > ARENA:
        s += (f"That is farther than the arena is wide ({ARENA:.0f} m): the dreamed pusher has left the table. ")
    clip = delta_m["train_clip_steps"]
    if e_ev > state_m["replay_pusher_err_eval_horizon"]:
        s += (f"A change-predicting model adds each step's small error to all the earlier ones, and it trained on "
              f"{clip}-step clips: nothing in its training saw what {delta_m['dream_steps_per_train_clip']:.2f} "
              "times as many accumulated steps do. Beating copy-last one step ahead says nothing about that.")
    else:
        s += f"Over {delta_m['eval_horizon']} steps its accumulated changes stay no farther off than the state model's."
    return s


def ensemble_sentence(single_m: dict, ens_m: dict, penalty: float | None = None) -> str:
    """The ensemble (with MOPO's penalty) against the single model: its gap at both horizons, real
    return and successes, and its members' disagreement (m) against its error from reality.
    ``penalty``: the run's ``disagreement_penalty`` (reward per step per metre), if known."""
    n = int(ens_m["eval_episodes"])
    s = ""
    for span in SPAN_KEYS:
        c = fix_change(single_m, ens_m, span)
        word = {"up": "rosier than the single model's, beyond the noise",
                "down": "less rosy than the single model's, beyond the noise",
                "same": "not told apart from the single model's"}[c.outcome]
        s += (f"Over {_steps(ens_m, span)} the ensemble's gap is {_pm(c.last, ens_m[f'imagination_gap_se_{span}'])} "
              f"against the single model's {_pm(c.first, single_m[f'imagination_gap_se_{span}'])}: "
              f"{c.diff:+.3f}, {word} ({_ratio_words(c)}). ")
    sd = sides(single_m, ens_m)
    s += (f"Reality pays its policy {ens_m['real_return_per_step']:+.3f} per step, the single model's "
          f"{single_m['real_return_per_step']:+.3f} ({sd['real']:+.3f}; "
          + ("within" if sd["moved"]["real"] == "same" else "beyond")
          + f" the yardstick of {sd['yardstick']:.3f}); real successes {successes(ens_m)}/{n} against "
          f"{successes(single_m)}/{n}. ")
    if "wm_ensemble_disagreement_train_horizon" not in ens_m:
        return s + "These metrics hold no ensemble disagreement (a single model has none)."
    dis_tr, dis_ev = ens_m["wm_ensemble_disagreement_train_horizon"], ens_m["wm_ensemble_disagreement_eval_horizon"]
    err_tr, err_ev = ens_m["replay_block_err_train_horizon"], ens_m["replay_block_err_eval_horizon"]
    s += (f"Along its policy's evaluation dream the members disagree on where the block is by {dis_tr:.3f} m on "
          f"average over {_steps(ens_m, 'train_horizon')} and {dis_ev:.3f} m over {_steps(ens_m, 'eval_horizon')}; "
          f"their mean dream, replaying the policy's real actions, has the block {err_tr:.3f} m off reality at the "
          f"training horizon and {err_ev:.3f} m at the end. ")
    # the most cautious comparison the metrics allow: the larger disagreement figure against the
    # smaller error figure (the disagreement is a mean over steps, the error a value at one step)
    if max(dis_tr, dis_ev) < min(err_tr, err_ev):
        s += (f"The members are closer to each other than their mean is to reality (by a factor of at least "
              f"{min(err_tr, err_ev) / max(dis_tr, dis_ev):.1f}, the smaller error over the larger disagreement): most of the error is one they share, a bias "
              "of the data they all learned from, and a penalty on disagreement cannot see it. ")
    else:
        s += "Their disagreement is as large as their error from reality: here it does flag the error. "
    if penalty is not None:
        gap_tr = ens_m["imagination_gap_train_horizon"]
        s += (f"With a penalty of {penalty:g} per metre the actor paid about {penalty * dis_tr:.3f} per step of "
              f"dreamed reward over its training horizon, against a gap of {gap_tr:+.3f} there.")
    return s.strip()


# --- the conclusion -------------------------------------------------------------------------------
def _fix_line(name: str, ref: dict, fix: dict, ref_name: str) -> str:
    n = int(fix["eval_episodes"])
    c = fix_change(ref, fix)
    sd = sides(ref, fix)
    dream = (f"in the dream, its gap over the whole evaluation went {c.first:+.3f} -> {c.last:+.3f} against "
             f"{ref_name} ("
             + ("its size shrank beyond the noise" if c.shrank else "its size grew beyond the noise" if c.grew
                else "its size did not shrink beyond the noise")
             + (", and it changed sign" if c.outcome != "same" and np.sign(c.first) != np.sign(c.last) else "")
             + ")")
    real = (f"in reality, the policy earns {fix['real_return_per_step']:+.3f} per step against "
            f"{ref['real_return_per_step']:+.3f} ("
            + ("within" if sd["moved"]["real"] == "same" else "beyond") + f" the yardstick of {sd['yardstick']:.3f})"
            f" and succeeds {successes(fix)}/{n} times against {successes(ref)}/{n}")
    return f"**{name}**: {dream}; {real}."


def conclusion(rounds: list, state_m: dict, delta_m: dict, ens_m: dict) -> str:
    """What each fix bought in each world (gap and real return against the single state model, real
    successes), and, as open questions, what real success plausibly needs, each tied to a number."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), last["round"]
    lines = [_fix_line(f"The real-data loop ({R} round{'s' if R != 1 else ''}, "
                       f"{last.get('policy_episodes', '?')} real policy episodes)",
                       first, last, "round 0"),
             _fix_line("Predicting changes", state_m, delta_m, "the state model"),
             _fix_line("An ensemble with a disagreement penalty", state_m, ens_m, "the single model")]
    runs = {"the loop": last, "the delta model": delta_m, "the ensemble": ens_m}
    won = [name for name, m in runs.items() if successes(m) > 0]
    if won:
        lines.append("Real successes appeared with " + ", ".join(f"{w} ({successes(runs[w])}/{n})" for w in won)
                     + ": one seed and a few starts; rerun other seeds before calling it a fix.")
    else:
        lines.append("**No fix produced a single real success.** Closing a gap is not solving the task: the gap "
                     "can close from the dream's side alone.")
    k = k_for(n)
    open_ = [f"*Data the policy never collects.* The loop corrects the model only where its policy goes: after "
             f"round {R} the real block still ends {last['real_final_tee_dist']:.3f} m from the target on average "
             f"(a success needs {SUCCESS_POS:.2f} m). The expert's data reach the goal, but by the expert's "
             "actions; the states between, which a better policy would have to pass through with its own "
             "actions, are in neither data set, and nothing corrects the dream there. Exploration aimed at "
             "what the model does not know would plausibly be needed."]
    tr, tse = last["gap_training_train_horizon"], last["gap_training_se_train_horizon"]
    if tr > k * tse:
        open_.append(f"*Reward exploitation.* After round {R} training still makes the dream rosier than reality "
                     f"over the training horizon by {_pm(tr, tse)} per step, beyond the noise: the actor keeps "
                     "learning things only the model pays for, and a better actor would find more of them.")
    else:
        open_.append(f"*Reward exploitation.* After round {R} the gap's training term over the training horizon "
                     f"is {_pm(tr, tse)}, not told apart from zero; but a stronger actor searches harder, and "
                     "every model has errors to find.")
    dc = metric_change(first, last, "gap_drift_eval_horizon", "gap_drift_se_eval_horizon")
    d0se = first["gap_drift_se_eval_horizon"]
    causal = (f"*Causal confusion.* With zero actions the round-0 dream is {_pm(dc.first, d0se)} per step against "
              "reality")
    if dc.first > k * d0se:
        causal += (": rosy with a pusher that never moves. In the expert data the block moves only when pushed, "
                   "and then toward the target; a model can learn \"the block approaches the target\" without "
                   "the contact that causes it. ")
    else:
        causal += ". "
    causal += (f"After round {R} that drift is {_pm(dc.last, last['gap_drift_se_eval_horizon'])}: "
               + {"down": "it fell beyond the noise. ", "up": "it rose beyond the noise. ",
                  "same": "not changed beyond the noise. "}[dc.outcome])
    pc, ec = last["wm_policy_one_step_block_copy_err"], last["wm_expert_one_step_block_copy_err"]
    if dc.outcome == "down" and pc < ec:
        causal += (f"The policy's data, in which the block moves less (copy-last's one-step block error is "
                   f"{_mm(pc)} on them, {_mm(ec)} on the expert's), may have taught the model otherwise. ")
    causal += ("Whether a model has the cause right is tested only by data where the cause and its usual "
               "companions come apart.")
    open_.append(causal)
    lines.append("**Open: what real success would plausibly need.** These runs suggest, they do not show: "
                 + " ".join(open_))
    return "\n\n".join(lines)


# --- figures --------------------------------------------------------------------------------------
def _round_axis(ax, rounds):
    r = [m["round"] for m in rounds]
    ax.set_xticks(r)
    ax.set_xlabel("loop round (0 = the offline chapter run)")
    ax.set_xlim(min(r) - 0.4, max(r) + 0.4)


@figure
def fig_rounds(rounds: list):
    """Left: the gap per round over the training horizon and over the whole evaluation, ± one
    standard error over the starts. Right: the dream's and reality's rating per round (whole
    evaluation), with each round's real successes."""
    import matplotlib.pyplot as plt

    x = np.array([m["round"] for m in rounds], dtype=float)
    last = rounds[-1]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.4))
    ax = axes[0]
    for dx, span, color in ((-0.06, "train_horizon", "tab:cyan"), (0.06, "eval_horizon", "k")):
        g = _series(rounds, f"imagination_gap_{span}")
        se = _series(rounds, f"imagination_gap_se_{span}")
        ax.errorbar(x + dx, g, yerr=se, fmt="o-", color=color, capsize=4, lw=1.5,
                    label=f"over {_steps(last, span)} (± 1 standard error)")
    ax.axhline(0, color="gray", lw=1, ls="--", label="dream = reality")
    ax.set_ylabel("imagination gap\n(imagined minus real reward per step)")
    ax.set_title("The gap, round by round")
    ax.legend(fontsize=8, loc="best")
    _round_axis(ax, rounds)
    ax = axes[1]
    ax.plot(x, _series(rounds, "imagined_return_per_step"), "o-", color=WORLD_COLORS["dream"], lw=2,
            label="in the dream")
    real = _series(rounds, "real_return_per_step")
    ax.plot(x, real, "s-", color=WORLD_COLORS["real"], lw=2, label="in reality")
    for xi, yi, m in zip(x, real, rounds):
        ax.annotate(f"{successes(m)}/{m['eval_episodes']} solved", (xi, yi), textcoords="offset points",
                    xytext=(0, -14), ha="center", va="top", fontsize=8, color=WORLD_COLORS["real"])
    ax.margins(y=0.2)                                      # room for the success labels
    ax.set_ylabel("mean reward per step\n(0 = block on target)")
    ax.set_title(f"The two ratings the gap is the difference of ({_steps(last, 'eval_horizon')})")
    ax.legend(fontsize=8, loc="best")
    _round_axis(ax, rounds)
    fig.suptitle("Dreamer's real-data loop: collect with the policy, train the model on everything, dream again")
    fig.tight_layout()
    return fig


@figure
def fig_model_error(rounds: list):
    """The world model's one-step (top) and open-loop (bottom) RMSE per round, pusher (left) and
    block (right), on the policy's data and on held-out expert data; copy-last dashed."""
    import matplotlib.pyplot as plt

    x = [m["round"] for m in rounds]
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True)
    for i, kind in enumerate(("one_step", "open_loop")):
        for j, part in enumerate(("pusher", "block")):
            ax = axes[i, j]
            vals = []
            for data in ("policy", "expert"):
                model = _series(rounds, f"wm_{data}_{kind}_{part}_err")
                copy_ = _series(rounds, f"wm_{data}_{kind}_{part}_copy_err")
                vals += model + copy_
                ax.plot(x, model, "o-", color=DATA_COLORS[data], lw=2, label=f"world model, {DATA_LABELS[data]}")
                ax.plot(x, copy_, "o--", color=DATA_COLORS[data], lw=1.2, alpha=0.7,
                        label=f"copy-last, {DATA_LABELS[data]}")
            if all(v > 0 for v in vals):                   # log scale only where every value can go on it
                ax.set_yscale("log")
            ax.set_ylabel(f"{part} position RMSE (m)")
            ax.set_title(f"{'One step ahead' if kind == 'one_step' else 'Open loop (the dream alone)'}: {part}")
            _round_axis(ax, rounds)
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle("The world model's error, round by round: on the policy's data (red) and the expert's (blue)")
    fig.tight_layout()
    return fig


@figure
def fig_block(rounds: list):
    """What the real policy does to the block, per round: episodes touching it, how far it moved
    (mean, with the bound on its standard error, and the largest), and how much closer to the target
    it ends than it spawned (mean, with the bound on its standard error)."""
    import matplotlib.pyplot as plt

    x = np.array([m["round"] for m in rounds], dtype=float)
    n = rounds[-1]["eval_episodes"]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    ax = axes[0]
    ax.bar(x, _series(rounds, "real_episodes_touching_block"), 0.6, color="tab:green", alpha=0.8)
    ax.set_ylim(0, n)
    ax.set_ylabel(f"evaluation episodes touching the block (of {n})")
    ax.set_title("Does the pusher reach the block?")
    _round_axis(ax, rounds)
    ax = axes[1]
    ax.errorbar(x, _series(rounds, "real_block_displacement"), yerr=[displacement_se_bound(m) for m in rounds],
                fmt="o-", color="tab:green", capsize=4, label="mean (bar: bound on 1 standard error)")
    ax.plot(x, _series(rounds, "real_block_displacement_max"), "v", color="tab:green", mfc="none",
            label="largest")
    ax.set_ylim(0, None)
    ax.set_ylabel("block displacement, spawn to end (m)")
    ax.set_title("How far the block moves")
    ax.legend(fontsize=8, loc="best")
    _round_axis(ax, rounds)
    ax = axes[2]
    ax.errorbar(x, _series(rounds, "real_block_toward_target"), yerr=[toward_se_bound(m) for m in rounds],
                fmt="o-", color="tab:brown", capsize=4, label="mean (bar: bound on 1 standard error)")
    ax.axhline(0, color="gray", ls="--", lw=1, label="ends as far as it spawned")
    ax.set_ylabel("spawn distance minus final distance\nto the target (m; > 0 = closer)")
    ax.set_title("Does it move toward the target?")
    ax.legend(fontsize=8, loc="best")
    _round_axis(ax, rounds)
    fig.suptitle(f"The real block under each round's policy ({n} evaluation starts)")
    fig.tight_layout()
    return fig


@figure
def fig_fixes(state_m: dict, loop_last_m: dict, delta_m: dict, ens_m: dict, labels=None):
    """The three fixes beside the single state model: the gap over the training horizon and over the
    whole evaluation (± one standard error), and both worlds' ratings, real successes under the bars.
    ``labels``: four names for the runs, in the order of the arguments."""
    import matplotlib.pyplot as plt

    runs = [state_m, loop_last_m, delta_m, ens_m]
    labels = list(labels) if labels is not None else [
        "single model\n(loop round 0)", f"loop, after\nround {loop_last_m.get('round', '?')}",
        "delta model", "ensemble\n+ penalty"]
    if len(labels) != len(runs):
        raise ValueError(f"need {len(runs)} labels, got {len(labels)}")
    colors = ["tab:gray", "tab:green", "tab:blue", "tab:purple"]
    x = np.arange(len(runs), dtype=float)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    for ax, span in zip(axes[:2], SPAN_KEYS):
        g = [m[f"imagination_gap_{span}"] for m in runs]
        se = [m[f"imagination_gap_se_{span}"] for m in runs]
        ax.bar(x, g, 0.6, yerr=se, capsize=5, color=colors, alpha=0.85, label="gap ± 1 standard error")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_xlabel("run")
        ax.set_ylabel("imagination gap\n(imagined minus real reward per step)")
        ax.set_title(f"The gap over {_steps(state_m, span)}")
        ax.legend(fontsize=8, loc="best")
    ax = axes[2]
    for dx, world, key in ((-0.18, "dream", "imagined_return_per_step"), (0.18, "real", "real_return_per_step")):
        ax.bar(x + dx, [m[key] for m in runs], 0.36, color=WORLD_COLORS[world], alpha=0.85,
               label="in the dream" if world == "dream" else "in reality")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(x, [f"{lab}\n{successes(m)}/{m['eval_episodes']} solved" for lab, m in zip(labels, runs)],
                  fontsize=8)
    ax.margins(y=0.25)                                     # room for the legend below the bars
    ax.set_xlabel("run (real successes under each name)")
    ax.set_ylabel("mean reward per step\n(0 = block on target)")
    ax.set_title(f"Both worlds' ratings ({_steps(state_m, 'eval_horizon')})")
    ax.legend(fontsize=8, loc="lower right")
    fig.suptitle("Three fixes against the chapter's single state model, on the same evaluation starts")
    fig.tight_layout()
    return fig


# --- self-checks ----------------------------------------------------------------------------------
SELF_CHECKS = {
    "dream_side": Question(
        "Round after round, the loop's world model gets more accurate on the policy's own data, and the gap "
        "shrinks; yet the policy may earn no more in reality than before. How can both be true?",
        {"a": "They cannot: a more accurate model always yields a better policy",
         "b": "Trained on what this policy's actions really do, the model stops promising what they do not "
              "deliver: the dream's rating comes down to reality's. The gap is a difference, and it closes just "
              "as well when only the dream moves",
         "c": "The gap is measured on new evaluation starts each round, so the rounds cannot be compared"},
        "b", "The gap is imagined minus real return. Fitting the model to the policy's data fixes the imagined "
             "side for this policy; nothing in that makes the real side rise. Read both ratings, not only their "
             "difference."),
    "shared_bias": Question(
        "Three world models are trained on the same data, each from its own initial weights and batch order. "
        "Why can they agree closely with each other and still all be wrong about the policy's real data?",
        {"a": "Because the disagreement penalty trains the members to agree",
         "b": "Because what they learn is set by the data: where the data never show something, every member "
              "fills it in with the same regularity the data did show. Disagreement measures how their guesses "
              "differ, not how far their common guess is from reality",
         "c": "Because three members are too few to disagree at all"},
        "b", "Random initialisation and batch order make members differ only where the data leave them free. "
             "A bias the data put into all of them (blocks that approach the target, a pusher never at a wall) "
             "is shared, and a penalty on their spread cannot see it. The penalty shapes the actor, not the "
             "members."),
    "delta_runaway": Question(
        "A world model that predicts the change from one frame to the next beats copy-last one step ahead on "
        "every dimension, yet its 100-step dream runs metres away. How?",
        {"a": "One step ahead, each prediction starts from the true previous frame; in a dream each step adds its "
              "small error to the sum of all the earlier ones, with no true frame to pull it back, and training "
              "on 16-step clips never penalised what 100 accumulated steps do",
         "b": "The one-step error was measured on the training data",
         "c": "Copy-last is so weak that beating it means the model is wrong"},
        "a", "A one-step test anchors the model to the truth at every step; a dream never does. Summing changes "
             "has nothing that keeps the result inside the arena, while a model that decodes positions is pulled "
             "toward positions it was trained on."),
    "fixed_norm": Question(
        "The loop normalises every round's data with the mean and standard deviation of the EXPERT frames, "
        "fixed, rather than recomputing them on all the data seen so far. Why?",
        {"a": "To save the time it takes to compute a mean",
         "b": "Because the policy's data have the same mean and spread as the expert's",
         "c": "The world model and the actor keep training from last round's weights, which read normalised "
              "inputs: new statistics would change what every input number means under those weights. Fixed, "
              "a number means the same physical state in every round"},
        "c", "Continuing training assumes the inputs keep their meaning. Re-normalising would shift every input "
             "under trained weights at once, and a round's change could then come from the new scale rather "
             "than the new data. (The errors above are in metres either way.)"),
}
