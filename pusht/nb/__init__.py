"""Support modules of the six notebooks: one per notebook, each with the notebook's figures (one
function per figure, returning the ``matplotlib`` figure), the small named functions that draw
its conclusions from the measured numbers (thresholds derived from measured noise, with a comment
saying which), and its self-check questions (``SELF_CHECKS``, see ``pusht.selfcheck``).

    world_model  notebook 01      reward   notebook 02      actor    notebook 03
    gap          notebook 04      horizon  notebook 05      closing  notebook 06

Keeping them here leaves the notebooks' code cells short, and lets the tests run every figure and
every conclusion without a kernel (``tests/test_nb_*.py``).
"""
