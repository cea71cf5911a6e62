"""Where grading tasks run: a pool of threads here, or a Dask cluster, and how a class is split into tasks."""

from __future__ import annotations

import hashlib
import os
from concurrent.futures import ThreadPoolExecutor

from .task import grade_task


def _split(students: list, notebooks: dict, jobs: int) -> list:
    """(student, notebook names) tasks. With at least as many students as cores, one task per
    student (its notebooks run one after another); with fewer, each student's notebooks are split
    into that many tasks, so the cores stay busy even for one student."""
    groups = max(1, jobs // max(1, len(students)))
    tasks = []
    for s in students:
        names = sorted(notebooks[s])
        for g in range(min(groups, len(names))):
            tasks.append((s, names[g::groups]))          # 01, 03, 05 | 02, 04, 06 for two groups
    return tasks


def run_tasks(tasks: list, jobs: int, scheduler, submit_args, on_done, log=print) -> None:
    """Run grading tasks on the Dask cluster ``scheduler`` if given, else here, ``jobs`` at a time.
    ``submit_args(task)`` gives grade_task's arguments; ``on_done(task, result)`` takes each result
    (in this process, in the order they finish)."""
    if scheduler is not None:
        run_dask(tasks, scheduler, submit_args, on_done, log=log)
    else:
        run_local(tasks, jobs, submit_args, on_done)


def run_local(tasks: list, jobs: int, submit_args, on_done) -> None:
    """Run grading tasks in a pool of ``jobs`` threads here (each task is its own process)."""
    from concurrent.futures import as_completed

    with ThreadPoolExecutor(jobs) as pool:
        futures = {pool.submit(grade_task, *submit_args(task)): task for task in tasks}
        for f in as_completed(futures):
            on_done(futures[f], f.result())


def run_dask(tasks: list, scheduler, submit_args, on_done, log=print) -> None:
    """Run grading tasks on a Dask cluster: ``scheduler`` is its address or a ``distributed.Client``.

    Each task grades in a temporary private course on whichever worker runs it and returns its
    results; nothing is written on the worker's disk beyond that. A task whose worker dies is
    rescheduled by Dask on another worker (``retries`` covers a task that fails outright), and the
    results are merged here by student, so a student is counted once however often it ran."""
    from distributed import Client, as_completed

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        missing = client.run(_worker_can_grade)
        bad = {w: why for w, why in missing.items() if why}
        if bad:
            raise RuntimeError("these Dask workers cannot grade: " + "; ".join(f"{w}: {why}" for w, why in bad.items())
                               + ". Start each worker from a checkout of the course after `make setup`, with "
                               "`--preload autograde.dask_preload` (docs/scale.md, 'Beyond one machine: Dask').")
        futures, scattered = {}, {}

        def once(x):           # large arguments (the course, the shared stages) go to every worker once
            if isinstance(x, (bytes, dict)) and x:
                if id(x) not in scattered:
                    scattered[id(x)] = client.scatter(x, broadcast=True, hash=True)
                return scattered[id(x)]
            return x
        for i, task in enumerate(tasks):
            args = submit_args(task)
            args = (once(args[0]),) + args[1:6] + (once(args[6]),) + args[7:]
            f = client.submit(grade_task, *args, key=f"grade-{task[0]}-{i}-{hashlib.sha1(repr(task).encode()).hexdigest()[:8]}",
                              retries=2, pure=False)
            futures[f] = task
        for f in as_completed(futures):
            on_done(futures[f], f.result())
    finally:
        if not isinstance(scheduler, Client):
            client.close()


def _worker_can_grade() -> str:
    """Run on each Dask worker: '' if it can run grade_task, else why not."""
    import importlib.util

    for mod in ("autograde.task", "pusht", "nbgrader"):
        if importlib.util.find_spec(mod) is None:
            return f"cannot import {mod!r}"
    return ""


def default_jobs() -> int:
    """Grading tasks at once when none is asked for: one per core this process may run on (its CPU
    affinity, which a container's cpuset narrows, where the OS tells it; else every core).

    On a 2-core host, 3 tasks graded classes of 12, 16 and 40 students 6-8% faster than 2, since a task
    leaves its core idle while it waits (its kernel factory importing torch, a kernel starting); one
    task per core stays the default, as it keeps the load and the memory (a kernel, up to about 0.5 GB,
    per task) predictable. ``--jobs`` sets any other number (benchmarks/grading_wallclock.txt)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)
