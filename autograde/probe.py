"""Verdict inputs from a process no student kernel ever touched.

The kernel that runs a hand-in is the student's: anything it writes, prints or leaves behind can be
forged. So no verdict reads it. For each hidden test, the grader instead:

1. takes the hand-in's cells above the test cell, as the kernel would run them (``cellcode``), and
   keeps every statement that can affect the graded function (``recreate.program``: every import
   and definition, every statement of the student's but those that provably change nothing the
   function needs, and the release's own statements that bind or change what it needs): no
   training, no plotting, no experiment of the chapter's;
2. chooses a fresh nonce (``secrets``) that seeds the cases' random inputs;
3. sends the statements, the cases and the nonce to a probe server (``pusht.grader.probe_server``) that
   it started itself in a sandbox of its own (bubblewrap, no network, the student's leased uid,
   the same limits as a kernel, a private size-capped ``/tmp``), with the package bound in a copy
   whose exercise implementations only raise (``stripped.py``); the server forks a child per test
   that defines the function and runs the cases;
4. reads the child's numbers back over a pipe, at most ``pusht.grader.probes.MAX_RESULTS`` bytes, within
   the time limit, and decodes them without decompressing or evaluating anything;
5. judges them against the same cases run on the real implementations in its own process
   (``checks.judge``).

What this proves: the numbers judged are what the hand-in's own definitions return on inputs they
could not know in advance, computed where the package's answers do not exist. What it does not
prove: that the function the student wrote is the one the kernel ran (the statements are run
again, ``exec`` and ``%%writefile`` included, but a string downloaded at run time is not there: no
network); where the kernel ran the test cell and the probe could not define or run the function,
``tripwire.py`` tells the instructor instead of a silent 0; that the code is the student's own (a copy of the
answer key is flagged for the instructor by ``answer_key.py``, not zeroed); that the student did
not compute the answer with other package functions that are not exercises.
"""

from __future__ import annotations

import ast
import inspect
import json
import os
import secrets
import select
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from pusht.reference import AUTOGRADE, GRADING_ENV

from . import cellcode, checks, sandbox, stripped
from .recreate import program, release_statements, test_cell_index  # noqa: F401  the probe's program

PROBE_SECONDS = 120          # per test: defining the function and every case


# --- what to run: ``recreate.program`` ----------------------------------------------------------------
def warm_statements(release) -> list[str]:
    """The release notebooks' top-level imports: the probe server imports them once, before forking."""
    out = []
    for nb in release.values():
        for cell in nb.cells:
            if cell.get("cell_type") == "code":
                tree = cellcode.parse(cellcode.source(cell))
                out += [ast.unparse(n) for n in (tree.body if tree else []) if isinstance(n, (ast.Import, ast.ImportFrom))]
    return sorted(set(out))


def helpers_for(test) -> dict[str, str]:
    """Source of the functions a test's cases hand to the student's function (``{"fn": name}``, or
    named in a generated case's ``"helpers"``):
    sent to that test's probe alone, never present anywhere else in the probe process."""
    names = {a["fn"] for c in test.cases for a in c.spec.get("args", []) if isinstance(a, dict) and "fn" in a}
    names |= {name for c in test.cases for name in c.spec.get("helpers", [])}      # a generated case's
    out = {}
    for name in sorted(names):
        source = inspect.getsource(checks.reference_function(checks.HELPERS[name]))
        tree = cellcode.python_tree(textwrap.dedent(source))
        tree.body[0].decorator_list = []
        out[name] = ast.unparse(tree)
    return out


# --- where to run it: a probe server of the grader's own ----------------------------------------------
class ProbeServer:
    """One grading task's probe server (``pusht.grader.probe_server``) in a sandbox of its own.

    ``with ProbeServer(uid, limits, warm) as server: server.run(test, statements)``. The sandbox
    binds nothing writable but a private ``/tmp``, and the package as ``stripped.package()``."""

    def __init__(self, uid: int | None, limits: dict, warm: list[str] = (), confine: bool = True,
                 seconds: float = PROBE_SECONDS):
        self.uid, self.limits, self.warm, self.confine = uid, limits, list(warm), confine
        self.seconds = seconds
        self.slack = 30.0          # seconds on top of ``seconds`` for one whole exchange with the server
        self.proc, self.init = None, None

    def __enter__(self) -> "ProbeServer":
        try:
            self.start()
        except Exception:          # noqa: BLE001  run() tries again, and says why each test was not checked
            self.stop()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def start(self) -> None:
        argv = [sys.executable, "-P", "-m", "pusht.grader.probe_server"]
        env = {k: os.environ[k] for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "MKL_CBWR") if k in os.environ}
        env.setdefault("OMP_NUM_THREADS", "1")
        env.setdefault("MKL_NUM_THREADS", "1")
        env["MPLBACKEND"] = "Agg"
        env[GRADING_ENV] = AUTOGRADE      # as in the kernel: the notebooks' grading settings
        if self.confine:
            env["PUSHT_PROBE_SWEEP"] = "1"              # alone in its sandbox's PID namespace
            package = stripped.package()
            self.proc, self.init = sandbox.start_sandbox(
                lambda fd: sandbox.bwrap_command(Path("/"), [], self.uid, limits=self.limits, env=env,
                                                 info_fd=fd, package=package),
                argv, memory=sandbox.sandbox_bytes(self.limits), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL, cwd="/")
        else:        # unconfined grading (no bubblewrap): the real package, with a loud warning upstream
            self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                         stderr=subprocess.DEVNULL, env={**os.environ, **env},
                                         start_new_session=True)
        os.set_blocking(self.proc.stdin.fileno(), False)     # every write has a deadline (_send)
        if self.warm:
            try:
                deadline = time.monotonic() + 300
                self._send({"warm": self.warm}, deadline)
                self._reply(deadline)
            except BaseException:
                self.stop()
                raise

    def stop(self) -> None:
        if self.proc is None:
            return
        if self.init is not None or self.confine:
            sandbox.end_sandbox(self.proc, self.init)
        else:
            self.proc.kill()
            self.proc.wait()
        for f in (self.proc.stdin, self.proc.stdout):
            try:
                f.close()
            except OSError:
                pass
        self.proc, self.init = None, None

    def _send(self, req: dict, deadline: float) -> None:
        """Write one request before ``deadline`` (a server stopped by a child's code reads nothing)."""
        fd, view = self.proc.stdin.fileno(), memoryview(json.dumps(req).encode() + b"\n")
        while view:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([], [fd], [], left)[1]:
                raise TimeoutError("the probe server did not take the request in time")
            try:
                view = view[os.write(fd, view[: 1 << 16]):]
            except BlockingIOError:
                continue

    def _read(self, n: int, deadline: float, line: bool = False) -> bytes:
        """At most ``n`` bytes (up to a newline with ``line``) from the server before ``deadline``."""
        fd, out = self.proc.stdout.fileno(), bytearray()
        while len(out) < n:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError("the probe server did not answer in time")
            chunk = os.read(fd, 1 if line else min(n - len(out), 1 << 16))
            if not chunk:
                raise EOFError("the probe server ended")
            out += chunk
            if line and chunk == b"\n":
                break
        return bytes(out)

    def _reply(self, deadline: float) -> tuple[dict, bytes]:
        from pusht.grader.probes import MAX_RESULTS

        head = json.loads(self._read(200, deadline, line=True))
        size = int(head.get("bytes", 0))
        if not 0 <= size <= MAX_RESULTS:
            raise ValueError("the probe server announced too many bytes")
        return head, self._read(size, deadline) if size else b""

    def run(self, test, statements: list[tuple[str, str]], fresh: int | None = None) -> dict:
        """The raw results of ``test``'s cases on the function ``statements`` define:
        {"fresh", "status", "setup": [lines], "results": [per case: arrays or error] or None}."""
        from pusht.grader.probes import decode_results

        fresh = secrets.randbelow(2 ** 24) if fresh is None else fresh
        req = {"function": test.function, "program": statements, "cases": [c.spec for c in test.cases],
               "fresh": fresh, "helpers": helpers_for(test), "seconds": self.seconds}
        out = {"fresh": fresh, "status": "ok", "setup": [], "results": None}
        try:
            if self.proc is None or self.proc.poll() is not None:
                self.stop()
                self.start()         # a server an earlier test's code killed: this test gets a new one
            deadline = time.monotonic() + self.seconds + self.slack      # the whole exchange, send and reply
            self._send(req, deadline)
            head, data = self._reply(deadline)
        except Exception as e:     # noqa: BLE001  a server that died, stalled or never started
            out["status"] = f"the probe process failed ({type(e).__name__}: {str(e)[:200]})"
            self.stop()          # a server that stopped answering is not asked again
            return out
        out["status"] = str(head.get("status", "?"))
        if out["status"] != "ok":
            return out
        try:
            out["setup"], out["results"] = decode_results(data, len(test.cases))
        except (ValueError, TypeError) as e:
            out["status"] = f"unreadable results ({str(e)[:200]})"
        return out
