"""Predict, then run: the chapter's experiments refuse to run until you have committed to a guess.

Predicting before you watch is what makes an experiment teach. So each exercise has two halves:

    lock_prediction("ex1", "b", "The model got the block wrong, so ...")   # prints a receipt
    result = run_exercise("ex1", experiment)                              # refuses without a lock

The lock keeps the FIRST prediction (locking again prints the original receipt), and every receipt
and every run prints a timestamp, so the order in which things happened is visible in the cell
outputs. The reconciliation is printed only after the experiment has run.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime, timezone

CHOICES = ("a", "b", "c")
MIN_WORDS = 6


@dataclass(frozen=True)
class Prediction:
    exercise: str
    choice: str
    reason: str
    locked_at: str   # ISO time, UTC


_LOCKS: dict[str, Prediction] = {}
_RUNS: dict[str, str] = {}


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def lock_prediction(exercise: str, choice: str, reason: str) -> Prediction:
    """Record your prediction for ``exercise``: a choice (a, b or c) and one real sentence of why.

    Raises ``ValueError`` with what is expected if the choice or the reason is not usable. The
    first valid lock is kept: calling again later prints the original receipt and changes nothing.
    """
    if not isinstance(choice, str) or choice.strip().lower().strip("()") not in CHOICES:
        raise ValueError(f"choice must be one of {', '.join(CHOICES)} (a single letter); got {choice!r}")
    words = re.findall(r"[A-Za-z]{2,}", reason if isinstance(reason, str) else "")
    if len(words) < MIN_WORDS:
        raise ValueError(f"reason must be one real sentence (at least {MIN_WORDS} words) saying WHY "
                         f"you expect that; got {reason!r}")
    if exercise in _LOCKS:
        p = _LOCKS[exercise]
        print(f"[prediction already locked] {exercise}: ({p.choice}) at {p.locked_at}; the first "
              f"lock is kept")
        return p
    if exercise in _RUNS:
        print(f"[warning] {exercise}: the experiment already ran at {_RUNS[exercise]}; this lock "
              f"comes after it and the receipt says so")
    p = Prediction(exercise, choice.strip().lower().strip("()"), reason.strip(), _now())
    _LOCKS[exercise] = p
    print(f"[prediction locked] {exercise}: ({p.choice}) at {p.locked_at}\n  reason: {p.reason}")
    return p


def prediction(exercise: str) -> Prediction | None:
    """The locked prediction for ``exercise``, or None."""
    return _LOCKS.get(exercise)


def run_exercise(exercise: str, experiment, *args, **kwargs):
    """Run ``experiment(*args, **kwargs)`` only if a prediction for ``exercise`` is locked."""
    if exercise not in _LOCKS:
        raise RuntimeError(f"{exercise}: lock your prediction first, e.g. "
                           f"lock_prediction({exercise!r}, 'a', 'one sentence of why'); "
                           f"the experiment runs only after that")
    started = _now()
    _RUNS.setdefault(exercise, started)
    print(f"[experiment started] {exercise} at {started} (prediction locked at "
          f"{_LOCKS[exercise].locked_at})")
    result = experiment(*args, **kwargs)
    print(f"[experiment finished] {exercise} at {_now()}")
    return result


def has_run(exercise: str) -> bool:
    return exercise in _RUNS


def reconcile(exercise: str, measured_choice: str, explanation: str) -> None:
    """Print how the measured outcome compares with the locked prediction (only after a run)."""
    if exercise not in _RUNS:
        raise RuntimeError(f"{exercise}: run the experiment first; the reconciliation comes after it")
    p = _LOCKS[exercise]
    verdict = "matches" if p.choice == measured_choice else "differs from"
    print(f"Reconcile {exercise}: you predicted ({p.choice}); the measurement says ({measured_choice}), "
          f"which {verdict} your prediction.\n{explanation}")


def _reset_for_tests() -> None:
    _LOCKS.clear()
    _RUNS.clear()
