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
``make claims`` (``scripts/claims.py``) collects the claims of notebooks 03-06 run on seeds 0-9
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
    when it holds, whether it is ``fixed`` text, its ``predicate``, and, for a claim that reads a
    cause ("the pushing brought the block in", "training exploits the dream", "the loop taught the
    model"), the ``control`` it is judged against: the run that differs from the claimed cause's run
    only in that cause (one of :data:`CONTROLS`)."""

    name: str
    says: str
    fixed: bool
    predicate: Callable[..., bool]
    control: str | None = None

    @property
    def notebook(self) -> str:
        return self.name.split(".", 1)[0]


# The controls a causal claim may name: each isolates one cause.
CONTROLS = {
    "zero actions": "a pusher that never moves, from the same starts in the same model: what the dream does "
                    "on its own (isolates the pushing)",
    "the untrained actor": "the actor before training, same starts, same model: isolates what training added",
    "the scripted expert": "the expert's real actions replayed in the dream: isolates the dream's reading of pushes "
                           "that solve the task (valid only where the zero-action dream leaves an untouched "
                           "block in place)",
    "round 0": "the same model and actor before any round of the loop: isolates what the rounds added",
    "the state model": "the chapter's own world model, same data and actor training: isolates the fix",
    "the page's wiring": "the chapter page's gradient wiring, same model and seed: isolates the wiring",
    "the shortest horizon": "the same sweep at its shortest horizon: isolates the horizon",
    "reality": "the same policy from the same starts in the real simulator: isolates the model's error",
    "the model without the change": "the same world model trained with one change undone (the data, predicting "
                                    "changes, or the width), read on the same starts: isolates that change",
}
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


def claim(name: str, says: str, fixed: bool = False, control: str | None = None):
    """Register the decorated predicate as claim ``name``. Calling it (keyword arguments only)
    returns its bool and records the evaluation. ``control``: for a causal claim, the control it is
    judged against (a key of :data:`CONTROLS`)."""
    if control is not None and control not in CONTROLS:
        raise ValueError(f"claim {name!r}: unknown control {control!r} (one of {sorted(CONTROLS)})")

    def register(predicate):
        old = REGISTRY.get(name)
        if old is not None and (old.predicate.__module__, old.predicate.__qualname__) != (
                predicate.__module__, predicate.__qualname__):     # a module reloaded may register again
            raise ValueError(f"claim {name!r} is registered twice ({old.predicate.__module__}."
                             f"{old.predicate.__qualname__} and {predicate.__module__}.{predicate.__qualname__})")
        REGISTRY[name] = Claim(name, says, fixed, predicate, control)

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
            f"(claim `{c.name}`). The chapter checked it on seeds 0-9 (`make claims`); trust the "
            "numbers printed beside it, not the sentence.")


def load_all() -> dict[str, Claim]:
    """Import every module that registers claims (the ``<nb>_claims`` modules of notebooks 03-07,
    whose ``@claim`` predicates register on import), and return the registry."""
    from . import actor_claims, closing_claims, gap_claims, horizon_claims, planning_claims  # noqa: F401  (registers)

    return REGISTRY


def finite(*values) -> bool:
    """All values are finite numbers (a predicate's inputs may be NaN in a degenerate run)."""
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)


# --- one test per quantity ------------------------------------------------------------------------
# The (value, standard error) pairs a predicate's inputs may hold: a number judged against its noise.
MEASURED = (("value", "se"), ("first", "first_se"), ("last", "last_se"), ("first", "first_bound"),
            ("last", "last_bound"), ("diff", "se"), ("signal", "se"),
            ("gap", "se"), ("drift", "se"))


def measurements(inputs: dict) -> list[tuple[float, float, float | None, float | None]]:
    """The numbers a claim's evaluation judged against their noise: ``(|value|, se, k, min_effect, what)``
    for each pair of :data:`MEASURED` in ``inputs`` (k and min_effect None where the claim has none; ``what``
    the quantity's name where the claim was given one (input ``quantity``), else None)."""
    out = []
    label = inputs.get("quantity") or None       # a claim may name its quantity: two names, two quantities
    for v, e in MEASURED:
        if (v, e) == ("gap", "se") and "drift" in inputs:     # drift_half_of_gap: the se is the drift's
            continue
        if v in inputs and e in inputs and finite(inputs[v], inputs[e]):
            out.append((abs(float(inputs[v])), float(inputs[e]), inputs.get("k"), inputs.get("min_effect"), label))
    return out


def conflicts(records: list[dict], rel: float = 1e-9, se_rel: float = 1e-3) -> list[str]:
    """Pairs of evaluations in one notebook run that judged the same number with different tests.

    ``records``: claim evaluations (``LEDGER`` entries, or ``make claims`` rows with ``notebook`` and
    ``seed``). Two measurements are of the same quantity when their sizes agree to ``rel`` (and are not
    zero); they must then carry the same standard error (to ``se_rel``), k and minimum effect, or one
    notebook would say "shrank" and "did not fall" of one drop. ``se_rel``: the gap's standard error
    comes from each start's total reward, the error size's from each start's two halves added
    (``split.size_split``), which agree to float rounding (2e-4 relative seen), not to the bit;
    a test whose standard error moves by 0.1% moves its verdict only where |t| is within 0.1% of k.
    Returns one line per conflict."""
    seen: dict[tuple, list] = {}
    bad = []
    for r in records:
        run = (r.get("notebook", r["claim"].split(".", 1)[0]), r.get("seed"))
        for size, se, k, eff, label in measurements(r["inputs"]):
            if size == 0:
                continue
            for other_size, other_se, ok, oeff, olabel, name in seen.get(run, []):
                if label != olabel:         # named as two different quantities (or one named, one not)
                    continue
                if abs(size - other_size) <= rel * max(size, other_size):
                    same = (abs(se - other_se) <= se_rel * max(se, other_se, 1e-300)
                            and (k is None or ok is None or abs(k - ok) <= rel * max(k, ok))
                            and (eff is None or oeff is None or eff == oeff))
                    if not same:
                        bad.append(f"{run[0]} seed {run[1]}: {name} and {r['claim']} judge {size:.6g} with "
                                   f"(se {other_se:.6g}, k {ok}, min {oeff}) and (se {se:.6g}, k {k}, min {eff})")
            seen.setdefault(run, []).append((size, se, k, eff, label, r["claim"]))
    return bad
