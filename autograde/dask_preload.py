"""Dask worker preload: make the course's grader importable on this worker.

    dask worker tcp://SCHEDULER:8786 --nworkers 2 --nthreads 1 --preload autograde/dask_preload.py

(run from a checkout of the course after ``make setup``; see the README, "Grading a large class").
Dask imports this file on every worker it starts, restarted ones included, so ``grade.grade_task``,
which the coordinator's tasks call, resolves to this checkout's ``autograde/grade.py``.
"""

import sys
from pathlib import Path

HERE = str(Path(__file__).resolve().parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)
