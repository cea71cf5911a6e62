"""Several runs of the pipeline at once, one per CPU core: the seeds and sweeps of notebooks 03-05.

    results = run_many([cfg.replace(seed=s) for s in (0, 1, 2)], cache_dir=CACHE, model_cache=CACHE)

Each run trains with one torch thread (``cfg.threads``), so a single run keeps one core busy and
leaves the others idle. The runs of a sweep do not depend on each other, so :func:`run_many` gives
each its own worker process and runs as many at once as the machine has cores. A worker runs the
very code a single :func:`pusht.dreamer.run` runs, seeded by its own config, so every number is
the one that run gives in this process (``tests/test_sweep.py`` checks it bit for bit); only the
wall-clock changes.

The longest runs start first (:func:`expected_work`: the steps their actors dream), so that no
long run is left to finish alone on one core at the end. :func:`start_many` starts the workers and
returns at once, leaving this process free for work of its own until it asks for the results
(notebook 03 trains the learner's agent in the kernel meanwhile).

With a stage cache (``model_cache``), runs that share a world model (the horizons and actor seeds
of notebook 05) wait for one worker to train it and then load it, instead of each training it
again. Without one, every run trains its own, as ``run`` does.

How many workers: ``workers``, else the ``PUSHT_WORKERS`` environment variable, else one per core
this process may use (its affinity, narrowed by a cgroup CPU quota such as Binder's), no more than
the free memory holds (``WORKER_BYTES`` each; a cgroup memory limit counts), and at most one per
run. One worker runs everything
here, in this process, with no pool at all, and that is the default in three cases: under nbgrader
(``NBGRADER_EXECUTION``: the grader already runs one student's kernel per core), on a GPU
(``cfg.device`` other than ``cpu``) and on a one-core machine.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from pathlib import Path
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from .config import Config
from .reference import grading
from .stage_cache import cached_file

WORKERS_ENV = "PUSHT_WORKERS"
# Each worker imports torch and trains one run at a time. Its peak resident memory at the default
# config was 343 MiB (benchmarks/bench_sweep.py, recorded in benchmarks/pipeline_wallclock.txt);
# budgeted with half as much again to spare.
WORKER_BYTES = 512 * 2**20


def _cgroup_dirs(controller: str) -> list:
    """The cgroup folders that may limit this process for ``controller`` ("cpu", "memory"): its own
    and each parent's, under both the cgroup v2 and the v1 layout."""
    root = Path("/sys/fs/cgroup")
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        return []
    dirs = []
    for line in lines:
        _, controllers, path = line.split(":", 2)
        names = controllers.split(",")
        if controllers == "":                                  # v2: one unified hierarchy
            base = root
        elif controller in names:                              # v1: its own mount
            base = root / controllers
            if not base.is_dir():
                base = root / controller
        else:
            continue
        here = Path(path)
        for p in (here, *here.parents):       # a container sees its own cgroup as "/", the host does not
            dirs.append(base / p.relative_to("/"))
    return [d for d in dict.fromkeys(dirs) if d.is_dir()]


def _read(path: Path) -> str | None:
    try:
        return path.read_text().strip()
    except OSError:
        return None


def cpu_quota() -> float | None:
    """The CPUs a cgroup quota gives this process (Binder and Kubernetes set one), None if none."""
    limits = []
    for d in _cgroup_dirs("cpu"):
        v2, quota, period = _read(d / "cpu.max"), _read(d / "cpu.cfs_quota_us"), _read(d / "cpu.cfs_period_us")
        try:
            if v2 and not v2.startswith("max"):
                q, p = v2.split()[:2]
                limits.append(int(q) / int(p))
            elif quota and period and int(quota) > 0 and int(period) > 0:
                limits.append(int(quota) / int(period))
        except ValueError:
            continue
    return min(limits) if limits else None


def available_memory() -> int | None:
    """Bytes this process may still use: the least of the machine's MemAvailable and each cgroup
    limit minus its use; None if none of them can be read."""
    free = []
    meminfo = _read(Path("/proc/meminfo")) or ""
    for line in meminfo.splitlines():
        if line.startswith("MemAvailable:"):
            free.append(int(line.split()[1]) * 1024)
    for d in _cgroup_dirs("memory"):
        for limit_file, use_file in (("memory.max", "memory.current"),
                                     ("memory.limit_in_bytes", "memory.usage_in_bytes")):
            limit, use = _read(d / limit_file), _read(d / use_file)
            if limit and use and limit.isdigit() and use.isdigit() and int(limit) < 2**60:
                free.append(max(int(limit) - int(use), 0))
    return min(free) if free else None


def usable_cores() -> int:
    """The cores this process may run on: those its affinity allows (a container's cpuset narrows
    them), or fewer where a cgroup CPU quota allows fewer (whole CPUs only); at least 1."""
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):       # macOS and Windows have no sched_getaffinity
        cores = os.cpu_count() or 1
    quota = cpu_quota()
    if quota is not None:
        cores = min(cores, int(quota))
    return max(cores, 1)


def default_workers(cfgs) -> int:
    """How many runs of ``cfgs`` to run at once when the caller does not say (module doc)."""
    value = os.environ.get(WORKERS_ENV, "").strip()
    if value:
        if not value.isdigit() or int(value) < 1:
            raise ValueError(f"{WORKERS_ENV} must be a whole number of worker processes, 1 or more "
                             f"(1 runs everything in this process); got {value!r}")
        return int(value)
    if grading() or any(c.device != "cpu" for c in cfgs):
        return 1
    threads = max(max(c.threads for c in cfgs), 1)
    workers = usable_cores() // threads
    free = available_memory()
    if free is not None:
        workers = min(workers, free // WORKER_BYTES)
    return max(workers, 1)


def describe(cfg: Config) -> str:
    """A short name for one run of a sweep, for progress bars and error messages."""
    base = Config()
    changed = [f"{k}={getattr(cfg, k)}" for k in ("seed", "actor_seed", "imag_horizon", "critic_wiring",
                                                  "ensemble_size", "disagreement_penalty")
               if getattr(cfg, k) != getattr(base, k) or k == "seed"]
    return ", ".join(changed)


def _world_model_task(cfg, cache_dir, model_cache):
    """In a worker: train (or load) the world-model stage of ``cfg`` into the cache; return nothing."""
    from .wm_stage import world_model_stage

    world_model_stage(cfg, cache_dir, model_cache, log=None)


def _run_task(cfg, cache_dir, model_cache):
    from .dreamer import run

    return run(cfg, cache_dir=cache_dir, model_cache=model_cache, log=None)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Stop a pool now: drop what has not started and end the workers (their runs are lost)."""
    terminate = getattr(pool, "terminate_workers", None)      # Python 3.14+
    if terminate is not None:
        terminate()
        return
    # Before 3.14 the workers are ended by hand; shutdown() forgets them, so they are read first.
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.terminate()


def expected_work(cfg: Config) -> int:
    """How long a run of ``cfg`` takes, relatively: the dreamed steps its actor trains on (updates x
    dreams x horizon, times the ensemble's members). A horizon-30 run of notebook 05 takes about twice
    a horizon-15 one. Only the order matters: :func:`start_many` starts the longest runs first."""
    return cfg.imag_iters * cfg.imag_batch * cfg.imag_horizon * cfg.ensemble_size


class Sweep:
    """The runs of :func:`start_many`: the pooled ones are under way in worker processes from the
    start; :meth:`results` runs the others in this process and waits for all of them.

    Use it as a context manager where this process has work of its own meanwhile: leaving the block
    with an error, or without having collected the results, stops the workers."""

    def __init__(self, cfgs, cache_dir, model_cache, workers: int | None, desc: str):
        from .agent_stage import AGENT_FIELDS
        from .stage_cache import stage_path
        from .wm_stage import WM_FIELDS

        self.cfgs, self.cache_dir, self.model_cache, self.desc = cfgs, cache_dir, model_cache, desc
        self._results: list = [None] * len(cfgs)
        self._done = False
        self._pool = None
        self._jobs: dict = {}               # future -> ("wm", path) or ("run", index)
        self._waiting: dict = {}            # world-model cache path -> indices of the runs that need it
        self._cond = threading.Condition(threading.RLock())   # guards _jobs; told of each new run
        self._start_error = None            # (what, error) if a waiting run could not be started

        # A worker takes about 2 s to start, more than a smoke run or a run whose trained agent is in
        # the cache (only its evaluation is left): those run here.
        def agent_cached(c):
            path = stage_path(model_cache, "agent", c, AGENT_FIELDS, "pusht.agent_stage")
            return path is not None and cached_file(path) is not None

        pooled = [i for i, c in enumerate(cfgs) if not c.smoke and not agent_cached(c)]
        if workers is None or workers < 2 or len(pooled) < 2:
            pooled = []
        self.here = sorted(set(range(len(cfgs))) - set(pooled))
        self.pooled = sorted(pooled, key=lambda i: -expected_work(cfgs[i]))    # longest first
        if not self.pooled:
            return

        # Runs that share an uncached world model wait for one task to train it (keyed as its cache is).
        ready: list = []
        for i in self.pooled:
            path = stage_path(model_cache, "wm", cfgs[i], WM_FIELDS, "pusht.wm_stage")
            if path is None or cached_file(path) is not None:
                ready.append(i)
            else:
                self._waiting.setdefault(path, []).append(i)
        self._pool = ProcessPoolExecutor(max_workers=min(workers, len(self.pooled)),
                                         mp_context=multiprocessing.get_context("spawn"))
        with self._cond:
            for path, indices in self._waiting.items():
                fut = self._pool.submit(_world_model_task, cfgs[indices[0]], cache_dir, model_cache)
                self._jobs[fut] = ("wm", path)
                fut.add_done_callback(lambda f, path=path: self._world_model_done(f, path))
            for i in ready:
                self._submit_run(i)

    def _submit_run(self, i: int) -> None:
        with self._cond:
            self._jobs[self._pool.submit(_run_task, self.cfgs[i], self.cache_dir, self.model_cache)] = ("run", i)
            self._cond.notify_all()

    def _world_model_done(self, fut, path) -> None:
        """A world model is in the cache: start the runs that waited for it at once, even while this
        process is busy with work of its own (called in the pool's own thread)."""
        if fut.cancelled() or fut.exception() is not None:
            return                          # results() raises its error
        for i in self._waiting[path]:
            try:
                self._submit_run(i)
            except Exception as e:  # noqa: BLE001  the pool broke, or is being stopped: results() says so
                with self._cond:
                    self._start_error = self._start_error or (("run", i), e)
                    self._cond.notify_all()
                return

    def _what(self, kind: str, key) -> str:
        return (f"the world model of {describe(self.cfgs[self._waiting[key][0]])}" if kind == "wm"
                else f"the run {describe(self.cfgs[key])}")

    def results(self, progress=None) -> list:
        """Run this process's share, wait for the workers' and return every run's
        :class:`~pusht.dreamer.RunResult`, in the order of the configs. A run that raised stops the
        sweep: its error is raised here, with the run named."""
        from .dreamer import run

        if self._done:
            return self._results
        try:
            for i in self.here:
                self._results[i] = run(self.cfgs[i], cache_dir=self.cache_dir, model_cache=self.model_cache,
                                       log=None, progress=progress)
            if self._pool is not None:
                self._collect(progress)
        except BaseException:           # an error or an interrupt: nothing else is worth waiting for
            self.cancel()
            raise
        self._done = True
        return self._results

    def _collect(self, progress) -> None:
        bar = progress(total=len(self.pooled), desc=self.desc) if progress else None
        remaining = set(self.pooled)
        try:
            while remaining:
                with self._cond:
                    if self._start_error is not None:
                        (kind, key), error = self._start_error
                        self._raise(kind, key, error, where="while this process started")
                    if not self._jobs:      # a world model just finished: its runs are being submitted
                        self._cond.wait(timeout=1.0)
                        continue
                    pending = list(self._jobs)
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    with self._cond:
                        kind, key = self._jobs.pop(fut)
                    try:
                        value = fut.result()
                    except Exception as e:  # noqa: BLE001  a run failed in its worker: raised again here with its name
                        self._raise(kind, key, e)
                    if kind == "run":
                        self._results[key] = value
                        remaining.discard(key)
                        if bar is not None:
                            bar.update(1)
        finally:
            if bar is not None:
                bar.close()
        self._pool.shutdown(wait=True)

    def _raise(self, kind: str, key, error: Exception, where: str = "in a worker process by"):
        """Raise ``error``, which stopped ``kind`` ("wm" or "run") ``key``, naming the run."""
        if isinstance(error, BrokenProcessPool):
            raise RuntimeError(
                f"a worker process died during {self._what(kind, key)}: out of memory, killed, "
                "or (in a script) the script's code is not under `if __name__ == \"__main__\":`, "
                f"which Python's process pools need. Run the sweep with workers=1 (or {WORKERS_ENV}=1) "
                "to run it in this process instead") from error
        error.add_note(f"(raised {where} {self._what(kind, key)})")
        raise error

    def cancel(self) -> None:
        """Stop the workers now; the runs they had not finished are lost."""
        if self._pool is not None:
            _stop(self._pool)
        self._done = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if not self._done:
            self.cancel()
        return False


def start_many(cfgs, cache_dir=None, model_cache=None, workers: int | None = None, desc: str = "runs") -> Sweep:
    """Start the runs of ``cfgs`` in worker processes and return at once (a :class:`Sweep`); its
    ``results()`` gives what :func:`run_many` gives. Between the two this process is free for work of
    its own, such as training a learner's own agent in the kernel (notebook 03) while the workers
    train the package's.

    The longest runs (:func:`expected_work`) start first, so that no long run is left to finish
    alone at the end. Smoke configs, runs whose trained agent is already in ``model_cache``, and
    every run where only one worker is available, run in this process, in ``results()``.
    """
    cfgs = list(cfgs)
    for c in cfgs:
        if not isinstance(c, Config):
            raise TypeError(f"run_many takes a list of pusht.config.Config, got a {type(c).__name__}")
        c.validate()
    workers = default_workers(cfgs) if workers is None and cfgs else workers
    if workers is not None and (not isinstance(workers, int) or isinstance(workers, bool) or workers < 1):
        raise ValueError(f"workers must be a whole number of processes, 1 or more; got {workers!r}")
    return Sweep(cfgs, cache_dir, model_cache, workers, desc)


def run_many(cfgs, cache_dir=None, model_cache=None, workers: int | None = None, progress=None,
             desc: str = "runs") -> list:
    """Run the pipeline once per config of ``cfgs``; the :class:`~pusht.dreamer.RunResult` of each,
    in the order given.

    ``cache_dir`` and ``model_cache`` are ``run``'s. ``workers``: how many runs at once (module
    doc; 1 runs them one after the other in this process). Smoke configs and runs whose trained
    agent is already in ``model_cache`` always run here, while the workers start: they take less
    time than a worker takes to start (about 2 s: it imports torch). ``progress``: a tqdm-like
    class (``tqdm.auto.tqdm``) for one bar over the pooled runs, or for each run's own bars when it
    runs here. A run that raises stops the sweep: its error is raised here, with the run named.
    """
    with start_many(cfgs, cache_dir, model_cache, workers, desc) as sweep:
        return sweep.results(progress)
