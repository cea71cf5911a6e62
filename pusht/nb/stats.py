"""The notebooks' name for :mod:`pusht.stats` (the verdicts live on the package's ground floor, where
the gate and the planner read them too)."""

from ..stats import (LEVEL, MIN_REWARD_EFFECT, THIN_MARGIN, Test, beyond, clear_of_threshold,  # noqa: F401
                     count_rise_p, k_for, margin_words, outcome, paired, sign_test, t_quantile, welch, wilson)
