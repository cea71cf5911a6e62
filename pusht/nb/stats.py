"""The tests behind every verdict of notebooks 04-06, in one place: Student's t without scipy, a
comparison's outcome, and the **minimum effect that matters**.

A verdict needs two things, and states both:

* **Significance**: the difference exceeds ``k`` standard errors, ``k`` the two-sided ``LEVEL``
  point of Student's t at the test's degrees of freedom (:func:`t_quantile`; 4.30 at 2 degrees of
  freedom, 2.05 at 29, 1.96 for a large sample). If nothing had changed, a difference that large
  would turn up by chance in about one comparison in 20.
* **Size**: the difference is at least ``min_effect``. A difference the noise cannot explain can
  still be too small to matter: with 0 successes in every run, a reward that moves by a few
  thousandths per step is not a policy that does anything different. For a reward per step the
  bar is :data:`MIN_REWARD_EFFECT`.

A comparison that passes the first and fails the second is reported as "detected, but smaller
than the minimum effect that matters" (:attr:`Test.detected` without :attr:`Test.matters`), never
as a change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..env import POS_SCALE, SUCCESS_POS

LEVEL = 0.95                 # two-sided confidence of every test

# The smallest change of a reward per step that these notebooks read as a change: the reward of
# holding the block the environment's success tolerance (SUCCESS_POS = 2 cm) nearer the target on
# every step. The reward's position term is -0.5 * distance / POS_SCALE, so 2 cm is 0.02 per step.
# (The yaw tolerance, 10 degrees, is worth 0.028 per step: the smaller of the two is the bar.)
MIN_REWARD_EFFECT = 0.5 * SUCCESS_POS / POS_SCALE


def _t_cdf(x: float, df: float, n: int = 4001) -> float:
    """P(T <= x) for Student's t with ``df`` degrees of freedom (x >= 0), by the trapezoid rule."""
    grid = np.linspace(0.0, x, n)
    log_c = math.lgamma((df + 1) / 2) - math.lgamma(df / 2) - 0.5 * math.log(df * math.pi)
    pdf = np.exp(log_c) * (1 + grid ** 2 / df) ** (-(df + 1) / 2)
    return 0.5 + float((pdf[1:] + pdf[:-1]).sum() * (grid[1] - grid[0]) / 2)


def t_quantile(df: float, level: float = LEVEL) -> float:
    """The two-sided ``level`` point of Student's t: |T| exceeds it with probability 1 - level.

    Computed by bisection on the t distribution's CDF (no scipy needed); ``df`` may be fractional
    (Welch's degrees of freedom are). df = 2 gives 4.30, df = 4 gives 2.78, df -> inf gives 1.96.
    """
    if not df > 0:
        raise ValueError(f"degrees of freedom must be positive, got {df}")
    target = 0.5 + level / 2
    lo, hi = 0.0, 1.0
    while _t_cdf(hi, df) < target:
        hi *= 2
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _t_cdf(mid, df) < target else (lo, mid)
    return (lo + hi) / 2


@lru_cache(maxsize=None)
def k_for(n_starts: int, level: float = LEVEL) -> float:
    """The threshold in standard errors for a mean over ``n_starts`` evaluation starts: Student's t,
    two-sided ``level``, at n_starts - 1 degrees of freedom (cached: every verdict asks for it)."""
    return t_quantile(n_starts - 1, level)


def outcome(diff: float, bar: float, min_effect: float = 0.0) -> str:
    """"up" or "down" when ``|diff|`` exceeds ``bar`` (k standard errors, or a resolution) and is at
    least ``min_effect``; otherwise "same"."""
    if abs(diff) > bar and abs(diff) >= min_effect and diff != 0:
        return "up" if diff > 0 else "down"
    return "same"


@dataclass(frozen=True)
class Test:
    """One comparison: ``diff`` (the mean, or the difference of two means), its standard error
    ``se``, the degrees of freedom ``df`` and the threshold ``k`` (in standard errors) of the test
    named by ``test``, the ``min_effect`` that matters, and the ``outcome``: "up", "down" or
    "same" (not beyond k standard errors, or smaller than the minimum effect)."""

    diff: float
    se: float
    df: float
    k: float
    outcome: str
    min_effect: float = 0.0
    test: str = "t-test"

    @property
    def ratio(self) -> float:
        """|diff| in standard errors (inf when the seeds agree exactly and diff is not 0)."""
        return abs(self.diff) / self.se if self.se > 0 else (math.inf if self.diff else 0.0)

    @property
    def detected(self) -> bool:
        """Beyond k standard errors: the noise does not explain it (whatever its size)."""
        return abs(self.diff) > self.k * self.se and self.diff != 0

    @property
    def matters(self) -> bool:
        """At least the minimum effect that matters (whatever the noise)."""
        return abs(self.diff) >= self.min_effect and self.diff != 0

    def why(self) -> str:
        """The test in words: which test, t and k, and the minimum effect, for a verdict's reader."""
        t = "many" if math.isinf(self.ratio) else f"{self.ratio:.2f}"
        s = (f"{self.test}: |t| = {t} standard errors against k = {self.k:.2f} (Student's t, "
             f"{LEVEL:.0%} two-sided, {self.df:.1f} degrees of freedom)")
        if self.min_effect > 0:
            s += f"; minimum effect that matters {self.min_effect:.3f}"
        return s


def _values(x) -> np.ndarray:
    v = np.asarray(list(x), dtype=float)
    if v.size < 2:
        raise ValueError(f"need at least two actor seeds to measure a spread, got {v.size}")
    return v


def sign_test(values, level: float = LEVEL, min_effect: float = 0.0) -> Test:
    """Is the mean of ``values`` (one per actor seed) above, below or not told apart from zero?

    One-sample t: standard error s / sqrt(n) with s the across-seed standard deviation, n - 1
    degrees of freedom.
    """
    v = _values(values)
    se = float(v.std(ddof=1) / np.sqrt(v.size))
    df = v.size - 1.0
    k = t_quantile(df, level)
    mean = float(v.mean())
    return Test(mean, se, df, k, outcome(mean, k * se, min_effect), min_effect, "one-sample t-test")


def welch(short, long, level: float = LEVEL, min_effect: float = 0.0) -> Test:
    """Did a quantity change between two groups of per-seed values, beyond their spread?

    Welch's t-test: the difference of the means (``long`` minus ``short``) against
    sqrt(s1^2/n1 + s2^2/n2), with Welch-Satterthwaite degrees of freedom, so the two groups may
    have different spreads and numbers of seeds.
    """
    a, b = _values(short), _values(long)
    v1, v2 = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    se = float(np.sqrt(v1 + v2))
    if v1 + v2 > 0:
        df = float((v1 + v2) ** 2 / (v1 ** 2 / (a.size - 1) + v2 ** 2 / (b.size - 1)))
    else:
        df = float(a.size + b.size - 2)
    k = t_quantile(df, level)
    diff = float(b.mean() - a.mean())
    return Test(diff, se, df, k, outcome(diff, k * se, min_effect), min_effect, "Welch's t-test")
