"""The tripwire: a function the kernel ran that the grader could not run again is never a silent 0.

The verdict on a hidden test comes from the probe process (``probe.py``), which defines the graded
function again from the hand-in's cells (``recreate.py``). If that re-creation ever loses what
the kernel had (a constant, a class attribute, a file), an honest student would score 0 with a
hint that blames their code. So each failed verdict is compared with what the kernel did: where
the kernel ran the test cell to its end (the function was defined, the visible asserts on it
passed) and the probe could not define or run the function (not defined, setup errors, a name or
an import missing, out of time, the probe process failed), the score stays 0 but the verdict
carries a ``tripwire``: ``report.csv``, the class report's "Needs a human", the LMS import files
(the student waits, like a hand-graded answer) and the student's own page say so, and the
instructor decides (``manual_grade.py``).

The kernel is the student's, so a student can make the kernel look fine: that earns nothing
(the score stays 0) but an instructor's look, which is what the wire is for.
"""

from __future__ import annotations

import json

from . import cellcode

# case errors that say a name the kernel had is missing in the probe, not that the code is wrong
MISSING = ("NameError", "UnboundLocalError", "ImportError", "ModuleNotFoundError")


def _read(notebook_text: str | None):
    try:
        return json.loads(notebook_text) if notebook_text is not None else None
    except ValueError:
        return None


def kernel_ran(notebook_text: str, test_id: str) -> bool:
    """Did the kernel run ``test_id``'s cell to its end (executed, no error output)?"""
    return _ran(_read(notebook_text), test_id)


def _ran(nb, test_id: str) -> bool:
    for cell in nb.get("cells", []) if isinstance(nb, dict) else []:
        if not isinstance(cell, dict) or cellcode.gid(cell) != test_id or cell.get("cell_type") != "code":
            continue
        outputs = cell.get("outputs") if isinstance(cell.get("outputs"), list) else []
        return cell.get("execution_count") is not None and \
            not any(isinstance(o, dict) and o.get("output_type") == "error" for o in outputs)
    return False


def reason(verdict: dict, ran_in_kernel: bool) -> str | None:
    """Why this failed verdict needs a human (None: it does not)."""
    if verdict.get("passed") or not ran_in_kernel:
        return None
    kind = verdict.get("kind", "")
    missing = [e for e in verdict.get("errors", []) if e.split(":", 1)[0] in MISSING]
    if kind == "undefined":
        why = "the grader could not define it again from the cells above the test"
    elif kind in ("timeout", "unchecked"):
        why = "the grader could not run it again (" + ("out of time" if kind == "timeout" else "its probe failed") + ")"
    elif kind == "raised" and missing:
        why = f"run again by the grader it raised {missing[0][:120]}"
    else:
        return None
    return (f"your function ran in your notebook (the test cell ran to its end there), but {why}; "
            f"this 0 is not final: your instructor has been told and will decide")


def mark(verdicts: dict, notebook_text: str | None) -> None:
    """Add ``tripwire`` to each of one notebook's verdicts ({test id: verdict dict}) that needs it."""
    nb = _read(notebook_text) if any(not v.get("passed") for v in verdicts.values()) else None
    for test_id, v in verdicts.items():
        why = reason(v, _ran(nb, test_id))
        if why:
            v["tripwire"] = why
