"""The worker process: one student's notebooks through nbgrader's autograde, in confined kernels.

    python -m autograde.worker ARGS_JSON

``task.grade_task`` starts it once per grading task. It runs in a private copy of the course, under
an address-space cap of its own (whatever a kernel prints lands in nbgrader's memory here), and
writes its answer (scores and timings, never a verdict) to a file no kernel can reach.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
from pathlib import Path

from pusht.reference import AUTOGRADE, GRADING_ENV

from . import sandbox
from .outputs import autograde_steps
from .course import ASSIGNMENT, COURSE_ID, _last_error


GRADER_BYTES = 3 << 30               # address space of the worker process (nbgrader's copy of the outputs)


ZYGOTE_ENV = "PUSHT_GRADING_ZYGOTE"   # "0": a new sandboxed kernel per notebook, no kernel factory


def worker(priv: Path, student: str, timeout: int, confine: bool, uid: int | None, limits: dict,
           shared: str | None = None, keep_workdir: bool = False) -> dict:
    """Run every notebook of one student in the private course ``priv`` through nbgrader's
    autograde, in confined kernels (runs in its own process, under a memory cap). Returns
    {notebook: {"ok", "error", "scores": {grade_id: auto score}, "verdicts": {}, "seconds"}}: the
    kernels decide no verdict (grade_task's probes do). ``shared``: a folder of stages computed
    once for the whole batch, which the kernels read. ``keep_workdir``: the kernels work in the
    notebooks' folder on the host, not a tmpfs (the instructor's own run, whose stages are kept)."""
    from .kernels import GradingKernelManager
    from traitlets.config import PyFileConfigLoader

    sandbox.die_with_parent()
    _cap_memory(limits)
    run = priv.parent / "run"
    sockets, runtime = run / "sockets", run / "runtime"
    for p in (sockets, runtime):
        p.mkdir(parents=True, exist_ok=True)
    os.environ["JUPYTER_RUNTIME_DIR"] = str(runtime)
    os.environ[GRADING_ENV] = AUTOGRADE
    os.environ["TQDM_DISABLE"] = "1"      # no progress bars (and no rates or times) in graded outputs
    # Grading runs one task per core, so a kernel's torch must not start a thread per core of its own:
    # two kernels doing so on two cores made notebooks several times slower (OpenMP threads waiting
    # on each other; benchmarks/grading_wallclock.txt). One thread is also the chapter's own setting
    # (Config.threads). An instructor's explicit setting is kept.
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    config = PyFileConfigLoader("nbgrader_config.py", path=str(priv)).load_config()
    config.CourseDirectory.root = str(priv)
    config.CourseDirectory.db_url = f"sqlite:///{priv / 'gradebook.db'}"
    config.Execute.timeout = timeout
    # Once the last cell has run (its results already on disk), the kernel is killed rather than asked
    # to shut down: a polite shutdown waits about 1.3 s per notebook for the kernel to exit
    # (benchmarks/grading_wallclock.txt), and a killed sandbox takes every process in it along.
    config.Execute.shutdown_kernel = "immediate"
    config.Execute.kernel_manager_class = GradingKernelManager    # notices the killed kernel within 10 ms
    config.KernelManager.transport = "ipc"
    # the graded copy's outputs cut to a size its feedback page can be made from, with a note where cut,
    # after SaveAutoGrades has scored them (outputs.py)
    config.Autograde.autograde_preprocessors = autograde_steps(config)
    config.KernelManager.ip = str(sockets / "k")
    zygote = None
    if confine:
        # the kernel makes its sockets in a folder it may write until the grader has connected to
        # them; from then on, before any of its cells runs, the folder is root's (sandbox.lock_sockets)
        config.Execute.on_notebook_start = lambda **_: sandbox.lock_sockets(sockets)
        settings = {"socket_dir": str(sockets), "uid": uid, "limits": limits, "shared_cache": shared,
                    "keep_workdir": keep_workdir}
        if os.environ.get(ZYGOTE_ENV, "1") != "0":
            # one kernel factory for all of this student's notebooks, in a sandbox around the folder
            # nbgrader runs them in (sandbox.Zygote): no kernel pays for Python, ipykernel and torch
            workdir = priv / "autograded" / student / ASSIGNMENT
            workdir.mkdir(parents=True, exist_ok=True)
            settings.update(zygote_state=str(run / "zygote.json"), connections_dir=str(run / "connections"))
            zygote = sandbox.Zygote(settings, workdir)
        sandbox.write_kernelspec(run / "jupyter", settings)
        os.environ["JUPYTER_PATH"] = str(run / "jupyter")
        config.Execute.kernel_name = sandbox.KERNEL_NAME
    elif shared:
        os.environ[sandbox.SHARED_CACHE_ENV] = shared
    try:
        if zygote is not None:
            zygote.start()    # its imports overlap nbgrader's (_grade_notebooks); the first notebook waits
        return _grade_notebooks(priv, student, config, zygote)
    finally:
        if zygote is not None:
            zygote.stop()


def _empty(folder: Path) -> None:
    """Remove everything in ``folder`` but the folder (a sandbox may have it bound)."""
    folder.mkdir(exist_ok=True)
    for p in folder.iterdir():
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)


def _cap_memory(limits: dict) -> None:
    """This process's address space capped at ``limits["grader_bytes"]``: whatever a kernel prints,
    nbgrader's copy of it in this process cannot take the host's memory (the worker fails, and the
    student's notebooks with it; nobody else's)."""
    import resource

    cap = int(limits.get("grader_bytes", GRADER_BYTES))
    try:      # the soft limit: the sandboxes it starts set their own (prlimit)
        resource.setrlimit(resource.RLIMIT_AS, (cap, resource.getrlimit(resource.RLIMIT_AS)[1]))
    except (ValueError, OSError):
        pass


def _grade_notebooks(priv: Path, student: str, config, zygote) -> dict:
    from nbgrader.api import Gradebook
    from nbgrader.apps import NbGraderAPI
    from nbgrader.coursedir import CourseDirectory

    out = {}
    for name in [p.name for p in sorted((priv / "submitted" / student / ASSIGNMENT).glob("*.ipynb"))]:
        nb_id = name[:-len(".ipynb")]
        if zygote is not None:
            zygote.ensure()
        coursedir = CourseDirectory(config=config)
        coursedir.notebook_id = nb_id
        api = NbGraderAPI(coursedir=coursedir, config=config)
        started = time.perf_counter()
        res = api.autograde(ASSIGNMENT, student, force=True, create=True)
        entry = {"ok": bool(res.get("success")), "error": "" if res.get("success") else
                 _last_error(res.get("error", "") or res.get("log", "")), "scores": {}, "verdicts": {},
                 "seconds": round(time.perf_counter() - started, 2)}   # nbgrader's autograde, kernel included
        if entry["ok"]:
            with Gradebook(config.CourseDirectory.db_url, course_id=COURSE_ID) as gb:
                sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                entry["scores"] = {g.name: g.auto_score for g in sub.grades}
        out[name] = entry
    return out


def main(argv=None) -> int:
    """``python -m autograde.worker ARGS_JSON``: run ``worker`` and write its answer where ARGS says."""
    a = json.loads((sys.argv[1:] if argv is None else argv)[0])
    out = worker(Path(a["priv"]), a["student"], a["timeout"], a["confine"], a["uid"], a["limits"], a.get("shared"),
                 a.get("keep_workdir", False))
    Path(a["answer"]).write_text(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
