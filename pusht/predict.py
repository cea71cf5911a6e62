"""Predict, then run: the chapter's experiments refuse to run until you have committed to a guess.

Predicting before you watch is what makes an experiment teach. So each exercise has two halves:

    lock_prediction("ex1", "b", "The model got the block wrong, so ...")   # prints a receipt
    result = run_exercise("ex1", experiment)                              # refuses without a lock

The lock keeps the FIRST prediction (locking again prints the original receipt), also across
kernel restarts: locks are saved to ``.pusht_predictions.json`` in the working directory (or the
file named by ``$PUSHT_PREDICTIONS``). Every receipt and every run prints a timestamp, so the order
in which things happened is visible in the cell outputs, which is what the autograder reads. The
reconciliation is printed only after the experiment has run.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from pathlib import Path

CHOICES = ("a", "b", "c")
# Exercises with more options than the default three.
EXERCISE_CHOICES = {"ex1": ("a", "b", "c", "d"), "ex3": ("a", "b", "c", "d"), "ex4": ("a", "b", "c", "d")}
MIN_WORDS = 6


@dataclass(frozen=True)
class Prediction:
    exercise: str
    choice: str
    reason: str
    locked_at: str   # ISO time, UTC


_LOCKS: dict[str, Prediction] = {}
_RUNS: dict[str, str] = {}

# Receipt formats, also parsed by the autograder (autograde/grade.py): keep them stable.
LOCK_RECEIPT = "[prediction locked] {exercise}: ({choice}) at {locked_at}"
RUN_RECEIPT = "[experiment started] {exercise} at {started} (prediction locked at {locked_at})"


def store_path() -> Path:
    return Path(os.environ.get("PUSHT_PREDICTIONS", ".pusht_predictions.json"))


def _load_store() -> dict:
    try:
        return json.loads(store_path().read_text())
    except (OSError, ValueError):
        return {}


def _saved_lock(exercise: str) -> Prediction | None:
    if exercise not in _LOCKS:
        saved = _load_store().get(exercise)
        if saved:
            _LOCKS[exercise] = Prediction(**saved)
    return _LOCKS.get(exercise)


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def choices_of(exercise: str) -> tuple:
    """The letters ``exercise`` accepts."""
    return EXERCISE_CHOICES.get(exercise, CHOICES)


def lock_prediction(exercise: str, choice: str, reason: str) -> Prediction:
    """Record your prediction for ``exercise``: a choice (a letter: a, b or c, for Exercises 1 and 3 also
    d) and one real sentence of why.

    Raises ``ValueError`` with what is expected if the choice or the reason is not usable. The
    first valid lock is kept: calling again later prints the original receipt and changes nothing.
    """
    options = choices_of(exercise)
    if not isinstance(choice, str) or choice.strip().lower().strip("()") not in options:
        raise ValueError(f"choice must be one of {', '.join(options)} (a single letter); got {choice!r}")
    words = re.findall(r"[A-Za-z]{2,}", reason if isinstance(reason, str) else "")
    if len(words) < MIN_WORDS:
        raise ValueError(f"reason must be one real sentence (at least {MIN_WORDS} words) saying WHY "
                         f"you expect that; got {reason!r}")
    p = _saved_lock(exercise)
    if p is not None:
        print(f"[prediction already locked] {exercise}: ({p.choice}) at {p.locked_at}; the first "
              f"lock is kept")
        return p
    if exercise in _RUNS:
        print(f"[warning] {exercise}: the experiment already ran at {_RUNS[exercise]}; this lock "
              f"comes after it and the receipt says so")
    p = Prediction(exercise, choice.strip().lower().strip("()"), reason.strip(), _now())
    _LOCKS[exercise] = p
    try:
        store_path().write_text(json.dumps({**_load_store(), exercise: asdict(p)}, indent=1))
    except OSError:
        pass   # a read-only folder only loses persistence across restarts, never the lock itself
    print(LOCK_RECEIPT.format(**asdict(p)) + f"\n  reason: {p.reason}")
    return p


def prediction(exercise: str) -> Prediction | None:
    """The locked prediction for ``exercise``, or None."""
    return _saved_lock(exercise)


def run_exercise(exercise: str, experiment, *args, **kwargs):
    """Run ``experiment(*args, **kwargs)`` only if a prediction for ``exercise`` is locked."""
    if _saved_lock(exercise) is None:
        raise RuntimeError(f"{exercise}: lock your prediction first, e.g. "
                           f"lock_prediction({exercise!r}, 'a', 'one sentence of why'); "
                           f"the experiment runs only after that")
    started = _now()
    _RUNS.setdefault(exercise, started)
    print(RUN_RECEIPT.format(exercise=exercise, started=started, locked_at=_LOCKS[exercise].locked_at))
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
    """Forget every lock and run, in memory and on disk."""
    _LOCKS.clear()
    _RUNS.clear()
    store_path().unlink(missing_ok=True)
