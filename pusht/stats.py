"""The tests behind every verdict of the notebooks, the gate and the planner, in one place: Student's t
without scipy, a comparison's outcome, and the **minimum effect that matters**.

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

from .env import POS_SCALE, SUCCESS_POS

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


def beyond(diff: float, se: float, k: float, min_effect: float = 0.0, sign: int = 0) -> bool:
    """THE verdict of every comparison in notebooks 03-06: ``diff`` is beyond ``k`` standard errors
    ``se`` AND at least ``min_effect`` in size (0: whatever its size), upward for ``sign`` +1,
    downward for -1, either way for 0. A difference of exactly 0 is never beyond; NaN never is."""
    d = diff * sign if sign else abs(diff)
    return d > k * se and d >= min_effect and d > 0


def outcome(diff: float, bar: float, min_effect: float = 0.0) -> str:
    """"up" or "down" when ``|diff|`` exceeds ``bar`` (k standard errors, or a resolution) and is at
    least ``min_effect``; otherwise "same"."""
    if beyond(diff, bar, 1.0, min_effect):
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
        return beyond(self.diff, self.se, self.k)

    @property
    def matters(self) -> bool:
        """At least the minimum effect that matters (whatever the noise)."""
        return abs(self.diff) >= self.min_effect and self.diff != 0

    def margin_words(self) -> str:
        """How far the test's decision is from the noise threshold, for an exercise's letter: |t| over k,
        and "thin" when it is within :data:`THIN_MARGIN` of 1 (another run could decide it the other way)."""
        return margin_words(self.ratio, self.k)

    def why(self) -> str:
        """The test in words: which test, t and k, and the minimum effect, for a verdict's reader."""
        t = "many" if math.isinf(self.ratio) else f"{self.ratio:.2f}"
        s = (f"{self.test}: |t| = {t} standard errors against k = {self.k:.2f} (Student's t, "
             f"{LEVEL:.0%} two-sided, {self.df:.1f} degrees of freedom)")
        if self.min_effect > 0:
            s += f"; minimum effect that matters {self.min_effect:.3f}"
        return s


# An exercise's letter hangs on a thin margin when |t| / k is within 10% of 1: at that distance a rerun
# on other seeds or starts moves t across k about as often as not.
THIN_MARGIN = 0.10


def clear_of_threshold(ratio: float, k: float) -> bool:
    """|t| (``ratio``) is more than :data:`THIN_MARGIN` away from ``k``, on either side: the decision is not
    one a rerun would flip about as often as not."""
    return math.isinf(ratio) or (k > 0 and abs(ratio / k - 1) > THIN_MARGIN)


def margin_words(ratio: float, k: float) -> str:
    """"decided with margin: |t| = 4.10, 1.9 times k = 2.18" or "a thin margin: ..." (``ratio`` = |t|)."""
    if math.isinf(ratio):
        return f"decided with margin: the values agree exactly, |t| is unbounded against k = {k:.2f}"
    r = ratio / k if k > 0 else math.inf
    words = (f"|t| = {ratio:.2f} is {r:.2f} times k = {k:.2f}")
    if abs(r - 1) <= THIN_MARGIN:
        return (f"a thin margin: {words}, within {THIN_MARGIN:.0%} of the threshold, so a rerun could decide the "
                "letter the other way")
    return f"decided with margin: {words} ({'beyond' if r > 1 else 'short of'} the threshold by over {THIN_MARGIN:.0%})"


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
    if se <= 1e-12 * max(1.0, float(np.abs(v).max())):      # the values agree to rounding: no spread at all
        se = 0.0
    df = v.size - 1.0
    k = t_quantile(df, level)
    mean = float(v.mean())
    return Test(mean, se, df, k, outcome(mean, k * se, min_effect), min_effect, "one-sample t-test")


def paired(short, long, level: float = LEVEL, min_effect: float = 0.0) -> Test:
    """Did a quantity change between two conditions measured on the SAME actor seeds (``short[i]`` and
    ``long[i]`` share seed i)? The one-sample t-test of the per-seed differences ``long - short``, n - 1
    degrees of freedom. Whatever each seed adds to both conditions alike cancels in its difference; in
    notebook 05 the gap is drift + motion + training with drift the same in every run and motion the same
    for one actor seed at every horizon, so the gap's change and the training term's change are, seed by
    seed, the same number, and this test gives them one verdict (Welch's test, which ignores the pairing,
    gave them two)."""
    a, b = _values(short), _values(long)
    if a.size != b.size:
        raise ValueError(f"a paired test needs the same seeds on both sides, got {a.size} and {b.size} values")
    t = sign_test(b - a, level, min_effect)
    return Test(t.diff, t.se, t.df, t.k, t.outcome, t.min_effect, "paired t-test over actor seeds")


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


def count_rise_p(before: int, after: int, n: int) -> float:
    """Fisher's exact test, one-sided: the chance of ``after`` or more out of ``n`` if both rounds
    had the same rate, given ``before + after`` events in all (hypergeometric tail)."""
    total = before + after
    denom = math.comb(2 * n, n)
    return float(sum(math.comb(total, x) * math.comb(2 * n - total, n - x)
                     for x in range(after, min(total, n) + 1)) / denom)


def wilson(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The Wilson score interval of a success rate, ``k`` successes in ``n`` trials, two-sided ``level``:
    ``(low, high)`` as fractions. Unlike k/n +- 1.96 se, it stays inside [0, 1] and is not zero-wide at
    0 or n successes (0 of 30 gives 0-11%, 10 of 30 gives 19-51%)."""
    if not 0 <= k <= n or n < 1:
        raise ValueError(f"need 0 <= k <= n and n >= 1, got k={k}, n={n}")
    from statistics import NormalDist

    z = NormalDist().inv_cdf(0.5 + level / 2)
    p, z2 = k / n, z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return max(0.0, centre - half), min(1.0, centre + half)
