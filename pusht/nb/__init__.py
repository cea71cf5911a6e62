"""Support modules of the six notebooks: one per notebook, each with the notebook's figures (one
function per figure, returning the ``matplotlib`` figure) and its self-check questions
(``SELF_CHECKS``, see ``pusht.selfcheck``), and the notebook's one import surface:

    world_model  notebook 01      reward   notebook 02      actor    notebook 03
    gap          notebook 04      horizon  notebook 05      closing  notebook 06

Notebooks 03-06 keep the rest in rooms named after them, re-exported by the notebook's module:

    <nb>_claims    the claims about the learner's run it registers (``@claim``; ``make claims``)
    <nb>_words     the sentences it prints, each reading guarded by a claim
    <nb>_exercise  its exercise: options, measured letter, reconciliation (gap, horizon, closing)
    actor_measure  what notebook 03 measures (gradient reach, detach effects, rise tests)
    gap_expert     notebook 04's controls in words (scripted expert, replayed pusher, data shift)
    closing_changes, closing_fixes, closing_summary
                   notebook 06's measured changes and metric keys; its fixes; its conclusion and summary

and the rooms they all share: ``session`` (the set-up cell's ``setup``), ``stats`` (the tests behind
every verdict, with the minimum effect that matters), ``fmt`` (how a number is printed in a
sentence), ``claims`` (the registry of claims about a run, checked by ``make claims``),
``timing`` (each notebook's measured time) and ``prose`` (the fixed words: self-checks, exercise
options and notes, read from one Markdown file per notebook in ``text/``).

Figure functions are named ``fig_*``. Every notebook's set-up cell is one call, ``setup`` (module
``pusht.nb.session``): the notebook's config, its folders under ``OUT``, and its ``show``::

    cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT, metrics="metrics/closing")

Keeping them here leaves the notebooks' code cells short, and lets the tests run every figure and
every conclusion without a kernel (``tests/test_nb_*.py``).
"""

from __future__ import annotations

import functools
import os

from pusht.reference import GRADING_ENV  # set by nbgrader while it runs a notebook


def figure(draw):
    """Mark a function that only draws a figure: while nbgrader runs the notebook it is not called.

    Figures grade nothing, and the notebooks' ``show`` neither saves nor displays them while
    grading; building them (axes, artists, ``tight_layout``'s text measurements) still cost time:
    not building them took the six autogrades of one correct hand-in from 10.5 s to 6-7 s
    (``benchmarks/grading_wallclock.txt``). So under nbgrader the decorated function returns None
    without running, and ``show(None, name)`` has nothing to close. Anything a figure function is
    given, a learner's reward function included, is therefore not evaluated for the figure while
    grading; what is graded is computed outside the figures, in every student's kernel. Outside
    nbgrader (the chapter, the tests) nothing changes.
    """
    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        if GRADING_ENV in os.environ:
            return None
        return draw(*args, **kwargs)

    return wrapper


from pusht.nb.session import Session, setup  # noqa: E402  (after figure, as the notebooks' face)

__all__ = ["GRADING_ENV", "Session", "figure", "setup"]
