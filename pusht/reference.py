"""What the package and its grader agree on: the mark on the exercises' implementations, and the
flag nbgrader sets while it runs a notebook.

Nothing here imports anything of the package, so any module can take these names without tying
itself to the grader: ``reward.py``, ``imagination.py``, ``evaluate.py``, ``ensemble.py`` and ``plan.py``
mark their exercise implementations with ``@reference``; the grader (``autograde/stripped.py``) finds
them by the mark and ships its probe process a copy of the package in which each only raises
``ReferenceRefused`` (``pusht/grader/probes.py`` says why).
"""

from __future__ import annotations

import os

GRADING_ENV = "NBGRADER_EXECUTION"   # set by nbgrader while it runs a notebook (autograde, validate)
AUTOGRADE = "autograde"              # ... its value while the autograder runs a student's notebook


class ReferenceRefused(RuntimeError):
    """The package's implementation of an exercise was called where the grader had removed it."""


def reference(exercise: str):
    """Mark a package function as the implementation of ``exercise`` (the function is unchanged)."""
    def mark(fn):
        fn.__pusht_reference__ = exercise
        return fn
    return mark


def grading() -> bool:
    """Whether nbgrader is running this notebook (autograding or validating it)."""
    return GRADING_ENV in os.environ


def autograding() -> bool:
    """Whether the autograder is running a student's notebook."""
    return os.environ.get(GRADING_ENV) == AUTOGRADE
