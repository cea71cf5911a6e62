"""One grading task: some notebooks of one student, start to end, in a temporary private course.

The worker process runs the notebooks in the student's kernels (for the feedback page and the
receipts); meanwhile this process has each hidden test probed in a probe server of the task's own
(``probe``) and judges the numbers (``checks``). What comes back from the worker is read with caps.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import zipfile
from functools import lru_cache
from pathlib import Path

import nbformat
from pusht.stage_cache import FILE_PATTERN as CACHE_FILE   # pusht's stage cache files

from . import checks, outputs, probe, sandbox, tripwire
from .course import ASSIGNMENT, _last_error, private_course, tool_env




_JUDGING = threading.Lock()


def probe_verdicts(notebooks: dict, warm: list[str], uid: int | None, confine: bool, limits: dict,
                   timeout: int = probe.PROBE_SECONDS, ours: dict | None = None) -> dict:
    """{notebook: {test id: verdict}} for the hidden tests of ``notebooks`` ({file name: JSON text}):
    each graded function defined from the hand-in's own cells and probed in a probe server of
    this task's own (``probe.py``), then judged here against the real implementations
    (``judge_locked``). ``timeout``: seconds for each test's probes (the cell timeout: what the
    test cell had in the kernel). ``ours``: {file name: the release's own statements}
    (``recreate.release_statements``), which are kept only where the function needs them."""
    out = {}
    todo = []
    for name, text in notebooks.items():
        tests = [t for t in checks.TESTS.values() if name.startswith(t.notebook)]
        if not tests:
            continue
        try:
            cells = nbformat.reads(text, as_version=4).cells
        except Exception:         # noqa: BLE001  repaired by prepare_student: cannot happen, costs nothing
            cells = []
        own = (ours or {}).get(name, frozenset())
        todo += [(name, t, probe.program(cells, t.test_id, t.function, own)) for t in tests]
    if not todo:
        return out
    with probe.ProbeServer(uid, limits, warm, confine=confine, seconds=timeout) as server:
        for name, test, statements in todo:
            out.setdefault(name, {})[test.test_id] = judge_locked(test, server.run(test, statements))
    return out


def judge_locked(test, raw: dict | None) -> dict:
    """``checks.judge`` of one test's probe results, as a dict; one judgement at a time in a process.

    Several tasks judge in threads of the same process, and the reference probes seed torch's
    global random generator to build their models (two at once drew each other's numbers, and a
    correct student lost the points). The caller's own random state is put back afterwards."""
    import torch

    with _JUDGING, torch.random.fork_rng(devices=[]):
        return vars(checks.judge(test, raw))


def grade_task(bundle: bytes, student: str, notebooks: dict, timeout: int, confine: bool, limits: dict,
               shared=None, keep_stages: bool = False) -> dict:
    """Grade some notebooks of one student, start to end, in a temporary private course.

    Self-contained, so that it runs the same in a thread here or on a Dask worker on another
    machine: everything comes in as arguments (``bundle`` from ``course_bundle``; ``notebooks``
    {file name: notebook JSON text}; ``shared`` a folder, or {file name: bytes}, of shared stages)
    and everything goes out in the return value: {"results": {notebook: entry}, "autograded":
    {notebook: JSON text}, "stages": {file name: bytes} (only with ``keep_stages``, the
    instructor's own run)}. Nothing is left behind.

    Two things run side by side: the worker process runs the notebooks through nbgrader in the
    student's kernels (their outputs, for the feedback page and the receipts), and this thread has
    the hidden tests probed in a probe server of its own (``probe_verdicts``): no verdict depends
    on anything a kernel did. What comes back from the worker is read with caps: its answer file,
    the autograded notebooks nbgrader wrote (``MAX_NOTEBOOK_BYTES``; their outputs are cut to fit
    by ``outputs.CapOutput``; where a copy is over it, or none was made, ``outputs.stand_in`` stands
    in for it, so every notebook graded has a feedback page), the last
    ``STDERR_TAIL`` bytes of what it and its kernels wrote to stderr.

    The student's uid (confined, as root) is leased for this task alone on this host
    (``sandbox.allocate_uid``), so other grading runs and Dask workers on the same host never share
    it. It is released when the task ends, whatever still ran as it
    killed first (``UidLease.sweep``: normally nothing, every sandbox dies with its namespace)."""
    lease = sandbox.allocate_uid() if confine else sandbox.UidLease()
    work = Path(tempfile.mkdtemp(prefix="pusht-grade-"))
    os.chmod(work, 0o755)
    try:
        priv = private_course(bundle, student, notebooks, work)
        if isinstance(shared, dict):
            folder = work / "shared"
            folder.mkdir()
            for name, data in shared.items():
                if CACHE_FILE.match(name):
                    (folder / name).write_bytes(data)
            shared = str(folder)
        args = {"priv": str(priv), "student": student, "timeout": timeout, "confine": confine,
                "uid": lease.uid, "limits": limits, "keep_workdir": keep_stages,
                "shared": str(shared) if shared else None, "answer": str(work / "answer.json")}
        proc = subprocess.Popen([sys.executable, "-m", "autograde.worker", json.dumps(args)],
                                cwd=priv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, env=tool_env(), start_new_session=True)
        tail = _Tail(proc.stderr)
        try:
            verdicts = probe_verdicts(notebooks, _warm_statements(bundle), lease.uid, confine, limits, timeout,
                                      _release_statements(bundle))
        finally:
            budget = limits["wall_seconds"] * max(1, len(notebooks)) + 120
            try:
                proc.wait(timeout=budget)
                stderr = tail.text()
            except subprocess.TimeoutExpired:
                stderr = "the grading of this student ran out of time"
            finally:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)   # nothing this student started outlives grading
                except ProcessLookupError:
                    pass
                proc.wait()
        # the worker's answer comes in a file no sandbox can reach: a kernel shares the worker's
        # stderr and could print something that looks like one
        data = _read_capped(work / "answer.json", MAX_ANSWER_BYTES) if proc.returncode == 0 else None
        try:
            result = json.loads(data) if data else {}
        except ValueError:
            result = {}
        if not result:
            result = {name: {"ok": False, "error": _last_error(stderr), "scores": {}, "verdicts": {}}
                      for name in notebooks}
        for name, found in verdicts.items():
            result.setdefault(name, {"ok": False, "error": "not run", "scores": {}})["verdicts"] = found
        src = priv / "autograded" / student / ASSIGNMENT
        out = {"results": result, "autograded": {}}
        for n in notebooks:
            data = _read_capped(src / n, MAX_NOTEBOOK_BYTES)
            graded = data.decode("utf-8", errors="replace") if data is not None else None
            if graded is not None:
                out["autograded"][n] = graded
            elif n in result:      # no graded copy to read (too large, or none made): a page all the same
                try:
                    st = os.lstat(src / n)
                    size = st.st_size if stat.S_ISREG(st.st_mode) else None
                except OSError:
                    size = None
                out["autograded"][n] = outputs.stand_in(notebooks[n], size)
                result[n]["note"] = ("its feedback page shows the notebook as handed in, without outputs: "
                                     + (f"its graded copy is {size / 1e6:.1f} MB, over the {MAX_NOTEBOOK_BYTES >> 20} MB "
                                        f"read back" if size is not None else "nbgrader made no graded copy of it"))
            if n in verdicts:          # a function the kernel ran and the probe could not: a human looks
                tripwire.mark(verdicts[n], graded)
        if keep_stages:
            out["stages"] = {}
            for p in sorted(src.rglob("*")):
                if CACHE_FILE.match(p.name):
                    data = _read_capped(p, MAX_STAGE_BYTES)
                    if data is not None:
                        out["stages"][p.name] = data
        return out
    finally:
        lease.sweep()          # the worker is gone: only a sandbox that escaped its namespace's end is left
        lease.close()
        shutil.rmtree(work, ignore_errors=True)


MAX_ANSWER_BYTES = 16 << 20          # the worker's answer: scores and timings, a few KB


MAX_NOTEBOOK_BYTES = 32 << 20        # an autograded notebook (a chapter notebook is under 2 MB)


MAX_STAGE_BYTES = 256 << 20          # one shared stage file of the instructor's run


STDERR_TAIL = 64 << 10               # what is kept of the worker's stderr: its last error


def _read_capped(path: Path, cap: int) -> bytes | None:
    """A file's bytes, read without following a link and only if it is a plain file of at most
    ``cap`` bytes; None otherwise (missing, a link, a fifo, too large)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode) or st.st_size > cap:
            return None
        data = f.read(cap + 1)
    return data if len(data) <= cap else None


class _Tail:
    """The last ``STDERR_TAIL`` bytes of a stream, read in a thread (nothing more is kept)."""

    def __init__(self, stream):
        self.buf, self.stream = bytearray(), stream
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            while chunk := self.stream.read1(1 << 16):
                self.buf += chunk
                del self.buf[:-STDERR_TAIL]
        except (OSError, ValueError):
            pass

    def text(self) -> str:
        self.thread.join(timeout=5)
        return bytes(self.buf).decode("utf-8", errors="replace")


@lru_cache(maxsize=4)
def _release(bundle: bytes) -> dict:
    """{file name: notebook} of the student release in a course bundle."""
    release = {}
    with zipfile.ZipFile(io.BytesIO(bundle)) as zf:
        for name in zf.namelist():
            if name.startswith(f"release/{ASSIGNMENT}/") and name.endswith(".ipynb"):
                release[name.rsplit("/", 1)[1]] = nbformat.reads(zf.read(name).decode("utf-8"), as_version=4)
    return release


@lru_cache(maxsize=4)
def _warm_statements(bundle: bytes) -> list[str]:
    """The release's imports (``probe.warm_statements``), read from a course bundle."""
    return probe.warm_statements(_release(bundle))


@lru_cache(maxsize=4)
def _release_statements(bundle: bytes) -> dict:
    """{file name: the release's own statements} (``recreate.release_statements``)."""
    return {name: probe.release_statements(nb) for name, nb in _release(bundle).items()}
