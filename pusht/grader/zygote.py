"""A kernel factory for the course's autograder: import once, fork a fresh kernel per notebook.

Learners never need this module. Grading one student runs every notebook (seven), each in a new Jupyter
kernel, and every one of those kernels used to spend about 3.4 s starting Python, ipykernel and
importing torch and this package before its first cell did anything (``benchmarks/
grading_wallclock.txt``). The autograder (``autograde/sandbox.py``) instead starts this process
once per student, *inside* that student's sandbox, and asks it for each notebook's kernel:

    python -m pusht.grader.zygote READY     (standard input: a Unix socket that brings the listening socket)

It imports what the chapter's notebooks import (and nothing runs: no torch op, no thread, no
event loop, so forking stays safe), creates the file ``READY`` (the grader waits for it), and for
every request on its listening socket forks. The child is an ordinary ipykernel on the request's
connection file, working folder and standard streams, with its own random seeds; the parent
watches the request's connection, and when the kernel exits, or the requester hangs up (its kernel
was shut down), it kills the kernel and every other process left in the sandbox, so nothing one
notebook started lives on into the next, as when each notebook had a sandbox of its own. One
kernel at a time: a new request first ends the last one.

The factory is not a way out of the sandbox: it runs inside the same one, as the same user, under
the same limits. What must hold is that only the grader can have it fork: a kernel that could
would choose the connection file, folder and descriptors of a process it does not control. So a
request is authenticated by *where it comes from*, never by a secret: every forked kernel starts as
a copy of this process's memory (its stack, its heap, every frame's locals), which the student's
code can read at leisure (``/proc/self/mem``, ``gc``, ``sys._current_frames``), so a token kept
here, as this factory once did, is a token every kernel holds.

* The listening socket is made by the grader (``sandbox.Zygote``) at a path in a private folder
  outside everything the sandbox binds, and handed to this process as a descriptor: it arrives over
  the Unix socket on standard input (SCM_RIGHTS) and is received before anything else runs. No
  process in the sandbox can name that path; a kernel cannot connect to it.
* Not as an inherited descriptor of bwrap: bwrap's own init (pid 1 of the sandbox) keeps every
  descriptor it was started with, and where grading does not run as root that init is the
  student's uid and dumpable, so a kernel could take a copy of any of them with ``pidfd_getfd``
  (measured). The socket pair on standard input is all that init holds, drained and closed at the
  grader's end before any kernel exists.
* Each forked kernel closes the listening socket, the requester's connection and the selector, and
  any other socket it inherited, before the first line of ipykernel runs.
* This process is not dumpable (``PR_SET_DUMPABLE`` 0, first thing): a kernel, of the same uid but
  without capabilities, can neither trace it, nor read its memory, nor list or copy its descriptors
  (``/proc/<pid>/fd``, ``pidfd_getfd``). A forked kernel makes itself dumpable again once the
  factory's descriptors are gone, as a freshly started kernel is (``/proc/self``, debuggers and
  torch's own introspection work as before).
* And a second check on every connection: the peer's credentials (``SO_PEERCRED``). The kernel
  reports a peer's pid as seen from this process's PID namespace, and a process outside the
  sandbox's namespace has no pid there: it reads 0. Every process in the sandbox (a kernel, its
  children, those of a nested namespace) reads as its nonzero pid, even after it has exited. So a
  connection whose peer pid is not 0 is refused, whatever it sends.

Peer credentials alone would not do: the path would then have to be in a folder the sandbox sees
(the socket folder is writable there, kernels' own sockets live in it), and a kernel could replace
the socket with its own, receive the next request and answer it.
"""

from __future__ import annotations

import json
import os
import selectors
import signal
import socket
import stat
import struct
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
            if not m.name.startswith("pusht.grader")]      # the grader's runtime: never a kernel's
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


def _close_sockets_but_stdio() -> None:
    """Close every socket this process holds but its standard streams: a kernel keeps nothing of
    the factory's (the named ones are closed by name first; this is the backstop)."""
    try:
        names = os.listdir("/proc/self/fd")
    except OSError:                # no /proc: the named ones are closed all the same
        return
    for name in names:
        fd = int(name)
        if fd <= 2:
            continue
        try:
            if stat.S_ISSOCK(os.fstat(fd).st_mode):
                os.close(fd)
        except OSError:            # the listing's own descriptor, already closed
            pass


def _child(request: dict, fds: list[int], factory: list) -> None:
    """In the forked child: become the notebook's kernel. Never returns. ``factory``: the
    factory's listening socket, selector and the requester's connection, closed first."""
    try:
        for thing in factory:
            thing.close()
        for target, fd in zip((0, 1, 2), fds):
            os.dup2(fd, target)
        for fd in fds:
            if fd > 2:
                os.close(fd)
        _prctl_dumpable(1)                       # an ordinary process again, as a fresh kernel is
        _close_sockets_but_stdio()
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


def peer_pid(conn: socket.socket) -> int:
    """The pid of the process that connected ``conn``, as this PID namespace numbers it: 0 for a
    process outside it (the grader's launcher), never 0 for one inside (``SO_PEERCRED``)."""
    pid, _uid, _gid = struct.unpack("3i", conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, 12))
    return pid


def _read_request(conn: socket.socket) -> tuple[dict | None, list[int]]:
    """The request on ``conn`` and the three descriptors that came with it, or (None, []) (the
    descriptors closed) if it is not one: not from outside the sandbox, not well formed, or its
    requester already gone."""
    fds: list[int] = []
    try:
        if peer_pid(conn) != 0:                  # from inside the sandbox: a kernel
            return None, []
        msg, fds, _, _ = socket.recv_fds(conn, MAX_REQUEST, 3)
        request = json.loads(msg.decode())
        ok = (isinstance(request, dict) and len(fds) == 3
              and all(isinstance(request.get(k), str) for k in ("connection_file", "cwd")))
        if ok:
            conn.setblocking(False)
            try:                                 # b"" here: the requester gave up and hung up
                ok = conn.recv(1, socket.MSG_PEEK) != b""
            except BlockingIOError:              # nothing more to read: it waits for its answer
                pass
    except (OSError, ValueError, UnicodeDecodeError):
        ok = False
    if ok:
        return request, fds
    for fd in fds:
        os.close(fd)
    return None, []


def serve(listener: socket.socket, ready: str | None = None) -> None:
    """Fork one kernel per request on ``listener`` (see the module doc); create the file ``ready``
    once listening."""
    sel = selectors.DefaultSelector()
    sel.register(listener, selectors.EVENT_READ)
    if ready:
        try:
            os.close(os.open(ready, os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK, 0o644))
        except OSError as e:       # the grader waits for it in vain, then finds it served all the same
            print(f"pusht.grader.zygote: cannot create {ready}: {e}", file=sys.stderr)
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
                try:
                    conn, _ = listener.accept()
                except OSError:
                    continue
                conn.settimeout(10)
                request, fds = _read_request(conn)
                if request is None:
                    conn.close()
                    continue
                if kernel is not None:                # one kernel at a time
                    end(kernel, -9)
                    kernel = None
                pid = os.fork()
                if pid == 0:
                    _child(request, fds, [listener, sel, conn])
                for fd in fds:
                    os.close(fd)
                sel.register(conn, selectors.EVENT_READ)
                kernel = (pid, conn)
                try:
                    conn.settimeout(None)
                    conn.sendall(f"pid {pid}\n".encode())
                except OSError:                        # the requester is gone: so is its kernel
                    end(kernel, -9)
                    kernel = None
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


def receive_listener(channel_fd: int = 0) -> socket.socket:
    """The listening socket the grader sends over the Unix socket ``channel_fd`` (SCM_RIGHTS)."""
    channel = socket.socket(fileno=os.dup(channel_fd))
    try:
        channel.settimeout(30)
        _, fds, _, _ = socket.recv_fds(channel, 16, 1)
    finally:
        channel.close()
    if len(fds) != 1:
        raise ValueError("no listening socket came on standard input")
    listener = socket.socket(fileno=fds[0])
    if (listener.family != socket.AF_UNIX or listener.type != socket.SOCK_STREAM
            or not listener.getsockopt(socket.SOL_SOCKET, socket.SO_ACCEPTCONN)):
        listener.close()
        raise ValueError("what came on standard input is not a listening Unix socket")
    return listener


def main(argv=None) -> int:
    _prctl_dumpable(0)                   # before anything else: no kernel may ever read or trace this
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m pusht.grader.zygote READY  (standard input: a Unix socket bringing the "
              "listening socket)", file=sys.stderr)
        return 2
    try:
        listener = receive_listener(0)
    except (OSError, ValueError) as e:
        print(f"pusht.grader.zygote: {e}", file=sys.stderr)
        return 2
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    preload()
    serve(listener, argv[0])
    return 0


if __name__ == "__main__":
    sys.exit(main())
