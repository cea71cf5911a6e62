"""Grade a whole class in one command: LMS download -> scores, feedback HTML and a grades CSV.

    python autograde/grade.py SUBMISSIONS [--course autograde] [--timeout 120] [--jobs N]

SUBMISSIONS is a .zip as the LMS hands it over, or a folder: each student's downloaded notebooks
(Jupyter or Colab), named ``<student_id>_<notebook>.ipynb`` or placed in ``<student_id>/``
folders (``intake.py`` says exactly what is accepted and what is refused).

Student code is untrusted. What happens, per student:

1. ``intake.collect`` reads the download in memory (hostile names refused, nothing written
   outside the course), normalises LMS ids and picks the newest of several uploads;
2. ``repair``: each notebook is decoded (any common encoding), cleaned of Colab metadata, its
   graded cells matched back to the instructor's (by id or content) and deleted test cells put
   back; the prediction receipts are checked (``receipts``); each graded function is followed
   through the notebook to see whether it reaches the package's implementation of what it was
   asked to write (``delegation``);
3. the student is graded in a private copy of the course (in a temporary folder), by nbgrader,
   in kernels confined by ``sandbox.py`` (bubblewrap: the student's own working folder and
   nothing else of the course, no network, resource and wall-clock limits, a throw-away uid,
   every process killed when the notebook is done). ``--jobs`` tasks run at once (default: one
   per core); with fewer students than jobs, each student's notebooks are split over several
   tasks, so even one student keeps every core busy. A failure in one notebook costs only that
   notebook;
4. the test cells' verdicts are made outside the kernel, by the grading task's own process, from
   the raw numbers the kernel recorded (``checks.judge``), so nothing the student's code does in
   the kernel can forge them;
5. only this process writes the course's gradebook: every student's scores, completion points
   and manual grades (``manual_grades.csv``); then the feedback pages (hidden tests removed,
   outputs capped; ``--jobs`` processes at once, each only reading the gradebook), ``grades.csv``
   (nbgrader's export of that gradebook) and ``report.csv``.

Grading again gives the same grades: manual grades live in ``manual_grades.csv`` and are
re-applied after every run.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
import warnings
import zipfile
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from pathlib import Path

import nbformat
import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

import answer_key  # noqa: E402
import cellcode  # noqa: E402
import checks  # noqa: E402
import delegation  # noqa: E402
import intake  # noqa: E402
import probe  # noqa: E402
import receipts  # noqa: E402
import repair  # noqa: E402
import sandbox  # noqa: E402

COURSE = yaml.safe_load((ROOT / "course.yaml").read_text())
ASSIGNMENT = COURSE["assignment"]
COURSE_ID = "zero2robot-ch3.2"      # the same as in nbgrader_config.py
NOTEBOOKS = sorted(p.name for p in (ROOT / "solutions").glob("*.ipynb"))
# The completion task cell of each predict-then-run exercise: "<ex>_order".
EXERCISES = {"ex1": "04_imagination_gap", "ex2": "05_horizon", "ex3": "06_closing_the_gap"}
FEEDBACK_OUTPUT_CHARS = 20_000      # per output in a feedback page; the rest is cut with a note
FEEDBACK_NOTEBOOK_CHARS = 2_000_000  # all outputs of one notebook together; all its cells' text too
FEEDBACK_SOURCE_CHARS = 20_000      # per cell's text (markdown or code) in a feedback page
FEEDBACK_TIMEOUT = 120              # seconds one student's feedback pages may take before they are skipped
WIDGET = "application/vnd.jupyter.widget-view+json"
ZYGOTE_ENV = "PUSHT_GRADING_ZYGOTE"   # "0": a new sandboxed kernel per notebook, no kernel factory
HIDDEN_NOTE = "# (hidden tests: run by the grader; their verdict is printed below)\n"
GRADER_BYTES = 3 << 30               # address space of the worker process (nbgrader's copy of the outputs)


def tool_env() -> dict:
    """nbgrader shells out to `alembic`: make this interpreter's scripts folder visible."""
    here, path = str(Path(sys.executable).parent), os.environ.get("PATH", "")
    return {**os.environ, "PATH": path if here in path.split(os.pathsep) else f"{here}{os.pathsep}{path}"}


def nbgrader(course: Path, *args: str, timeout: int | None = None) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "nbgrader", *args, f"--CourseDirectory.root={course}",
           f"--CourseDirectory.db_url=sqlite:///{course / 'gradebook.db'}"]
    if timeout:
        cmd.append(f"--Execute.timeout={timeout}")
    return subprocess.run(cmd, cwd=course, capture_output=True, text=True, env=tool_env())


def prepare_course(course: Path) -> None:
    """Copy solutions/ into the course's source folder and (re)generate the assignment."""
    src = course / "source" / ASSIGNMENT
    src.mkdir(parents=True, exist_ok=True)
    for path in (ROOT / "solutions").glob("*.ipynb"):
        shutil.copy(path, src / path.name)
    if course.resolve() != HERE:
        shutil.copy(HERE / "nbgrader_config.py", course / "nbgrader_config.py")
    res = nbgrader_api(course).generate_assignment(ASSIGNMENT, force=True)
    if not res.get("success"):
        sys.exit(f"nbgrader generate_assignment failed:\n{(res.get('error') or res.get('log') or '')[-3000:]}")


def nbgrader_api(course: Path):
    """nbgrader's own Python API (``NbGraderAPI``) on ``course``, in this process.

    The same steps as the ``nbgrader`` command, without a new interpreter each: one import of
    nbgrader serves the whole batch (an import cost 2.5 s on the recording host; see
    benchmarks/grading_wallclock.txt).
    """
    from feedback_html import FeedbackHTMLExporter
    from nbgrader.apps import NbGraderAPI
    from nbgrader.coursedir import CourseDirectory
    from traitlets.config import PyFileConfigLoader

    os.environ["PATH"] = tool_env()["PATH"]     # a new gradebook runs the venv's `alembic`
    config = PyFileConfigLoader("nbgrader_config.py", path=str(course)).load_config()
    config.CourseDirectory.root = str(course)
    config.CourseDirectory.db_url = f"sqlite:///{course / 'gradebook.db'}"
    # nbconvert's HTMLExporter, less the BeautifulSoup round trip that was half of each student's
    # feedback time, and made safe: no script survives, a Content-Security-Policy forbids any
    # (feedback_html.py); otherwise the pages are nbconvert's documents
    config.GenerateFeedback.exporter_class = FeedbackHTMLExporter
    return NbGraderAPI(coursedir=CourseDirectory(config=config), config=config)


def export_csv(course: Path, filename: Path) -> None:
    """``nbgrader export`` (its CSV plugin) of the course gradebook into ``filename``, in this process."""
    from nbgrader.api import Gradebook
    from nbgrader.plugins import CsvExportPlugin
    from traitlets.config import Config

    config = Config()
    config.CsvExportPlugin.to = str(filename)      # the plugin's destination trait is `to`
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        CsvExportPlugin(config=config).export(gb)


# --- per student: repair, then grade in a private course ----------------------------------------
def prepare_student(uploads: dict, release: dict) -> tuple[dict, list[str], dict, dict]:
    """(repaired notebooks by file name, notes, completion verdicts, delegations by test id)."""
    notebooks, notes, completion, delegated = {}, [], {}, {}
    for name, up in sorted(uploads.items()):
        try:
            nb = intake.decode_notebook(up.data)
        except ValueError as e:
            notes.append(f"{name}: {e}; it scores 0")
            continue
        try:
            notes += _prepare_notebook(name, nb, release[name], completion, delegated)
        except Exception as e:       # noqa: BLE001  one odd hand-in never stops the class
            notes.append(f"{name}: could not be read for grading ({type(e).__name__}: {str(e)[:200]}); it "
                         f"scores 0. {intake.REDOWNLOAD}")
            continue
        notebooks[name] = nb
    return notebooks, notes, completion, delegated


def _prepare_notebook(name: str, nb, release, completion: dict, delegated: dict) -> list[str]:
    """Repair one notebook in place, read its receipts and follow its graded functions; returns
    its notes (``completion`` and ``delegated`` are filled in)."""
    notes = []
    if repair.clean_colab(nb):
        notes.append(f"{name}: saved by Colab; its extra metadata was removed")
    notes += [f"{name}: {n}" for n in repair.match_cells(nb, release)]
    for g in repair.restore_locked_cells(nb, release):
        notes.append(f"{name}: the locked test cell '{g}' was missing and was put back; never delete test cells")
    for ex, stem in EXERCISES.items():
        if name.startswith(stem):
            completion[ex] = receipts.receipt_verdict(nb, ex, release)
    for test in checks.TESTS.values():
        if name.startswith(test.notebook):
            copy = answer_key.copies(nb.cells, test)
            if copy:
                notes.append(f"{name}: answer key, for the instructor: {copy}")
            found = delegation.delegations(test, nb.cells, release)
            if found.definite:
                delegated[test.test_id] = found.definite
            elif found.ambiguous:
                notes.append(f"{name}: for the instructor: the grader cannot tell whether `{test.function}` "
                             f"reaches the package's own `{test.function}` ({'; '.join(found.ambiguous[:3])}); "
                             f"its score stands. Read that code; the student need do nothing unless you ask")
    return notes


def course_bundle(course: Path) -> bytes:
    """What a grading task needs of the course, as one zip: nbgrader's config, the assignment's
    source and release versions and an empty gradebook (no other student, no manual grades). It
    is built once per batch; a Dask worker on another machine receives it once."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.write(course / "nbgrader_config.py", "nbgrader_config.py")
        for sub in ("source", "release"):
            for p in sorted((course / sub).rglob("*")):
                if p.is_file():
                    zf.write(p, p.relative_to(course).as_posix())
        zf.write(course / "gradebook.template.db", "gradebook.db")
    return buf.getvalue()


def private_course(bundle: bytes, student: str, notebooks: dict, work: Path) -> Path:
    """A copy of the course with only this student in it; the kernel sees none of it but its folder."""
    priv = work / "course"
    priv.mkdir(parents=True)
    with zipfile.ZipFile(io.BytesIO(bundle)) as zf:
        zf.extractall(priv)           # our own zip: names were written by course_bundle above
    dest = priv / "submitted" / student / ASSIGNMENT
    dest.mkdir(parents=True)
    for name, nb in notebooks.items():
        (dest / name).write_text(nb, encoding="utf-8")          # notebook JSON text
    (dest / "timestamp.txt").write_text("2026-01-01 00:00:00.000000 UTC")   # fixed: regrades match
    return priv


def worker(priv: Path, student: str, timeout: int, confine: bool, uid: int | None, limits: dict,
           shared: str | None = None, keep_workdir: bool = False) -> dict:
    """Run every notebook of one student in the private course ``priv`` through nbgrader's
    autograde, in confined kernels (runs in its own process, under a memory cap). Returns
    {notebook: {"ok", "error", "scores": {grade_id: auto score}, "verdicts": {}, "seconds"}}: the
    kernels decide no verdict (grade_task's probes do). ``shared``: a folder of stages computed
    once for the whole batch, which the kernels read. ``keep_workdir``: the kernels work in the
    notebooks' folder on the host, not a tmpfs (the instructor's own run, whose stages are kept)."""
    from kernels import GradingKernelManager
    from traitlets.config import PyFileConfigLoader

    sandbox.die_with_parent()
    _cap_memory(limits)
    run = priv.parent / "run"
    sockets, runtime = run / "sockets", run / "runtime"
    for p in (sockets, runtime):
        p.mkdir(parents=True, exist_ok=True)
    os.environ["JUPYTER_RUNTIME_DIR"] = str(runtime)
    os.environ["NBGRADER_EXECUTION"] = "autograde"
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


_JUDGING = threading.Lock()


def probe_verdicts(notebooks: dict, warm: list[str], uid: int | None, confine: bool, limits: dict,
                   timeout: int = probe.PROBE_SECONDS) -> dict:
    """{notebook: {test id: verdict}} for the hidden tests of ``notebooks`` ({file name: JSON text}):
    each graded function defined from the hand-in's own cells and probed in a probe server of
    this task's own (``probe.py``), then judged here against the real implementations
    (``judge_locked``). ``timeout``: seconds for each test's probes (the cell timeout: what the
    test cell had in the kernel)."""
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
        todo += [(name, t, probe.program(cells, t.test_id, t.function)) for t in tests]
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


def _last_error(text: str) -> str:
    lines = [l for l in text.strip().splitlines() if l.strip() and "NbGraderException" not in l]
    for l in reversed(lines):
        if "Error" in l or "error" in l:
            return l.strip()[:300]
    return (lines[-1] if lines else "nbgrader failed")[:300]


CACHE_FILE = re.compile(r"^(expert_.*\.npz|(wm|agent|loop)_[0-9a-f]{16}\.pt)$")   # pusht's stage cache files


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
    the autograded notebooks nbgrader wrote (``MAX_NOTEBOOK_BYTES``), the last
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
        proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker", json.dumps(args)],
                                cwd=priv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, env=tool_env(), start_new_session=True)
        tail = _Tail(proc.stderr)
        try:
            verdicts = probe_verdicts(notebooks, _warm_statements(bundle), lease.uid, confine, limits, timeout)
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
            if data is not None:
                out["autograded"][n] = data.decode("utf-8", errors="replace")
            elif (src / n).exists() and n in result:
                result[n]["note"] = (f"its graded copy is larger than {MAX_NOTEBOOK_BYTES >> 20} MB (its outputs): "
                                     f"no feedback page is made for it")
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
def _warm_statements(bundle: bytes) -> list[str]:
    """The release's imports (``probe.warm_statements``), read from a course bundle."""
    release = {}
    with zipfile.ZipFile(io.BytesIO(bundle)) as zf:
        for name in zf.namelist():
            if name.startswith(f"release/{ASSIGNMENT}/") and name.endswith(".ipynb"):
                release[name] = nbformat.reads(zf.read(name).decode("utf-8"), as_version=4)
    return probe.warm_statements(release)


# --- the whole batch ---------------------------------------------------------------------------
REFERENCE = "reference-solution"     # the instructor's solutions, graded first when stages are shared
STATE_FILE = "graded.json"           # per student: what was graded (fingerprint) and its results
SHARE_FROM = 4                       # share stages from this many students to grade (see grade_class)


SHARED_DIR = "shared_stages"         # in the course: a copy of the stages the reference run left


def shared_stages(bundle: bytes, course: Path, jobs: int, scheduler, timeout: int, confine: bool,
                  limits: dict, log=print) -> dict:
    """The stages no student's code can change, computed once: grade the instructor's solutions as
    one more (confined) submission and keep the stage files its kernels wrote. Returns them as
    {file name: bytes} (each task writes them into its own temporary folder, so no path of the
    course is ever visible in a sandbox) and leaves a copy in ``course/shared_stages`` to look at.

    Which stages qualify is decided by how pusht caches them: a stage is written to the cache only
    when everything it was computed from is named in its file name (the config fields and the
    source of the package modules it runs, hashed); a stage given a learner's function (an actor
    trained with the learner's own lambda-return, say) is never cached, so it is never shared and
    every student's kernel computes it with their own code. A file a student's kernel looks up
    under the same name is therefore the same stage, computed from the same inputs. The shared
    folder is read-only inside every student's sandbox, and nothing a student writes reaches it.
    """
    notebooks = {p.name: p.read_text(encoding="utf-8") for p in sorted((ROOT / "solutions").glob("*.ipynb"))}
    stages, failed = {}, []

    def on_done(task, out):
        stages.update(out.get("stages", {}))
        for name, entry in out["results"].items():
            if not entry["ok"]:
                failed.append(f"{name} ({entry['error']})")
            failed.extend(f"{name}: {t}" for t, v in entry["verdicts"].items() if not v["passed"])

    def submit_args(task):
        return (bundle, REFERENCE, {n: notebooks[n] for n in task[1]}, timeout, confine, limits, None, True)

    t = time.perf_counter()
    tasks = _split([REFERENCE], {REFERENCE: notebooks}, jobs if scheduler is None else 2)
    run_tasks(tasks, jobs, scheduler, submit_args, on_done, log)
    folder = course / SHARED_DIR
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    for name, data in stages.items():
        (folder / name).write_bytes(data)
    log(f"shared stages: {len(stages)} files ({sum(map(len, stages.values())) / 1e6:.1f} MB) from grading the "
        f"solutions in {time.perf_counter() - t:.0f} s; every student's kernel reads them")
    if failed:
        log("WARNING: the instructor's solutions fail some of their own tests: " + "; ".join(failed)[:2000])
    return stages


def grader_fingerprint(timeout: int, confine: bool, limits: dict) -> str:
    """Everything besides the submission that decides a student's results: the solutions, the
    grader's code and tests, the package, the settings. A change to any of it regrades everyone."""
    h = hashlib.sha256(json.dumps([timeout, confine, sorted(limits.items())]).encode())
    files = sorted((ROOT / "solutions").glob("*.ipynb")) + sorted(HERE.glob("*.py")) + \
        sorted((ROOT / "pusht").rglob("*.py"))
    for p in files:
        h.update(p.relative_to(ROOT).as_posix().encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def submission_fingerprint(notebooks: dict, grader: str) -> str:
    h = hashlib.sha256(grader.encode())
    for name in sorted(notebooks):
        h.update(name.encode() + b"\0" + nbformat.writes(notebooks[name]).encode() + b"\0")
    return h.hexdigest()


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
                               "`--preload autograde/dask_preload.py` (README, 'Grading a large class').")
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

    for mod in ("grade", "pusht", "nbgrader"):
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


COURSE_LOCK = ".grading.lock"        # in the course folder while a grading run holds it


def _lock_holder(fd: int) -> str:
    """What the holder of a course lock wrote of itself (it writes just after it locks)."""
    for _ in range(20):
        text = os.pread(fd, 200, 0).decode(errors="replace").strip()
        if text:
            return text
        time.sleep(0.05)
    return "a process that has not said its pid yet"


class course_lock:
    """Hold the course folder ``course`` for one grading run: ``with course_lock(course, log): ...``

    Everything a run writes lives there (gradebook.db, graded.json, feedback/, shared_stages/), so
    two runs on one folder at once (a regrade started while a batch runs) would corrupt each other.
    The lock is an ``flock`` on ``course/.grading.lock``, which says who holds it (pid, host, since
    when); a second run logs that and waits. The kernel drops the lock of a holder that dies; the
    holder removes the file when it is done, still holding it (a waiter that then gets a removed
    file sees so and locks the new one)."""

    def __init__(self, course: Path, log=print):
        self.path, self.log, self.fd = Path(course) / COURSE_LOCK, log, None

    def __enter__(self) -> Path:
        import fcntl
        import socket

        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    self.log(f"waiting for another grading run of this course to finish: {_lock_holder(fd)} "
                             f"holds {self.path}")
                    fcntl.flock(fd, fcntl.LOCK_EX)
                try:
                    current = os.stat(self.path, follow_symlinks=False)
                except FileNotFoundError:
                    current = None
                mine = os.fstat(fd)
                if current is not None and (current.st_dev, current.st_ino) == (mine.st_dev, mine.st_ino):
                    break
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)             # the run before removed this file on its way out: lock the new one
        self.fd = fd
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}, grading since "
                      f"{time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode(), 0)
        return self.path

    def __exit__(self, *exc) -> None:
        self.path.unlink(missing_ok=True)      # before the lock goes: see the class's doc
        os.close(self.fd)
        self.fd = None


def _one_run_per_course(fn):
    """``fn`` (grade_class) runs holding its ``course`` argument's folder (``course_lock``)."""
    import functools
    import inspect

    signature = inspect.signature(fn)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        with course_lock(Path(bound.arguments["course"]).resolve(), bound.arguments["log"]):
            return fn(*args, **kwargs)
    return run


@_one_run_per_course
def grade_class(submissions: Path, course: Path = HERE, timeout: int = 120, jobs: int | None = None,
                log=print, confine: bool | None = None, limits: dict | None = None,
                progress: bool = True, scheduler=None, share: bool | None = None,
                regrade: bool = False) -> dict:
    """Grade every submission in ``submissions``; returns the per-student report.

    ``scheduler``: a Dask scheduler address (or ``distributed.Client``) to grade on its workers;
    None grades here, ``jobs`` tasks at once (default: one per core). ``share``: compute the
    stages that depend on no student (expert data, the world models and actors the notebooks
    train from the package's own code at the grading config) once, by grading the instructor's
    solutions first, and let every student's kernel read them (None: when there are at least
    SHARE_FROM students to grade). ``regrade``: grade again students whose submission, and
    everything else that decides their results, did not change since the last run in ``course``
    (by default their recorded results are reused).

    The whole run holds the course folder (``course_lock``): a second run on the same folder
    waits for this one, and says whose run it waits for.
    """
    from nbgrader.api import Gradebook
    from tqdm.auto import tqdm

    course = course.resolve()
    limits = {**sandbox.DEFAULT_LIMITS, **(limits or {})}
    ok, why = sandbox.available()
    if confine is None:
        confine = ok
    if confine and not ok:
        raise RuntimeError(f"confined grading was asked for, but {why}")
    if not confine:
        msg = (f"WARNING: submissions are NOT confined ({why or 'confinement switched off'}): "
               f"student code runs as you, with your files in reach. Install bubblewrap to confine it.")
        log(msg)
        warnings.warn(msg)
    prepare_course(course)
    shutil.copy(course / "gradebook.db", course / "gradebook.template.db")
    got = intake.collect(submissions, NOTEBOOKS)
    for line in got.rejected:
        log(f"skipped {line}")
    for line in got.warnings:            # e.g. look-alike ids not checked: PyICU is missing
        log(f"WARNING: {line}")
        warnings.warn(line)
    release = {name: nbformat.read(course / "release" / ASSIGNMENT / name, as_version=4) for name in NOTEBOOKS}
    report = {s: {"notes": list(got.notes.get(s, [])), "completion": {}, "verdicts": {}, "failed": {}}
              for s in got.students}
    prepared = {}
    for s, uploads in got.students.items():
        nbs, notes, completion, delegated = prepare_student(uploads, release)
        report[s]["notes"] += notes
        report[s]["completion"] = completion
        report[s]["delegated"] = delegated
        prepared[s] = nbs
    jobs = jobs or default_jobs()
    students = sorted(s for s in prepared if prepared[s])

    # Unchanged since the last run (same notebooks, same grader): reuse the recorded results.
    grader = grader_fingerprint(timeout, confine, limits)
    state_path = course / STATE_FILE
    state = json.loads(state_path.read_text()) if state_path.exists() else {}
    prints = {s: submission_fingerprint(prepared[s], grader) for s in students}
    results = {}
    for s in students:
        old = state.get(s, {})
        folder = course / "autograded" / s / ASSIGNMENT
        if not regrade and old.get("fingerprint") == prints[s] and \
                all((folder / n).is_file() for n in old.get("results", {})):
            results[s] = old["results"]
    if results:
        log(f"{len(results)} of {len(students)} students unchanged since the last grading: their results "
            f"are reused (regrade to grade them again)")
    todo = [s for s in students if s not in results]
    for s in todo:
        shutil.rmtree(course / "autograded" / s / ASSIGNMENT, ignore_errors=True)

    bundle = course_bundle(course)
    settings = dict(timeout=timeout, confine=confine, limits=limits)
    shared = None
    if share is None:
        share = len(todo) >= SHARE_FROM
    if share and todo:
        shared = shared_stages(bundle, course, jobs, scheduler, log=log, **settings)

    def submit_args(task):
        s, names = task
        return (bundle, s, {n: nbformat.writes(prepared[s][n]) for n in names}, timeout, confine, limits, shared)

    left = {}
    tasks = _split(todo, prepared, jobs if scheduler is None else 1)
    for s, _ in tasks:
        left[s] = left.get(s, 0) + 1
    where = f"on Dask at {getattr(scheduler, 'scheduler', None) and scheduler.scheduler.address or scheduler}" \
        if scheduler is not None else f"{jobs} at a time"
    with tqdm(total=len(todo), desc=f"grading ({where})", unit="student", disable=not progress) as bar:
        def on_done(task, out):
            s, _ = task
            results.setdefault(s, {}).update(out["results"])
            dest = course / "autograded" / s / ASSIGNMENT
            dest.mkdir(parents=True, exist_ok=True)
            for name, text in out["autograded"].items():
                (dest / name).write_text(text, encoding="utf-8")
            left[s] -= 1
            if not left[s]:                  # the bar counts students: all their tasks done
                bar.set_postfix_str(s[:20])
                bar.update()
        run_tasks(tasks, jobs, scheduler, submit_args, on_done, log)
    state = {s: {"fingerprint": prints[s], "results": results[s]} for s in students if s in results}
    state_path.write_text(json.dumps(state, indent=1, sort_keys=True))
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for s in report:
            gb.update_or_create_student(s)
            try:
                gb.remove_submission(ASSIGNMENT, s)
            except Exception:
                pass
        gb.db.commit()
    record(course, report, results)
    sanitize_feedback_sources(course, report)
    for student, error in generate_feedback(course, [s for s in report if results.get(s)], jobs, log).items():
        report[student]["notes"].append(f"no feedback pages: {error}")
    export(course, report, got.rejected)
    return report


def generate_feedback(course: Path, students: list[str], jobs: int, log=print,
                      timeout: float = FEEDBACK_TIMEOUT) -> dict:
    """nbgrader's feedback pages for ``students``, ``jobs`` processes at once; {student: error} for
    the students whose pages could not be made (their grades stand).

    Each student's pages depend only on their autograded notebooks and their rows in the gradebook,
    which every process only reads, so they can be made side by side (nbgrader's own
    ``generate_feedback`` makes them one student after another; benchmarks/grading_wallclock.txt
    has what that cost). The pages are the same whichever process makes them.

    A student whose pages take more than ``timeout`` seconds (a submission built to be slow to
    render) loses their pages, not the batch: their process is killed, their half-made pages are
    removed, and the students after them get a new process. The pages are capped in size before
    (``sanitize_feedback_sources``), so a real notebook takes a few seconds at most."""
    students = sorted(students)
    errors: dict = {}
    n = max(1, min(jobs, len(students)))
    with tempfile.TemporaryDirectory(prefix="pusht-feedback-") as tmp:
        queue = [students[i::n] for i in range(n) if students[i::n]]
        running, count = [], 0

        def start(chunk):
            nonlocal count
            count += 1
            done, err = Path(tmp) / f"{count}.jsonl", Path(tmp) / f"{count}.err"
            args = json.dumps({"course": str(course), "students": chunk, "answer": str(done)})
            with open(err, "w") as stderr:       # a file, not a pipe: no process waits on a full one
                proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--feedback", args],
                                        cwd=course, stdout=subprocess.DEVNULL, stderr=stderr, env=tool_env(),
                                        start_new_session=True)
            running.append({"chunk": chunk, "done": done, "err": err, "proc": proc, "seen": 0,
                            "since": time.monotonic()})

        for chunk in queue:
            start(chunk)
        while running:
            time.sleep(0.05)
            for job in list(running):
                finished = []
                for line in job["done"].read_text().splitlines() if job["done"].exists() else []:
                    try:
                        finished.append(json.loads(line))
                    except ValueError:           # a line being written as we read
                        break
                if len(finished) > job["seen"]:
                    job["seen"], job["since"] = len(finished), time.monotonic()
                left = job["chunk"][len(finished):]
                exited = job["proc"].poll() is not None
                late = not exited and time.monotonic() - job["since"] > timeout
                if not (exited or late):
                    continue
                running.remove(job)
                errors.update({f["student"]: f["error"] for f in finished if f["error"]})
                if late:
                    try:
                        os.killpg(job["proc"].pid, signal.SIGKILL)
                    except ProcessLookupError:
                        pass
                    job["proc"].wait()
                if not left:
                    continue
                stuck = left[0]
                errors[stuck] = (f"its feedback pages took more than {timeout:g} s to make and were "
                                 "skipped (the grades are recorded)" if late else
                                 _last_error(job["err"].read_text(errors="replace")))
                shutil.rmtree(course / "feedback" / stuck / ASSIGNMENT, ignore_errors=True)
                if left[1:]:
                    start(left[1:])
    for student, error in sorted(errors.items()):
        log(f"nbgrader generate_feedback failed for {student}: {error}")
    return errors


def _feedback_for(course: Path, students: list[str], answer: Path | None = None) -> dict:
    """Feedback for each of ``students`` in this process; returns {student: error} for failures.
    With ``answer``, each student's outcome is also appended to that file as one JSON line the
    moment it is known (the parent's clock runs per student)."""
    api = nbgrader_api(course)
    errors = {}
    for student in students:
        res = api.generate_feedback(ASSIGNMENT, student_id=student, force=True)
        error = None if res.get("success") else _last_error(res.get("error") or res.get("log") or "")
        if error:
            errors[student] = error
        if answer is not None:
            with open(answer, "a") as f:
                f.write(json.dumps({"student": student, "error": error}) + "\n")
    return errors


def record(course: Path, report: dict, results: dict) -> None:
    """Write every student's scores into the course gradebook (this process is its only writer)."""
    from nbgrader.api import Gradebook, MissingEntry

    scheme = yaml.safe_load((HERE / "mark_scheme.yaml").read_text()) if (HERE / "mark_scheme.yaml").exists() else {}
    manual = read_manual(course)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for student, rep in report.items():
            res = results.get(student, {})
            if not res:
                continue
            with warnings.catch_warnings():
                # nbgrader's add_submission builds its rows before adding them to the session, which
                # SQLAlchemy 2 reports once per process ("Object of type <SubmittedAssignment> not in
                # session"); the rows are added right after, so it is noise on the instructor's screen
                warnings.filterwarnings("ignore", message=r"Object of type <\w+> not in session")
                gb.add_submission(ASSIGNMENT, student, timestamp="2026-01-01 00:00:00.000000 UTC")
            for name, entry in res.items():
                nb_id = name[:-len(".ipynb")]
                if entry.get("note"):
                    rep["notes"].append(f"{name}: {entry['note']}")
                if not entry["ok"]:
                    rep["failed"][name] = entry["error"]
                    rep["notes"].append(f"{name}: nbgrader could not finish this notebook ({entry['error']}); "
                                        f"points from the tests that had already run are kept")
                sub = gb.find_submission_notebook(nb_id, ASSIGNMENT, student)
                for grade in sub.grades:
                    g = grade.name
                    comment = None
                    if g in entry["scores"] and entry["scores"][g] is not None:
                        grade.auto_score = entry["scores"][g]
                    if g in entry["verdicts"]:
                        v = entry["verdicts"][g]
                        found = rep["delegated"].get(g)
                        if found:
                            v = vars(checks.judge(checks.TESTS[g], "", delegation=found))
                        grade.manual_score = grade.max_score if v["passed"] else 0.0
                        grade.needs_manual_grade = False
                        rep["verdicts"][g] = (grade.manual_score, grade.max_score, v["message"])
                    ex = g[:-len("_order")] if g.endswith("_order") else None
                    if ex in rep["completion"]:
                        ok, why = rep["completion"][ex]
                        grade.manual_score = grade.max_score if ok else 0.0
                        grade.needs_manual_grade = False
                        comment = why
                    elif g in scheme:
                        comment = f"Mark scheme: {scheme[g]}"
                    row = manual.get((student, nb_id, g))
                    if row:
                        try:
                            score = float(row["score"])
                        except ValueError:
                            score = float("nan")
                        if 0 <= score <= grade.max_score:
                            grade.manual_score = score
                            grade.needs_manual_grade = False
                            comment = (row.get("comment") or "") + (f"\n\n{comment}" if comment else "")
                        else:
                            rep["notes"].append(f"manual grade {row['score']!r} for {nb_id} {g} refused: "
                                                f"outside 0..{grade.max_score}")
                    if comment is not None:
                        try:
                            gb.find_comment(g, nb_id, ASSIGNMENT, student).manual_comment = comment
                        except MissingEntry:
                            pass
            gb.db.commit()


def read_manual(course: Path) -> dict:
    manual = {}
    if (course / "manual_grades.csv").exists():
        with open(course / "manual_grades.csv", newline="") as f:
            for row in csv.DictReader(f):
                manual[(row["student_id"], row["notebook"], row["grade_id"])] = row
    return manual


def sanitize_feedback_sources(course: Path, report: dict) -> None:
    """Before feedback: hidden tests out, each test's verdict in, long outputs cut."""
    for student, rep in report.items():
        folder = course / "autograded" / student / ASSIGNMENT
        for path in folder.glob("*.ipynb"):
            nb = nbformat.read(path, as_version=4)
            nb.metadata.pop("widgets", None)
            budget = text_budget = FEEDBACK_NOTEBOOK_CHARS
            for cell in nb.cells:
                g = cellcode.gid(cell)
                if cell.cell_type == "code" and "### BEGIN HIDDEN TESTS" in cell.source:
                    cell.source = _strip_hidden(cell.source)
                text_budget = _cap_source(cell, text_budget)
                if g in rep["verdicts"]:
                    score, max_score, msg = rep["verdicts"][g]
                    cell.outputs = _without_grader_lines(cell.get("outputs", []))
                    cell.outputs.append(nbformat.v4.new_output("stream", name="stdout",
                                        text=f"[grader] {g}: {score:g} of {max_score:g} points: {msg}\n"))
                if cell.cell_type == "code":
                    # widgets (progress bars) are live views with random ids: nothing in a static page
                    cell.outputs = _coalesce_streams([o for o in cell.get("outputs", []) if WIDGET not in o.get("data", {})])
                    budget = _cap_outputs(cell, budget)
            nbformat.write(nb, path)


def _without_grader_lines(outputs: list) -> list:
    """A test cell's outputs without the kernel's own grading lines (the verdict replaces them).
    Line by line, after joining the streams: where the kernel cut the printed text into messages
    depends on timing, so a student's line can share a message with a grading line."""
    out = []
    for o in _coalesce_streams(outputs):
        if o.get("output_type") == "stream":
            lines = [l for l in _text(o).splitlines(keepends=True)
                     if "[graded outside this kernel]" not in l and not l.startswith("[grader] ")]
            if not lines:
                continue
            o["text"] = "".join(lines)
        out.append(o)
    return out


def _coalesce_streams(outputs: list) -> list:
    """Consecutive stdout (or stderr) outputs joined into one, as Jupyter displays them. Where the
    kernel cut a cell's printed text into messages depends on timing (it flushes on a clock), so
    without this two gradings of the same notebook could give different feedback pages."""
    out = []
    for o in outputs:
        if (o.get("output_type") == "stream" and out and out[-1].get("output_type") == "stream"
                and out[-1].get("name") == o.get("name")):
            out[-1]["text"] = _text(out[-1]) + _text(o)
        else:
            out.append(o)
    return out


def _text(o) -> str:
    t = o.get("text", "")
    return "".join(t) if isinstance(t, list) else t


def _strip_hidden(src: str) -> str:
    out, hidden = [], False
    for line in src.splitlines(keepends=True):
        if line.strip() == "### BEGIN HIDDEN TESTS":
            hidden = True
            out.append(HIDDEN_NOTE)
        elif line.strip() == "### END HIDDEN TESTS":
            hidden = False
        elif not hidden:
            out.append(line)
    return "".join(out)


def _cap_source(cell, budget: int) -> int:
    """A cell's text cut at FEEDBACK_SOURCE_CHARS, or removed once the notebook's texts have used
    ``budget``; returns what is left of it. Rendering is linear but not fast (nbconvert's markdown
    took about 7 s per million characters of the slowest text tried), and a hand-in may be 50 MB."""
    source = cell.get("source", "")
    if len(source) <= min(FEEDBACK_SOURCE_CHARS, budget):
        return budget - len(source)
    note = (f"[... this cell's text is cut at {FEEDBACK_SOURCE_CHARS} characters in the feedback page]"
            if budget >= FEEDBACK_SOURCE_CHARS else
            "[... this cell's text is left out of the feedback page: the page is capped in size]")
    keep = source[:FEEDBACK_SOURCE_CHARS] if budget >= FEEDBACK_SOURCE_CHARS else ""
    cell.source = keep + (f"\n# {note}\n" if cell.cell_type == "code" else f"\n\n*{note}*\n")
    return max(budget - len(keep), 0)


def _cap_outputs(cell, budget: int) -> int:
    kept = []
    for o in cell.get("outputs", []):
        for key in ("text",):
            if isinstance(o.get(key), str) and len(o[key]) > FEEDBACK_OUTPUT_CHARS:
                o[key] = o[key][:FEEDBACK_OUTPUT_CHARS] + f"\n[... output cut at {FEEDBACK_OUTPUT_CHARS} characters]\n"
        if o.get("output_type") == "error":
            o["traceback"] = [t[:FEEDBACK_OUTPUT_CHARS] for t in o.get("traceback", [])[:50]]
        size = len(json.dumps(o))
        if size > budget:
            kept.append(nbformat.v4.new_output("stream", name="stdout",
                                               text="[... further output removed: the page is capped in size]\n"))
            break
        budget -= size
        kept.append(o)
    cell.outputs = kept
    return budget


def export(course: Path, report: dict, rejected: list[str] = ()) -> None:
    """grades.csv (nbgrader's export of the gradebook) and report.csv (what happened to each file)."""
    export_csv(course, course / "grades.csv")
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb, \
            open(course / "report.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["student_id", "score", "max_score", "notes"])
        for student in sorted(report):
            try:
                sub = gb.find_submission(ASSIGNMENT, student)
                score, max_score = sub.score, sub.max_score
            except MissingEntry:
                score, max_score = 0.0, gb.find_assignment(ASSIGNMENT).max_score
            rep = report[student]
            notes = rep["notes"] + [why for _, why in rep["completion"].values()]
            notes += [f"{g}: {s:g}/{m:g}: {msg}" for g, (s, m, msg) in sorted(rep["verdicts"].items())]
            w.writerow([student, round(score, 3), round(max_score, 3), " | ".join(notes)])
        for line in rejected:          # files that could not be placed to any student
            w.writerow(["(not graded)", "", "", line])


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--worker"]:
        a = json.loads(argv[1])
        out = worker(Path(a["priv"]), a["student"], a["timeout"], a["confine"], a["uid"], a["limits"], a.get("shared"),
                     a.get("keep_workdir", False))
        Path(a["answer"]).write_text(json.dumps(out))
        return 0
    if argv[:1] == ["--feedback"]:
        a = json.loads(argv[1])
        _feedback_for(Path(a["course"]), a["students"], Path(a["answer"]))
        return 0
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("submissions", type=Path, help="a .zip from the LMS, or a folder of notebooks")
    p.add_argument("--course", type=Path, default=HERE, help="nbgrader course folder (default: autograde/)")
    p.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    p.add_argument("--jobs", type=int, default=None, help="grading tasks at once (default: one per core); fewer students than that split their notebooks")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="grade on a Dask cluster, e.g. tcp://10.0.0.5:8786 (README: 'Grading a large class')")
    p.add_argument("--regrade", action="store_true",
                   help="grade again students whose submissions did not change since the last run")
    p.add_argument("--share", choices=("auto", "yes", "no"), default="auto",
                   help=f"compute the stages no student can change once, from the solutions (auto: from {SHARE_FROM} students)")
    p.add_argument("--no-confine", action="store_true",
                   help="run student code unconfined (only for trusted notebooks; prints a warning)")
    args = p.parse_args(argv)
    if not args.submissions.exists():
        p.error(f"{args.submissions} does not exist")
    report = grade_class(args.submissions, args.course, args.timeout, args.jobs,
                         confine=False if args.no_confine else None, scheduler=args.scheduler,
                         share={"auto": None, "yes": True, "no": False}[args.share], regrade=args.regrade)
    print(f"graded {len(report)} students: scores in {args.course / 'grades.csv'}, per-file notes in "
          f"{args.course / 'report.csv'}, feedback in {args.course / 'feedback'}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
