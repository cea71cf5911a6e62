"""A kernel factory for the course's autograder: import once, fork a fresh kernel per notebook.

Learners never need this module. Grading one student runs six notebooks, each in a new Jupyter
kernel, and every one of those kernels used to spend about 3.4 s starting Python, ipykernel and
importing torch and this package before its first cell did anything (``benchmarks/
grading_wallclock.txt``). The autograder (``autograde/sandbox.py``) instead starts this process
once per student, *inside* that student's sandbox, and asks it for each notebook's kernel:

    python -m pusht.zygote SOCKET < token

It imports what the chapter's notebooks import (and nothing runs: no torch op, no thread, no
event loop, so forking stays safe), listens on the Unix socket ``SOCKET``, and for every request
that carries the token it read from its standard input, forks. The child is an ordinary
ipykernel on the request's connection file, working folder and standard streams, with its own
random seeds; the parent watches the request's socket, and when the kernel exits, or the
requester hangs up (its kernel was shut down), it kills the kernel and every other process left
in the sandbox, so nothing one notebook started lives on into the next, as when each notebook had
a sandbox of its own. One kernel at a time: a new request first ends the last one.

The factory is not a way out of the sandbox: it runs inside the same one, as the same user, under
the same limits. It makes itself non-dumpable, so a kernel it forked cannot trace it or read its
memory, and it serves only requests that know the token, which no kernel can read.
"""

from __future__ import annotations

import json
import os
import secrets
import selectors
import signal
import socket
import sys
import time

PR_SET_DUMPABLE = 4
MAX_REQUEST = 1 << 16


def _prctl_dumpable(value: int) -> None:
    import ctypes

    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_DUMPABLE, value, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def preload() -> None:
    """Import what a notebook's kernel will: ipykernel, torch, numpy, matplotlib, this package."""
    os.environ.setdefault("MPLBACKEND", "module://matplotlib_inline.backend_inline")   # as ipykernel sets
    import importlib
    import pkgutil

    import pusht

    # every module of this package, found rather than listed, so that one added later is preloaded
    # too (walk_packages imports the subpackages it descends into; one that fails is skipped here)
    ours = [m.name for m in pkgutil.walk_packages(pusht.__path__, "pusht.", onerror=lambda name: None)
            if m.name != "pusht.zygote"]
    for name in ["ipykernel.kernelapp", "ipykernel.ipkernel", "IPython.display", "numpy", "torch",
                 "torch.nn.functional", "matplotlib.pyplot", "tqdm.auto", "pymunk", *ours]:
        try:
            importlib.import_module(name)
        except Exception:        # noqa: BLE001  a module that fails here fails again, visibly, in the kernel
            pass


def _others() -> list[int]:
    """Every process in this sandbox's PID namespace but its init (1) and this one."""
    me = os.getpid()
    return [int(p) for p in os.listdir("/proc") if p.isdigit() and int(p) not in (1, me)]


def kill_others() -> None:
    """SIGKILL every other process in the sandbox, until none is left (a forking one included)."""
    for _ in range(50):
        pids = _others()
        if not pids:
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.01)
        _reap()


def _reap() -> dict:
    """Collect exited children without blocking: {pid: exit code}."""
    done = {}
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return done
        if pid == 0:
            return done
        done[pid] = os.waitstatus_to_exitcode(status)


def _child(request: dict, fds: list[int], listener: socket.socket, conn: socket.socket) -> None:
    """In the forked child: become the notebook's kernel. Never returns."""
    try:
        listener.close()
        conn.close()
        _prctl_dumpable(1)                       # an ordinary process again, as a fresh kernel is
        for target, fd in zip((0, 1, 2), fds):
            os.dup2(fd, target)
        for fd in fds:
            if fd > 2:
                os.close(fd)
        os.chdir(request["cwd"])
        sys.path.insert(0, os.getcwd())           # as ``python -m ipykernel_launcher`` run there has it
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        import random

        import numpy as np

        random.seed()                             # a kernel of its own: fresh seeds, as a new process has
        np.random.seed()
        from ipykernel.kernelapp import IPKernelApp

        sys.argv = ["ipykernel_launcher", "-f", request["connection_file"],
                    "--HistoryManager.hist_file=:memory:"]
        IPKernelApp.launch_instance(argv=sys.argv[1:])
        code = 0
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else 1
    except BaseException:                        # noqa: BLE001  reported on the kernel's stderr
        import traceback

        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def serve(path: str, token: str) -> None:
    """Listen on ``path``; fork one kernel per authenticated request (see the module doc)."""
    _prctl_dumpable(0)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass
    listener.bind(path)
    os.chmod(path, 0o600)
    listener.listen(4)
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ)
    kernel: tuple[int, socket.socket] | None = None     # (pid, the requester's connection)

    def end(kernel, code):
        pid, conn = kernel
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        kill_others()
        try:
            conn.sendall(f"exit {code}\n".encode())
        except OSError:
            pass
        sel.unregister(conn)
        conn.close()

    while True:
        for key, _ in sel.select(timeout=0.05):
            if key.fileobj is listener:
                conn, _ = listener.accept()
                conn.settimeout(10)
                try:
                    msg, fds, _, _ = socket.recv_fds(conn, MAX_REQUEST, 3)
                    request = json.loads(msg.decode())
                    given = request.get("token") if isinstance(request, dict) else None
                    ok = (isinstance(given, str) and secrets.compare_digest(given.encode(), token.encode())
                          and len(fds) == 3)
                except (OSError, ValueError, UnicodeDecodeError):
                    ok, fds = False, []
                if not ok:
                    for fd in fds:
                        os.close(fd)
                    conn.close()
                    continue
                if kernel is not None:                # one kernel at a time
                    end(kernel, -9)
                    kernel = None
                pid = os.fork()
                if pid == 0:
                    _child(request, fds, listener, conn)
                for fd in fds:
                    os.close(fd)
                conn.settimeout(None)
                conn.sendall(f"pid {pid}\n".encode())
                sel.register(conn, selectors.EVENT_READ)
                kernel = (pid, conn)
            elif kernel is not None and key.fileobj is kernel[1]:
                try:
                    data = kernel[1].recv(64)
                except OSError:
                    data = b""
                if not data:                         # the requester hung up: its kernel is done
                    end(kernel, -9)
                    kernel = None
        done = _reap()
        if kernel is not None and kernel[0] in done:
            end(kernel, done[kernel[0]])
            kernel = None


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m pusht.zygote SOCKET  (the token on standard input)", file=sys.stderr)
        return 2
    token = sys.stdin.readline().strip()
    if not token:
        print("pusht.zygote: no token on standard input", file=sys.stderr)
        return 2
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    preload()
    serve(argv[0], token)
    return 0


if __name__ == "__main__":
    sys.exit(main())
