"""Notebook 06's measured changes: a quantity from one round (or run) to another with its test
(:class:`Change`, :func:`compare`), the gap's and the fixes' changes, the success counts, and
the metric keys and spans every sentence and figure of the notebook reads.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from ..metric_keys import GAP, RETURN, WM_RATIO, key
from .closing_claims import (_crossed, _size_fell, _size_rose, block_closer, block_farther, change_down,
                             change_up, gap_crossed_zero, gap_grew, gap_shrank, success_rose_claim)
from .gap_words import NEAR
from .stats import LEVEL, MIN_REWARD_EFFECT, Test, beyond, k_for, outcome as _test_outcome


# 1 mm: the resolution at which the model's errors are read as changed. Physically: a thirtieth of
# the pusher's radius (3 cm), a twentieth of the success radius (2 cm); it is also the package's
# threshold for "the block moved" (``prediction_error_vs_copy_last``'s ``block_moving_fraction``).
# Errors are RMSEs over hundreds of clips, but the metrics keep no spread for them.
ERR_RES = 1e-3


COUNT_P = (1 - LEVEL) / 2          # one-sided bar for a count's rise (see the module doc)


SPAN_KEYS = ("train_horizon", "eval_horizon")


@dataclass(frozen=True)
class Change(Test):
    """One quantity, measured twice: stats' ``Test`` (``diff`` = last minus first, its standard
    error ``se`` = sqrt of the sum of the two squared standard errors, the degrees of freedom, the
    threshold ``k``, the minimum effect that matters and the ``outcome`` "up", "down" or "same")
    plus the two values themselves, ``first`` and ``last``, with their own standard errors."""

    first: float = math.nan
    last: float = math.nan
    first_se: float = math.nan
    last_se: float = math.nan

    @property
    def crossed(self) -> bool:
        """Ended on the other side of zero, beyond k of its own standard errors at both ends."""
        return _crossed(self.first, self.first_se, self.last, self.last_se, self.k)

    @property
    def shrank(self) -> bool:
        """The size |value| fell by more than k standard errors and by at least the minimum effect,
        toward zero, not through it (a crossing beyond the noise is a change of sign)."""
        return _size_fell(self.first, self.first_se, self.last, self.last_se, self.k, self.min_effect)

    @property
    def grew(self) -> bool:
        """The size |value| rose by more than k standard errors and by at least the minimum effect."""
        return _size_rose(self.first, self.first_se, self.last, self.last_se, self.k, self.min_effect)

    def claims(self) -> dict:
        """The registered claims on this change, evaluated (and recorded): shrank, grew, crossed."""
        kw = dict(first=self.first, first_se=self.first_se, last=self.last, last_se=self.last_se, k=self.k)
        return {"shrank": gap_shrank(**kw, min_effect=self.min_effect),
                "grew": gap_grew(**kw, min_effect=self.min_effect),
                "crossed": gap_crossed_zero(**kw)}

    def direction(self) -> str:
        """"up", "down" or "same", decided by the registered claims ``06.change_up``/``_down``."""
        kw = dict(diff=self.diff, se=self.se, k=self.k, min_effect=self.min_effect)
        return "up" if change_up(**kw) else "down" if change_down(**kw) else "same"


def _outcome(diff: float, bar: float) -> str:
    if beyond(diff, bar, 1.0):
        return "up" if diff > 0 else "down"
    return "same"


TEST_NAME = "t-test on two means over the same evaluation starts, their standard errors added in quadrature"


def compare(first: float, first_se: float, last: float, last_se: float, n_starts: int,
            level: float = LEVEL, min_effect: float = 0.0) -> Change:
    """Did a mean over ``n_starts`` evaluation starts change from ``first`` to ``last``, given each
    one's standard error, beyond k standard errors and by at least ``min_effect``? (See the module
    doc for why this is conservative on shared starts.)"""
    se = float(math.sqrt(first_se ** 2 + last_se ** 2))
    k = k_for(int(n_starts), level)
    diff = float(last - first)
    return Change(diff=diff, se=se, df=float(n_starts - 1), k=k,
                  outcome=_test_outcome(diff, k * se, min_effect), min_effect=float(min_effect),
                  test=TEST_NAME, first=float(first), last=float(last), first_se=float(first_se),
                  last_se=float(last_se))


def metric_change(a: dict, b: dict, key: str, se_key: str, level: float = LEVEL,
                  min_effect: float = MIN_REWARD_EFFECT) -> Change:
    """``compare`` of ``a[key]`` (± ``a[se_key]``) and ``b[key]``, on ``b``'s evaluation starts,
    against ``min_effect`` (by default the minimum reward effect: these are rewards per step)."""
    return compare(a[key], a[se_key], b[key], b[se_key], int(b["eval_episodes"]), level, min_effect)


def _gap_keys(span: str, part: str | None = None) -> tuple[str, str]:
    if span not in SPAN_KEYS:
        raise ValueError(f"span must be one of {SPAN_KEYS}, got {span!r}")
    return key(GAP, part=part, span=span), key(GAP, se=True, part=part, span=span)


def gap_change(rounds: list, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap's change from round 0 to the last round (last minus round 0), over ``span``
    ("eval_horizon": the whole evaluation, ``imagination_gap``; or "train_horizon"), against the
    minimum reward effect ``MIN_REWARD_EFFECT``."""
    if len(rounds) < 2:
        raise ValueError(f"need round 0 and at least one later round, got {len(rounds)} round(s)")
    return metric_change(rounds[0], rounds[-1], *_gap_keys(span), level=level)


def fix_change(ref: dict, fix: dict, span: str = "eval_horizon", level: float = LEVEL) -> Change:
    """The gap of a fix (``fix``'s metrics) against the reference run ``ref``, over ``span``,
    against the minimum reward effect."""
    return metric_change(ref, fix, *_gap_keys(span), level=level)


def successes(m: dict) -> int:
    """Real successes out of the evaluation starts."""
    return int(round(m["real_success_rate"] * m["eval_episodes"]))


def success_rose(rounds: list) -> bool:
    """Exercise 3's "real success rises": more real successes after the last round than in
    round 0 (a success is an event: one counts, see the module doc). Claim ``06.success_rose``."""
    return success_rose_claim(before=successes(rounds[0]), after=successes(rounds[-1]))


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
    return key(RETURN, policy="trained", world="dream", span=span)


def _real_key(span: str) -> str:
    return key(RETURN, policy="trained", world="real", span=span)


def _series(rounds, key) -> list[float]:
    return [float(m[key]) for m in rounds]


def _arrow(values) -> str:
    return " -> ".join(f"{1000 * v:.1f}" for v in values) + " mm"


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
    return "closer" if block_closer(toward=t, bar=bar) else "farther" if block_farther(toward=t, bar=bar) else "same"


# --- the other two fixes --------------------------------------------------------------------------
def expert_ratio(m: dict, kind: str, dim: str) -> float:
    """The model's error over copy-last's on held-out expert data, ``kind`` "one_step" or
    "open_loop", for one observation dimension (``metrics.json`` or a loop round)."""
    for name in (key(WM_RATIO, kind=kind, dim=dim), key(WM_RATIO, data="expert", kind=kind, dim=dim)):
        if name in m:
            return float(m[name])
    raise KeyError(f"no {kind} copy-last ratio for {dim} in these metrics")
