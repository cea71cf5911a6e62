"""How notebooks 03-06 print a number in their sentences: one home for the formats they share.

A standard error or a threshold (:func:`num`), a value with its standard error (:func:`pm`,
:func:`pm_bold`), a test statistic against its k (:func:`tk`), a distance in millimetres
(:func:`mm`), and a ratio printed apart from its k (:func:`apart`). Changing one here changes
every notebook's sentences (and ``tests/test_notebooks.py`` compares them with the recorded ones).
"""

from __future__ import annotations

import math


def num(x: float) -> str:
    """A standard error or a threshold: 3 decimals, or 2 significant figures when smaller."""
    return f"{x:.3f}" if x == 0 or abs(x) >= 0.001 else f"{x:.1e}"


def pm(v: float, se: float) -> str:
    """'+0.123 ± 0.045': a signed value and its standard error."""
    return f"{v:+.3f} ± {num(se)}"


def pm_bold(t) -> str:
    """'**+0.123** ± 0.045': a test's difference (bold) and its standard error (``t``: a ``stats.Test``)."""
    return f"**{t.diff:+.3f}** ± {num(t.se)}"


def tk(t) -> str:
    """'|t| = 4.29 vs k = 4.30': the test statistic against its threshold, in short."""
    r = "many" if math.isinf(t.ratio) else f"{t.ratio:.2f}"
    return f"|t| = {r} vs k = {t.k:.2f}"


def mm(x: float) -> str:
    """A distance in metres, printed in millimetres ('12.3 mm')."""
    return f"{1000 * x:.1f} mm"


def apart(ratio: float, k: float) -> tuple[str, str]:
    """``ratio`` and ``k`` printed with the fewest decimals (2 to 4) that keep them apart."""
    for d in (2, 3, 4):
        a, b = f"{ratio:.{d}f}", f"{k:.{d}f}"
        if a != b:
            break
    return a, b
