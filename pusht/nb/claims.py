"""Claims about the learner's run, as named predicates on that run's numbers.

A sentence in notebooks 03-06 that states a fact about *this* run ("the actor exploits the dream",
"the gap shrank", "reality did not improve") is one of two kinds:

* **guarded**: the notebook evaluates the claim's predicate on the run's numbers and prints the
  sentence when it holds, and its true alternative when it does not;
* **fixed** (``fixed=True``): the sentence is printed as it stands, because it held on every seed
  ``make claims`` recorded. It is still evaluated on every run; if it fails on the learner's run,
  :func:`note_if_false` prints a visible note beneath it instead of letting it stand.

Every claim is registered here by the module that uses it (``@claim(...)`` on its predicate), so
:data:`REGISTRY` is the one list of them. Calling a predicate returns a bool and records the
evaluation (claim, the numbers it read, the outcome) in :data:`LEDGER`, and, when the environment
variable ``PUSHT_CLAIMS_LOG`` names a file, appends it there as one JSON line: that is how
``make claims`` (``scripts/claims.py``) collects the claims of notebooks 03-06 run on seeds 0-5
into ``benchmarks/claims.json``. ``tests/test_claims.py`` re-evaluates every recorded predicate on
its recorded numbers, and fails when a fixed claim is false on a recorded seed, when a registered
claim was never recorded, or when a predicate no longer gives the recorded outcome.

A predicate takes keyword arguments only, each a number (or a list of numbers, or a string), so the
record is plain JSON and the test can call it again on exactly what it saw.
"""

from __future__ import annotations

import functools
import json
import math
import os
from dataclasses import dataclass
from typing import Callable

LOG_ENV = "PUSHT_CLAIMS_LOG"


@dataclass(frozen=True)
class Claim:
    """One claim: ``name`` ("04.training_exploits"; the prefix is the notebook), what it ``says``
    when it holds, whether it is ``fixed`` text, and its ``predicate``."""

    name: str
    says: str
    fixed: bool
    predicate: Callable[..., bool]

    @property
    def notebook(self) -> str:
        return self.name.split(".", 1)[0]


REGISTRY: dict[str, Claim] = {}
LEDGER: list[dict] = []          # every evaluation in this process, in order


def _plain(v):
    """A JSON-safe copy of one input (floats kept exact; NaN and inf as strings json can read)."""
    if isinstance(v, bool) or v is None or isinstance(v, str):
        return v
    if hasattr(v, "tolist"):                                   # numpy scalars and arrays
        return _plain(v.tolist())
    if isinstance(v, int):
        return int(v)
    if isinstance(v, float) or hasattr(v, "__float__") and not hasattr(v, "__len__"):
        return float(v)
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    return [_plain(x) for x in v]


def claim(name: str, says: str, fixed: bool = False):
    """Register the decorated predicate as claim ``name``. Calling it (keyword arguments only)
    returns its bool and records the evaluation."""
    def register(predicate):
        old = REGISTRY.get(name)
        if old is not None and (old.predicate.__module__, old.predicate.__qualname__) != (
                predicate.__module__, predicate.__qualname__):     # a module reloaded may register again
            raise ValueError(f"claim {name!r} is registered twice ({old.predicate.__module__}."
                             f"{old.predicate.__qualname__} and {predicate.__module__}.{predicate.__qualname__})")
        REGISTRY[name] = Claim(name, says, fixed, predicate)

        @functools.wraps(predicate)
        def evaluate(**numbers) -> bool:
            inputs = {k: _plain(v) for k, v in numbers.items()}
            holds = bool(predicate(**inputs))
            record = {"claim": name, "holds": holds, "fixed": fixed, "inputs": inputs}
            LEDGER.append(record)
            path = os.environ.get(LOG_ENV)
            if path:
                with open(path, "a") as f:
                    f.write(json.dumps(record, allow_nan=True) + "\n")
            return holds

        evaluate.claim = REGISTRY[name]
        return evaluate

    return register


def note_if_false(holds: bool, evaluate) -> str:
    """The visible note that goes under a fixed sentence when its claim failed on this run ("" when
    it held): the chapter recorded it as true on every seed it ran, this run is an exception, and
    the numbers printed beside it are what was measured."""
    if holds:
        return ""
    c = evaluate.claim
    return (f"\n\n> **Note.** On this run the sentence above does not hold: *{c.says}* is false here "
            f"(claim `{c.name}`). The chapter checked it on seeds 0-5 (`make claims`); trust the "
            "numbers printed beside it, not the sentence.")


def load_all() -> dict[str, Claim]:
    """Import every notebook module that registers claims, and return the registry."""
    from . import actor, closing, gap, horizon  # noqa: F401  (importing registers their claims)

    return REGISTRY


def finite(*values) -> bool:
    """All values are finite numbers (a predicate's inputs may be NaN in a degenerate run)."""
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)
