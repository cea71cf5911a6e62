"""A notebook's session: its config, its folders under ``OUT``, and ``show`` for its figures.

Every notebook's set-up cell is one call, the same in all six but for the metrics folder::

    cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT, metrics="metrics/closing")

``GRADING`` is true while nbgrader runs the notebook (autograde, validate): the config is then the
reduced (smoke) one, and ``show`` neither saves nor displays a figure (figures grade nothing, and
drawing them was about a tenth of a graded notebook's time; ``pusht.nb.figure`` does not even build
them, so ``show`` may be handed None).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, NamedTuple

from pusht.config import Config, make_config
from pusht.reference import GRADING_ENV


class Session(NamedTuple):
    """What a notebook's later cells use; unpacked in the set-up cell into the names they use."""

    cfg: Config                 # the notebook's config (the smoke one while grading or with SMOKE)
    grading: bool               # nbgrader is running the notebook (the notebook's GRADING)
    cache: Path                 # OUT/cache: trained models shared by the notebooks (not created here)
    figs: Path                  # OUT/figures: where ``show`` saves (created)
    metrics: Path | None        # OUT/<metrics>: the notebook's json results (created), None if not asked for
    show: Callable              # show(fig, name): save under ``figs`` and display; while grading, only close


def setup(seed: int, smoke: bool, device: str, out, metrics: str | None = None) -> Session:
    """The session of a notebook run with parameters SEED, SMOKE, DEVICE, OUT (its parameters cell).

    ``metrics``: a folder under ``out`` for the notebook's json results (``"metrics"``,
    ``"metrics/closing"``), created; None (the default) for a notebook that writes none.
    """
    import matplotlib.pyplot as plt

    grading = GRADING_ENV in os.environ      # the autograder runs a reduced config
    out = Path(out)
    cfg = make_config(smoke=smoke or grading, seed=seed, device=device, out=out)
    figs = out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    metrics_dir = None
    if metrics is not None:
        metrics_dir = out / metrics
        metrics_dir.mkdir(parents=True, exist_ok=True)

    def show(fig, name: str) -> None:
        """Save a figure under FIGS (as ``name``) and show it. While grading, neither: the figure
        (None when ``pusht.nb.figure`` did not build it) is only closed."""
        if grading:
            plt.close(fig)
            return
        fig.savefig(figs / name, dpi=100)
        plt.show()

    return Session(cfg=cfg, grading=grading, cache=out / "cache", figs=figs, metrics=metrics_dir, show=show)
