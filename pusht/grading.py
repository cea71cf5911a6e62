"""The learner's side of the autograder: the last line of each hidden test cell.

    __import__("pusht.grading").grading.submit("reward_impl_tests", reward_from_obs)

It records nothing and decides nothing. Once a notebook is handed in, the grader runs the hidden
tests' probes on the function's definition in a process of its own (``pusht.grader``, which a
learner's kernel never imports), so outside grading this line does nothing and learners never
notice it; while nbgrader grades, it prints one line that the feedback page replaces with the
verdict. The mark on the package's own implementations of the exercises is ``pusht.reference``.
"""

from __future__ import annotations

import sys

from .reference import autograding


def submit(test_id: str, fn) -> None:
    """The last line of each hidden test cell. It records nothing: the grader runs the probes on
    ``fn``'s definition in a process of its own (see the module's doc). While nbgrader grades, it
    prints one line, which the feedback page replaces with the verdict."""
    if autograding():
        print(f"[graded outside this kernel] {test_id}: checked by the grader in a process of its own",
              file=sys.stdout)
