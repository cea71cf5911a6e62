"""pusht.sweep.run_many: a sweep's runs on several cores give exactly the numbers of running them here.

The configs are tiny but not flagged smoke (run_many runs smoke configs in-process, since a worker
takes longer to start than they take to run), so the pool really starts: two spawned processes.
"""

import time

import numpy as np
import pytest
import torch

from pusht import sweep
from pusht.config import make_config
from pusht.dreamer import run
from pusht.sweep import default_workers, run_many, start_many


def tiny(**changes):
    """The smoke config's sizes as a learner's own small config (not flagged smoke)."""
    return make_config(smoke=True).replace(smoke=False, **changes)


def same_run(a, b) -> bool:
    if a.metrics != b.metrics or a.history.keys() != b.history.keys():
        return False
    if not all(np.array_equal(a.history[k], b.history[k]) for k in a.history):
        return False
    sa, sb = a.agent.state_dict(), b.agent.state_dict()
    return sa.keys() == sb.keys() and all(torch.equal(sa[k], sb[k]) for k in sa)


@pytest.mark.slow                  # trains in a pool of worker processes
def test_a_sweep_on_two_workers_gives_the_numbers_of_running_it_here(tmp_path):
    # Two world models (seeds 0 and 1) and, on seed 0's, two horizons: with an empty stage cache
    # seed 0's model is trained by one task that the two runs on it wait for.
    cfgs = [tiny(seed=0, imag_horizon=5), tiny(seed=1), tiny(seed=0, imag_horizon=8, actor_seed=1)]
    here = [run(c, cache_dir=tmp_path / "data", log=None) for c in cfgs]
    pooled = run_many(cfgs, cache_dir=tmp_path / "data", model_cache=tmp_path / "cache", workers=2)
    assert [r.cfg for r in pooled] == cfgs, "results come back in the order of the configs"
    for c, a, b in zip(cfgs, here, pooled):
        assert same_run(a, b), f"{sweep.describe(c)}: the pooled run differs from the same run in this process"
    assert len(list((tmp_path / "cache").glob("wm_*.pt"))) == 2
    assert len(list((tmp_path / "cache").glob("agent_*.pt"))) == 3
    assert not list((tmp_path / "cache").glob("*.tmp")), "a half-written cache file was left behind"
    # a second sweep finds every agent in the cache and so starts no pool, with the same numbers
    again = run_many(cfgs, cache_dir=tmp_path / "data", model_cache=tmp_path / "cache", workers=2)
    assert all(same_run(a, b) for a, b in zip(here, again))


@pytest.mark.slow                  # trains in a pool of worker processes
def test_the_longest_runs_start_first_and_this_process_is_free_meanwhile(tmp_path):
    # Notebook 05's sweep in small: the runs that dream longest start first, so that no long run is
    # left to finish alone at the end. Between start_many and results() this process trains a run of
    # its own, as notebook 03 trains the learner's agent in the kernel while the workers train the
    # package's; the world model the pooled runs wait for is trained by a worker meanwhile.
    cfgs = [tiny(imag_horizon=h, actor_seed=a) for h, a in ((3, 0), (12, 1), (6, 2))]
    with start_many(cfgs, cache_dir=tmp_path / "data", model_cache=tmp_path / "cache", workers=2) as pending:
        assert [cfgs[i].imag_horizon for i in pending.pooled] == [12, 6, 3]
        mine = run(tiny(seed=1), cache_dir=tmp_path / "data", log=None)
        pooled = pending.results()
    here = [run(c, cache_dir=tmp_path / "data", log=None) for c in cfgs]
    assert all(same_run(a, b) for a, b in zip(here, pooled)), "the order changes no number"
    assert same_run(mine, run(tiny(seed=1), cache_dir=tmp_path / "data", log=None))
    assert pending.results() is pooled, "results() can be asked for again"


def test_a_pool_that_breaks_as_a_world_model_is_done_is_reported_not_waited_for(monkeypatch, tmp_path):
    # The runs that wait for a world model are started from the pool's own thread. Should the pool
    # break just then (a worker killed between the two tasks), the sweep must say so, not wait forever.
    import threading
    from concurrent.futures.process import BrokenProcessPool

    def broken(self, i):
        raise BrokenProcessPool("a worker was killed")

    monkeypatch.setattr(sweep.Sweep, "_submit_run", broken)
    cfgs = [tiny(seed=0, imag_horizon=5), tiny(seed=0, imag_horizon=8)]     # both wait for seed 0's model
    outcome = []

    def sweep_it():
        try:
            run_many(cfgs, cache_dir=tmp_path / "data", model_cache=tmp_path / "cache", workers=2)
        except Exception as e:  # noqa: BLE001  handed to the test, which says what the thread raised
            outcome.append(e)

    t = threading.Thread(target=sweep_it, daemon=True)
    t.start()
    t.join(timeout=120)
    assert not t.is_alive(), "the sweep waited forever for runs that were never started"
    assert isinstance(outcome[0], RuntimeError) and "worker process died" in str(outcome[0])
    assert "imag_horizon=8" in str(outcome[0]), "the first run it could not start, the longest, is named"


def test_leaving_the_block_with_an_error_stops_the_workers(tmp_path):
    # (an interrupted kernel too: KeyboardInterrupt leaves the block the same way)
    cfgs = [tiny(seed=0), tiny(seed=1)]
    with pytest.raises(KeyError):
        with start_many(cfgs, cache_dir=tmp_path / "data", model_cache=tmp_path / "cache", workers=2) as pending:
            workers = list(pending._pool._processes.values())
            assert len(workers) == 2
            raise KeyError("the learner's own cell failed")
    deadline = time.monotonic() + 10
    for proc in workers:
        # exitcode, not is_alive(): the pool's own thread may reap the process first, and then
        # is_alive() can still say True for a moment
        while proc.exitcode is None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert proc.exitcode is not None, "a worker outlived the sweep it belonged to"
        assert proc.exitcode < 0, "the worker was ended by a signal, not left to finish its run"


class NoPool:
    def __init__(self, *args, **kwargs):
        raise AssertionError("run_many started a process pool")


def test_smoke_configs_and_a_single_run_start_no_pool(monkeypatch, tmp_path):
    monkeypatch.setattr(sweep, "ProcessPoolExecutor", NoPool)
    smoke = [make_config(smoke=True, seed=s) for s in (0, 1)]
    assert [r.cfg for r in run_many(smoke, cache_dir=tmp_path, workers=2)] == smoke
    assert len(run_many([tiny()], cache_dir=tmp_path, workers=4)) == 1
    assert run_many([], workers=2) == []


@pytest.mark.slow                  # trains in a pool of worker processes
def test_a_run_that_fails_in_a_worker_raises_its_own_error_naming_the_run(tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the stage cache should be\n")
    cfgs = [tiny(seed=0), tiny(seed=1)]
    with pytest.raises(OSError) as info:       # each worker fails to create the cache folder
        run_many(cfgs, cache_dir=tmp_path / "data", model_cache=blocker / "cache", workers=2)
    assert any("raised in a worker process by the world model of seed=" in n
               for n in getattr(info.value, "__notes__", [])), info.value


def test_how_many_workers(monkeypatch):
    cfgs = [make_config(seed=0)]
    monkeypatch.delenv("NBGRADER_EXECUTION", raising=False)
    monkeypatch.delenv(sweep.WORKERS_ENV, raising=False)
    assert default_workers(cfgs) == sweep.usable_cores()
    assert default_workers([make_config(seed=0, threads=2)]) == max(sweep.usable_cores() // 2, 1)
    assert default_workers([cfgs[0].replace(device="cuda")]) == 1
    monkeypatch.setenv(sweep.WORKERS_ENV, "3")
    assert default_workers(cfgs) == 3
    for bad in ("0", "two", "-1", "1.5"):
        monkeypatch.setenv(sweep.WORKERS_ENV, bad)
        with pytest.raises(ValueError, match=sweep.WORKERS_ENV):
            default_workers(cfgs)
    monkeypatch.delenv(sweep.WORKERS_ENV)
    monkeypatch.setenv("NBGRADER_EXECUTION", "autograde")   # the grader runs a kernel per core already
    assert default_workers(cfgs) == 1
    with pytest.raises(ValueError, match="workers"):
        run_many(cfgs, workers=0)
    with pytest.raises(TypeError, match="Config"):
        run_many([{"seed": 0}])



def fake_cgroup(monkeypatch, tmp_path, files: dict, meminfo_kb: int = 64 * 2**20):
    """A cgroup folder holding ``files`` (name -> content), as the only one that limits this process."""
    d = tmp_path / "cgroup"
    d.mkdir(parents=True)
    for name, text in files.items():
        (d / name).write_text(text + "\n")
    monkeypatch.setattr(sweep, "_cgroup_dirs", lambda controller: [d])
    real_read = sweep._read
    monkeypatch.setattr(sweep, "_read", lambda path: f"MemAvailable: {meminfo_kb} kB"
                        if str(path) == "/proc/meminfo" else real_read(path))


@pytest.mark.parametrize("files, cores", [({"cpu.max": "max 100000"}, None),          # cgroup v2, no quota
                                          ({"cpu.max": "150000 100000"}, 1),          # v2: 1.5 CPUs
                                          ({"cpu.cfs_quota_us": "-1", "cpu.cfs_period_us": "100000"}, None),
                                          ({"cpu.cfs_quota_us": "300000", "cpu.cfs_period_us": "100000"}, 3)])
def test_a_cgroup_cpu_quota_narrows_the_cores(monkeypatch, tmp_path, files, cores):
    monkeypatch.setattr(sweep.os, "sched_getaffinity", lambda pid: set(range(16)))   # a big Binder node
    fake_cgroup(monkeypatch, tmp_path, files)
    assert sweep.usable_cores() == (16 if cores is None else cores)


def test_a_memory_limit_caps_the_workers(monkeypatch, tmp_path):
    # Binder: a 2 GB limit, a kernel already using 1.5 GB of it: no room for a worker, so the sweep
    # runs in the kernel
    monkeypatch.delenv("NBGRADER_EXECUTION", raising=False)
    monkeypatch.delenv(sweep.WORKERS_ENV, raising=False)
    monkeypatch.setattr(sweep.os, "sched_getaffinity", lambda pid: set(range(16)))
    fake_cgroup(monkeypatch, tmp_path, {"memory.max": str(2 * 2**30), "memory.current": str(int(1.5 * 2**30))})
    assert sweep.available_memory() == 2**29
    assert default_workers([make_config()]) == 1
    (tmp_path / "cgroup" / "memory.max").write_text("max\n")     # no limit: only the cores count
    assert default_workers([make_config()]) == 16
    (tmp_path / "cgroup" / "memory.max").write_text(f"{int(1.5 * 2**30) + 3 * sweep.WORKER_BYTES}\n")
    assert default_workers([make_config()]) == 3
    # cgroup v1 names, and the machine's own MemAvailable when it is the tighter
    fake_cgroup(monkeypatch, tmp_path / "v1", {"memory.limit_in_bytes": str(2**62),
                                               "memory.usage_in_bytes": str(2**30)},
                meminfo_kb=2 * sweep.WORKER_BYTES // 1024)
    assert default_workers([make_config()]) == 2
