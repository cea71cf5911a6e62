"""The grader's probe process: define a student's function from their cells, run the probes on it.

Learners never need this module. The autograder (``autograde/probe.py``) starts it once per
grading task, inside a sandbox of its own, with a copy of this package in which the exercises'
implementations only raise (``pusht.grader.probes``), and talks to it over its standard streams:

    python -P -m pusht.grader.probe_server

Each line on its standard input is a request (JSON) from the grader: the statements that define
the graded function (the student's cells above the test cell, as ``autograde/probe.py`` chose
them), the function's name, the probe cases, the nonce, any function the cases hand over
(``helpers``, source text) and a time limit. For each, it forks a child that executes the
statements in a fresh ``__main__``, runs the cases on the function and writes the encoded results
(``pusht.grader.probes.encode_results``) into a pipe of its own; the server reads at most
``MAX_RESULTS`` bytes from it before the limit, kills the child's process group, and answers on
its standard output with one header line and those bytes. The grader decodes them
(``decode_results``) and judges them; nothing the child writes is trusted. Then every other
process in the sandbox is killed (``_sweep``), so nothing a child started outlives its request.

The server itself runs no student code. It makes itself non-dumpable (inherited by every child),
so a child cannot trace it or any other child, nor open their descriptors through ``/proc``; a
child holds only its own pipe and ``/dev/null`` on its standard streams, so it cannot answer for
another request. One student's requests share a server, so a child can at worst spoil its own
student's later results (kill the server, say), never another student's.
"""

from __future__ import annotations

import json
import linecache
import os
import select
import signal
import sys
import time

PR_SET_DUMPABLE = 4
MAX_REQUEST = 8 << 20          # bytes of one request line (the grader's own)


def _nondumpable() -> None:
    import ctypes

    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_DUMPABLE, 0, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def warm(statements: list[str]) -> None:
    """Import what the notebooks import, once, before any fork (each one that fails is skipped)."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    import numpy  # noqa: F401
    import torch  # noqa: F401

    import pusht.grader.probes  # noqa: F401
    for src in statements:
        try:
            exec(compile(src, "<warm-up>", "exec"), {"__name__": "__warm__"})
        except BaseException:      # noqa: BLE001  an import this sandbox cannot do
            pass


DEFINE_SECONDS = 60.0          # the statements above the test cell, all together, at most
SETUP_SECONDS = 5.0            # each definition or import after that budget is spent


_SHELL = None      # the one _Shell, made below


class _OutOfTime(BaseException):
    """Raised in a statement that re-ran longer than the definitions' budget."""


class _Shell:
    """What ``get_ipython()`` answers in the probe: the magics a cell turns into calls
    (``cellcode``) run as the kernel ran them where they define something (``%%writefile`` writes
    its module, here in the probe's private folder), and do nothing otherwise (``%matplotlib``,
    ``!pip``): they change nothing a graded function reads."""

    def run_cell_magic(self, name, line, cell):
        if name == "writefile":
            args = line.split()
            append = "-a" in args or "--append" in args
            paths = [a for a in args if not a.startswith("-")]
            if paths:
                with open(paths[0], "a" if append else "w") as f:
                    f.write(cell)

    def run_line_magic(self, name, line, *args):
        return None

    def system(self, *args, **kwargs):
        return None

    def getoutput(self, *args, **kwargs):
        return []


_SHELL = _Shell()


def _future_flags(code) -> int:
    import __future__

    return code.co_flags & sum(getattr(__future__, f).compiler_flag for f in __future__.all_feature_names)


def define(program: list, ns: dict, budget: float, function: str | None = None) -> list[str]:
    """Run ``program`` ([(label, source)], the statements above the test cell in notebook order) in
    ``ns`` as the kernel ran them; returns what went wrong, one line per statement.

    Each statement is compiled under the ``__future__`` flags in force at that point, as IPython
    does (a ``from __future__ import annotations`` holds for every later cell), and registered as
    IPython registers a cell, so that ``inspect.getsource`` (``torch.jit.script``, say) finds it.
    One that raises does not stop the others. Together they have ``budget`` seconds; once it is
    spent, only imports and definitions run, each for at most ``SETUP_SECONDS``. The lines of the
    statements that bind ``function`` come first (the learner reads the first)."""
    import ast
    import time

    flags, out, first = 0, [], []
    ns.setdefault("get_ipython", lambda: _SHELL)
    cwd = os.getcwd()           # a kernel imports the modules its notebook wrote from its folder; so does this
    if cwd not in sys.path:
        sys.path.append(cwd)
    deadline = time.monotonic() + budget

    def alarm(signum, frame):
        raise _OutOfTime()

    old = signal.signal(signal.SIGALRM, alarm)
    try:
        for label, src in program:
            linecache.cache[label] = (len(src), None, src.splitlines(True), label)
            try:
                code = compile(src, label, "exec", flags=flags, dont_inherit=True)
            except BaseException as e:     # noqa: BLE001  the kernel could not have run it either
                out.append(f"{label}: {type(e).__name__}: {str(e)[:200]}")
                continue
            flags |= _future_flags(code)
            left = deadline - time.monotonic()
            if left <= 0:
                try:
                    kind = type(ast.parse(src).body[0]).__name__
                except Exception:          # noqa: BLE001
                    kind = ""
                if kind not in ("Import", "ImportFrom", "FunctionDef", "AsyncFunctionDef", "ClassDef"):
                    out.append(f"{label}: not run: the cells above the test took more than {budget:.0f} s")
                    continue
                left = SETUP_SECONDS
            signal.setitimer(signal.ITIMER_REAL, left)
            try:
                exec(code, ns)
            except BaseException as e:     # noqa: BLE001  the cell's own error, as the kernel had it
                line = (f"{label}: stopped: the cells above the test took more than {budget:.0f} s to run again"
                        if isinstance(e, _OutOfTime) else f"{label}: {type(e).__name__}: {str(e)[:200]}")
                (first if function and function in code.co_names else out).append(line)
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    return first + out


def _child(req: dict, w: int) -> None:
    """In the forked child: define, probe, write the results to ``w``; never returns."""
    import resource
    import types

    from pusht.grader import probes as grading

    try:
        os.setsid()
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        os.closerange(3, w)
        os.closerange(w + 1, 1 << 16)
        seconds = max(1, int(req.get("seconds", 120)))
        resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 1))
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        main = types.ModuleType("__main__")
        sys.modules["__main__"] = main
        ns = main.__dict__
        setup = define(req["program"], ns, min(DEFINE_SECONDS, seconds / 2), req["function"])
        helpers = {}
        for name, src in req.get("helpers", {}).items():
            space = {"torch": __import__("torch"), "__name__": "pusht_helpers"}
            exec(compile(src, f"<{name}>", "exec", dont_inherit=True), space)
            helpers[name] = space[name]
        fn = ns.get(req["function"])
        n = len(req["cases"])
        if not callable(fn):
            why = (f"`{req['function']}` is not defined by the cells above the test cell"
                   if fn is None else f"`{req['function']}` is not a function by the cells above the test cell")
            results = [why] * n
        else:
            results = grading.run_probes(req["cases"], fn, int(req["fresh"]), helpers)
        data = grading.encode_results(results, setup)
    except BaseException as e:             # noqa: BLE001
        data = json.dumps({"setup": [f"the probe stopped: {type(e).__name__}: {str(e)[:200]}"],
                           "results": None}).encode()
    view = memoryview(data)
    try:
        while view:
            view = view[os.write(w, view[: 1 << 16]):]
    finally:
        os._exit(0)


def _collect(pid: int, r: int, limit: int, seconds: float) -> tuple[str, bytes]:
    """Read the child's pipe until it is done, the limit or the clock; then kill its group."""
    chunks, size, status = [], 0, "ok"
    deadline = time.monotonic() + seconds
    exited = False
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            status = "timeout"
            break
        ready, _, _ = select.select([r], [], [], min(left, 0.05 if exited else 1.0))
        if ready:
            data = os.read(r, 1 << 16)
            if not data:
                break
            chunks.append(data)
            size += len(data)
            if size > limit:
                status = "toolarge"
                break
        elif exited:
            break                      # the child is gone and nothing more came: a grandchild holds the pipe
        if not exited:
            done, _ = os.waitpid(pid, os.WNOHANG)
            exited = done == pid
    for target in (-pid, pid):
        try:
            os.kill(target, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    if not exited:
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass
    os.close(r)
    return status, b"".join(chunks)


SWEEP_ENV = "PUSHT_PROBE_SWEEP"     # "1": this server is alone in a PID namespace of its own (a sandbox)


def _sweep() -> None:
    """Kill every process of the sandbox but its init and this server: what a child left behind
    (a grandchild that left its process group) never lives on into the next test's child. Only in
    a sandbox of its own (``SWEEP_ENV``), where ``/proc`` lists nothing else."""
    me = os.getpid()
    for name in os.listdir("/proc"):
        if name.isdigit() and int(name) not in (1, me):
            try:
                os.kill(int(name), signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
    while True:
        try:
            if os.waitpid(-1, os.WNOHANG)[0] == 0:
                break
        except ChildProcessError:
            break


def serve(stdin, stdout) -> None:
    from pusht.grader.probes import MAX_RESULTS

    while True:
        line = stdin.readline(MAX_REQUEST)
        if not line:
            return
        req = json.loads(line)
        if "warm" in req:
            warm(req["warm"])
            stdout.write(b'{"status": "warm"}\n')
            stdout.flush()
            continue
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            _child(req, w)
        os.close(w)
        status, data = _collect(pid, r, MAX_RESULTS, float(req.get("seconds", 120)) + 5)
        if status == "toolarge":
            data = b""
        if os.environ.get(SWEEP_ENV) == "1":
            _sweep()
        stdout.write(json.dumps({"status": status, "bytes": len(data)}).encode() + b"\n" + data)
        stdout.flush()


def main() -> int:
    _nondumpable()
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    os.chdir(os.environ.get("TMPDIR", "/tmp"))
    stdin = os.fdopen(os.dup(0), "rb")
    stdout = os.fdopen(os.dup(1), "wb")
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)
    serve(stdin, stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())
