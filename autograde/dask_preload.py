"""Dask worker preload: check, on every worker Dask starts, that this course's grader imports there.

    dask worker tcp://SCHEDULER:8786 --nworkers 2 --nthreads 1 --preload autograde.dask_preload

(run from a checkout of the course after ``make setup``, which installs the ``autograde`` package
with ``pusht``; see docs/scale.md, "Beyond one machine: Dask"). The coordinator's tasks call
``autograde.task.grade_task``; importing it here makes a worker without the course fail at start,
not at its first task.
"""

import autograde.task  # noqa: F401
