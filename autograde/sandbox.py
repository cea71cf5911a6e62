"""Confine a student's kernel: bubblewrap, a throw-away user id, resource limits, one wall clock.

nbgrader runs every submission in an ordinary Jupyter kernel as the grading user; its FAQ points
to containers for anything stricter. We wire confinement in the same way a container-backed
kernel is wired: through a *kernel spec*. ``write_kernelspec`` writes ``pusht-sandbox``, whose
command is this file; nbgrader (``Execute.kernel_name``) starts it for each notebook with the
notebook's folder as working directory, and this launcher starts ipykernel inside ``bwrap``:

* the filesystem is empty but for, read-only, the system's ``/usr``, the Python installation, the
  venv and the ``pusht`` package, and, writable, a working folder and a ``/tmp`` of its own (each
  an empty tmpfs, size-capped: ``work_bytes``, ``tmp_bytes``; the working folder sits at the path
  of the notebook's folder on the host, which the kernel never sees) and the folder its Unix
  sockets live in, which goes back to root once the grader has connected (``lock_sockets``). No
  other submission, no gradebook, no solutions, no manual grades, nothing nbgrader writes;
* new network, PID, IPC and UTS namespaces: no network at all (the kernel talks to nbgrader over
  Unix sockets), and when the kernel ends every process it started dies with it, including those
  that left its session with ``setsid``;
* a dedicated unprivileged user id per student (when grading runs as root), no capabilities, no
  new privileges; rlimits on address space, process count, CPU seconds and file size;
* a wall clock per notebook: the launcher kills the sandbox when it runs out.

Several grading runs may share a host (two sections at once, a regrade beside a batch, several Dask
workers), so nothing that names a student's processes is fixed per run. A student's uid is leased
for the grading task's lifetime (``allocate_uid``) under a lock file of its own in a root-only folder
that every process on the host uses: no two tasks on one host hold the same uid at once, a task
that dies frees its uids (the kernel drops a dead process's locks), and a uid some process still runs
as is not handed out. A sandbox is killed through its PID namespace (``SandboxInit``): bwrap tells
the host pid of the namespace's init (``--info-fd``), a pidfd holds on to that very process, and
when it dies the kernel kills every process in the namespace, and nothing outside it. Nothing kills
"every process of a uid" on the host, but for a uid its task still holds (``UidLease.sweep``).

One sandbox per student, not per notebook, is what the grader starts (``Zygote``): all of a
student's notebooks run in one folder, so it holds ``pusht.grader.zygote``, a process that has imported
ipykernel, torch and the package once, and ``launch`` has it fork each notebook's kernel (the same
folder, uid and limits; every process the kernel started is killed when it ends). Where no
factory answers, ``launch`` starts a sandbox of its own around the kernel, as described above.

Why bubblewrap: it is a small, audited, well-kept tool (it is the sandbox under Flatpak), packaged
by Debian (``apt-get install bubblewrap``), needs no daemon, no image and no root-owned service,
and starts in milliseconds; a container per notebook would need a container runtime the CI
machine and most instructors' laptops do not have.

Where bwrap is missing (an instructor's laptop), ``available()`` says why and grading falls back
to an ordinary kernel, with a loud warning that submissions are NOT confined.
"""

from __future__ import annotations

import fcntl
import json
import os
import select
import shutil
import signal
import socket
import stat
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

import pusht
from pusht.reference import GRADING_ENV
from pusht.stage_cache import SHARED_CACHE_ENV

KERNEL_NAME = "pusht-sandbox"
PACKAGE_DIR = Path(pusht.__file__).resolve().parent
DEFAULT_LIMITS = {
    "memory_bytes": 6 * 2 ** 30,      # address space per process (torch reserves a lot of it)
    "processes": 256,                 # per student uid: threads count too
    "cpu_seconds": 900,               # per process
    "file_bytes": 512 * 2 ** 20,      # largest file it may write
    "wall_seconds": 600,              # per notebook, then the sandbox is killed
    "work_bytes": 1 << 30,            # the kernel's working folder: a tmpfs of this size, in RAM
    "tmp_bytes": 256 << 20,           # its /tmp: the same
    "sandbox_bytes": 4 << 30,         # all of one sandbox's memory, its tmpfs pages included (memory cgroup)
}


@lru_cache(maxsize=1)
def available() -> tuple[bool, str]:
    """(True, "") where a confined kernel can start here, else (False, why not)."""
    if not sys.platform.startswith("linux"):
        return False, "bubblewrap needs Linux"
    if not shutil.which("bwrap"):
        return False, "bubblewrap is not installed (Debian/Ubuntu: sudo apt-get install bubblewrap)"
    cmd = bwrap_command(Path("/"), [], uid=_probe_uid()) + ["true"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired) as e:
        return False, f"bwrap could not start ({e})"
    if proc.returncode != 0:
        return False, f"bwrap refused to start a sandbox here: {proc.stderr.strip()[:300]}"
    return True, ""


def _probe_uid():
    return 61999 if os.geteuid() == 0 else None


# --- a throw-away uid per student, leased machine-wide ---------------------------------------------
STUDENT_UIDS = range(61000, 61900)     # students' uids on this host (61999 is available()'s probe)
# where the per-uid lock files live: the first of these whose base is writable; every process on the
# host makes the same choice, so all of them lock the same files
UID_LOCK_DIRS = (("/run", "pusht-grading/uids"), ("/var/lock", "pusht-grading/uids"), ("/tmp", "pusht-grading-uids"))


class UidLease:
    """A student uid that this process alone holds on this host, until ``close`` or its death.

    The hold is an ``flock`` on the uid's lock file (``allocate_uid``); the kernel drops it when
    the file is closed or its holder dies, however it dies. The descriptor is close-on-exec and is
    never passed on, so no worker or sandbox holds it. ``uid`` is None where grading does not run
    as root (nothing switches uids then)."""

    def __init__(self, uid: int | None = None, fd: int | None = None, path: Path | None = None):
        self.uid, self.fd, self.path = uid, fd, path

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __del__(self) -> None:      # a lease dropped unclosed frees its uid with it, not at exit
        try:
            self.close()
        except OSError:
            pass

    def __enter__(self) -> "UidLease":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"UidLease(uid={self.uid}, {'held' if self.fd is not None else 'released'})"

    def sweep(self) -> int:
        """SIGKILL whatever still runs as this uid; returns how many processes that was.

        Normally nothing does: every sandbox dies with its PID namespace. This is the last resort
        for one that escaped that (a worker killed while its sandbox was still being set up), and
        it is allowed only because the lease is held: no other grading run on this host uses the
        uid meanwhile. Each process is killed through a pidfd, checked to run as the uid after it
        was opened, so a pid reused in between is never hit."""
        if self.uid is None or self.fd is None:
            return 0
        killed = 0
        for _ in range(50):
            found = 0
            for pid in _pids_running_as(self.uid):
                try:
                    pidfd = os.pidfd_open(pid)
                except OSError:
                    continue
                try:
                    if self.uid in _uids_of(pid):          # read after the pidfd was opened (see above)
                        signal.pidfd_send_signal(pidfd, signal.SIGKILL)
                        found += 1
                except OSError:
                    pass
                finally:
                    os.close(pidfd)
            if not found:
                return killed
            killed += found
            time.sleep(0.01)
        return killed


def _uids_of(pid: int) -> tuple[int, ...]:
    """(real, effective, saved, filesystem) uid of a live process, from /proc (a zombie: ())."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return ()
    if "\nState:\tZ" in status:
        return ()
    for line in status.splitlines():
        if line.startswith("Uid:"):
            return tuple(int(x) for x in line.split()[1:])
    return ()


def _live_uids() -> set[int]:
    """Every uid some live process on this host runs as (any of its four), from /proc."""
    uids: set[int] = set()
    for pid in filter(str.isdigit, os.listdir("/proc")):
        uids.update(_uids_of(int(pid)))
    return uids


def _pids_running_as(uid: int) -> list[int]:
    return [int(p) for p in filter(str.isdigit, os.listdir("/proc")) if uid in _uids_of(int(p))]


def _private_dir(path: Path) -> None:
    """Refuse ``path`` as a lock folder unless it is a real directory of root's that no one else can
    write (anyone who could would plant or take locks); make it root's alone (0700)."""
    st = os.lstat(path)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != 0 or st.st_mode & 0o022:
        raise RuntimeError(
            f"refusing {path} as the folder of the grading uid locks: it must be a directory owned by root "
            f"that no one else can write (it is {'a directory' if stat.S_ISDIR(st.st_mode) else 'not a directory'}, "
            f"owner uid {st.st_uid}, mode {stat.S_IMODE(st.st_mode):o}); remove it and grade again")
    if stat.S_IMODE(st.st_mode) != 0o700:
        os.chmod(path, 0o700)


def uid_lock_dir() -> Path:
    """The folder of the uid lock files, created if need be: the same for every process on the host
    (the first of ``UID_LOCK_DIRS`` that can be made), root's alone. Root only."""
    tried = []
    for base, rel in UID_LOCK_DIRS:
        path = Path(base)
        try:
            for part in Path(rel).parts:
                path = path / part
                try:
                    os.mkdir(path, 0o700)
                except FileExistsError:
                    pass
                _private_dir(path)
            return path
        except OSError as e:           # a base this host does not let us write (RuntimeError is a refusal)
            tried.append(f"{path}: {e.strerror or e}")
    raise RuntimeError("no folder for the grading uid locks could be made: " + "; ".join(tried))


_RECORDERS: list[list[int]] = []         # the lists of recording_leases, while they record
_RECORDERS_LOCK = threading.Lock()


@contextmanager
def recording_leases():
    """``with recording_leases() as leased: grade_class(...)``: ``leased`` lists the uid of every
    lease ``allocate_uid`` hands out in this process meanwhile (a local run's tasks are threads of
    it, the instructor's reference run included; a Dask worker's leases are its own). A check of a
    run's leftovers looks at these uids alone: another grading run on the host runs as others, or
    as these once this run has given them back (tests/conftest.py, ``leftovers_of``)."""
    leased: list[int] = []
    with _RECORDERS_LOCK:
        _RECORDERS.append(leased)
    try:
        yield leased
    finally:
        with _RECORDERS_LOCK:
            _RECORDERS.remove(leased)


def allocate_uid() -> UidLease:
    """Lease a student uid no other grading task on this host holds (root only; else a lease of no
    uid). The first uid of ``STUDENT_UIDS`` whose lock file this process can lock, and that no live
    process runs as (a crashed run's leftover), is held until the lease is closed. Raises
    RuntimeError when every one is taken."""
    if os.geteuid() != 0:
        return UidLease()
    folder = uid_lock_dir()
    live = None
    for uid in STUDENT_UIDS:
        path = folder / f"{uid}.lock"
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:            # another grading task on this host holds it
            os.close(fd)
            continue
        if live is None:      # once: a new process of an unheld uid can only be a leftover's child
            live = _live_uids()
        if uid in live:                    # a leftover of a run that died still runs as it
            os.close(fd)
            continue
        try:                               # who holds it, for whoever looks
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:
            pass
        with _RECORDERS_LOCK:
            for leased in _RECORDERS:
                leased.append(uid)
        return UidLease(uid, fd, path)
    raise RuntimeError(
        f"all {len(STUDENT_UIDS)} student uids ({STUDENT_UIDS.start}-{STUDENT_UIDS.stop - 1}) are taken on this "
        f"host: grading tasks hold them (each holder's pid is in its file in {folder}), or processes still run "
        f"as them (ps -eo uid,pid,args | awk '$1>={STUDENT_UIDS.start} && $1<{STUDENT_UIDS.stop}'). "
        f"Wait for the other grading runs, or grade with fewer jobs at once")


def _ro_paths() -> list[Path]:
    """What every kernel needs read-only: the system, the interpreter, the venv, the package."""
    paths = [Path("/usr"), Path(sys.base_prefix), Path(sys.prefix), PACKAGE_DIR]
    for etc in ("/etc/ld.so.cache", "/etc/localtime", "/etc/alternatives", "/etc/fonts"):
        if os.path.exists(etc):
            paths.append(Path(etc))
    out = []
    for p in paths:
        p = Path(os.path.realpath(p))
        if not any(p == q or q in p.parents for q in out):
            out = [q for q in out if p not in q.parents] + [p]
    return out


def _parents(path: Path, made: set) -> list[str]:
    """``--dir`` arguments (mode 0755) for every missing parent of ``path`` inside the sandbox."""
    args = []
    for parent in reversed(path.parents):
        if str(parent) != "/" and parent not in made:
            made.add(parent)
            args += ["--perms", "0755", "--dir", str(parent)]
    return args


def bwrap_command(workdir: Path, writable: list[Path], uid: int | None,
                  readonly: list[Path] = (), limits: dict | None = None, env: dict | None = None,
                  info_fd: int | None = None, package: Path | None = None, scratch: bool = False) -> list[str]:
    """The command line (without the program to run) of a sandbox around ``workdir``. ``info_fd``:
    a descriptor bwrap writes the host pid of the sandbox's init to (see ``start_sandbox``).
    ``package``: a folder bound read-only where the ``pusht`` package is, in its place (the probe
    process's stripped copy, ``stripped.py``); the real package is then not bound at all.
    ``scratch``: ``workdir`` is not bound but replaced, inside the sandbox, by an empty tmpfs of
    ``limits["work_bytes"]`` at the same path: the kernel works there, and nothing it writes
    reaches the host's folder (nbgrader's, which the grader writes as root)."""
    limits = {**DEFAULT_LIMITS, **(limits or {})}
    cmd = ["bwrap", "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
           "--unshare-cgroup-try", "--die-with-parent", "--clearenv"]
    if info_fd is not None:
        cmd += ["--info-fd", str(info_fd)]
    if os.geteuid() != 0:
        cmd.append("--unshare-user")
    made: set = set()
    for link in ("bin", "lib", "lib64", "sbin"):
        target = Path("/", link)
        if target.is_symlink():
            cmd += ["--symlink", os.readlink(target), str(target)]
        elif target.exists():
            cmd += ["--ro-bind", str(target), str(target)]
    # the private /tmp first: a course, venv or package that lives under /tmp is bound on top of it
    cmd += ["--proc", "/proc", "--dev", "/dev", "--perms", "1777", "--size", str(int(limits["tmp_bytes"])),
            "--tmpfs", "/tmp"]
    made.add(Path("/tmp"))
    system = _ro_paths()
    if package is not None:
        system = [p for p in system if p != PACKAGE_DIR]
    for p in system + [Path(os.path.realpath(r)) for r in readonly]:
        cmd += _parents(p, made) + ["--ro-bind", str(p), str(p)]
    if package is not None:        # after the venv: a package installed inside it is covered too
        cmd += _parents(PACKAGE_DIR, made) + ["--ro-bind", str(Path(package).resolve()), str(PACKAGE_DIR)]
    for p in writable:
        p = Path(os.path.realpath(p))
        cmd += _parents(p, made) + ["--bind", str(p), str(p)]
    if workdir != Path("/"):
        w = Path(os.path.realpath(workdir))
        if scratch:
            cmd += _parents(w, made) + ["--perms", "1777", "--size", str(int(limits["work_bytes"])),
                                        "--tmpfs", str(w), "--chdir", str(w)]
        else:
            cmd += _parents(w, made) + ["--bind", str(w), str(w), "--chdir", str(w)]
    base_env = {"PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin", "HOME": "/tmp", "USER": "student",
                "LOGNAME": "student", "LANG": "C.UTF-8", "TMPDIR": "/tmp", "PYTHONNOUSERSITE": "1",
                "MPLCONFIGDIR": "/tmp/matplotlib", "IPYTHONDIR": "/tmp/ipython", "PYTHONDONTWRITEBYTECODE": "1"}
    for key, value in {**base_env, **(env or {})}.items():
        cmd += ["--setenv", key, str(value)]
    cmd += ["prlimit", f"--as={limits['memory_bytes']}", f"--cpu={limits['cpu_seconds']}",
            f"--fsize={limits['file_bytes']}", f"--nproc={limits['processes']}", "--core=0", "--"]
    if uid is not None:
        cmd += ["setpriv", f"--reuid={uid}", f"--regid={uid}", "--clear-groups", "--no-new-privs",
                "--inh-caps=-all", "--bounding-set=-all", "--"]
    return cmd


PASS_ENV = (GRADING_ENV, "TQDM_DISABLE", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
            "MKL_CBWR", "OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "PUSHT_SMOKE")


def write_kernelspec(dest: Path, settings: dict) -> Path:
    """Write the ``pusht-sandbox`` kernel spec under ``dest/kernels``; put ``dest`` on JUPYTER_PATH.

    ``settings``: ``socket_dir`` (where the kernel's Unix sockets are made), ``uid``, ``limits``, ``shared_cache`` (a folder of stages shared by the batch, bound read-only,
    or None).
    """
    spec_dir = dest / "kernels" / KERNEL_NAME
    spec_dir.mkdir(parents=True, exist_ok=True)
    (spec_dir / "settings.json").write_text(json.dumps(settings))
    (spec_dir / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "autograde.sandbox", str(spec_dir / "settings.json"),
                 "{connection_file}"],
        "display_name": "Python 3 (pusht sandbox)", "language": "python", "interrupt_mode": "message",
        "metadata": {"debugger": False}}))
    return spec_dir


def _chown_tree(path: Path, uid: int) -> None:
    for root, dirs, files in os.walk(path):
        for name in [root] + [os.path.join(root, n) for n in dirs + files]:
            try:
                os.lchown(name, uid, uid)
            except OSError:
                pass


def die_with_parent() -> None:
    """Have the kernel deliver SIGKILL to this process when its parent dies (Linux's
    PR_SET_PDEATHSIG), so a grading process whose coordinator was killed (a Dask worker lost mid-
    task, say) does not run on, orphaned. Elsewhere it does nothing."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    parent = os.getppid()
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)   # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:       # the parent died before the request was made
        os.kill(os.getpid(), signal.SIGKILL)


def _confinement(s: dict, workdir: Path, readonly: list[Path], info_fd: int | None = None) -> list[str]:
    """The bwrap command (without the program) of a kernel's sandbox under settings ``s``: the
    student's ``workdir`` a size-capped tmpfs of its own (``scratch``; bound from the host only for
    the instructor's own run, ``s["keep_workdir"]``, whose stages the batch shares), the socket
    folder writable; ``readonly`` and the shared stages read-only. Hands the folders the kernel
    writes on the host to the student's uid first (root only)."""
    uid = s.get("uid")
    _hand_over(s, workdir)
    env = {k: os.environ[k] for k in PASS_ENV if k in os.environ}
    readonly = list(readonly)
    if s.get("shared_cache"):
        env[SHARED_CACHE_ENV] = s["shared_cache"]
        readonly.append(Path(s["shared_cache"]))
    return bwrap_command(workdir, [Path(s["socket_dir"])], uid, readonly=readonly, limits=s.get("limits"),
                         env=env, info_fd=info_fd, scratch=not s.get("keep_workdir"))


def _hand_over(s: dict, workdir: Path) -> None:
    """Make the host folders a kernel writes (the sockets; the working folder of the instructor's
    run) belong to the student's uid (root only), emptied of what an earlier kernel left."""
    sockets = Path(s["socket_dir"])
    unlock_sockets(sockets, s.get("uid"))
    if s.get("uid") is not None and s.get("keep_workdir"):
        _chown_tree(workdir, s["uid"])


def unlock_sockets(folder: Path, uid: int | None) -> None:
    """Let the next kernel make its sockets in ``folder``: empty it of everything but the kernel
    factory's socket (nothing is followed), then hand it to ``uid`` (root only)."""
    folder.mkdir(parents=True, exist_ok=True)
    for p in folder.iterdir():
        if p.name != "zygote":
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                p.unlink(missing_ok=True)
    if uid is not None:
        os.lchown(folder, uid, uid)
        os.chmod(folder, 0o755)


def lock_sockets(folder: Path) -> None:
    """Once a kernel has made its sockets and the grader has connected to them, before any of the
    student's code runs (nbclient's ``on_notebook_start``): ``folder`` back to root, read-only to
    the kernel, so that it cannot put a link where the grader's ZeroMQ reconnects (it would follow
    it, as root). Where grading does not run as root nothing changes hands
    (docs/grader.md, "Student code is treated as hostile")."""
    if os.geteuid() == 0:
        os.lchown(folder, 0, 0)
        os.chmod(folder, 0o755)


def _wall(s: dict) -> float:
    return float(s.get("limits", {}).get("wall_seconds", DEFAULT_LIMITS["wall_seconds"]))


# --- killing a sandbox: its PID namespace, and nothing else ------------------------------------------
class SandboxInit:
    """The init (pid 1) of one sandbox's PID namespace, held as a pidfd.

    Killing it kills the whole sandbox and nothing outside it: when a namespace's init dies, the
    kernel kills every process in that namespace (ones that left their session or process group,
    and those of nested namespaces, included) and reaps them before the init's own exit is seen.
    A pidfd names one process, never a later one given the same pid."""

    def __init__(self, fd: int, pid: int, pidns: int | None, started: int):
        self.fd, self.pid, self.pidns, self.started = fd, pid, pidns, started

    @classmethod
    def open(cls, pid, pidns=None, parent: int | None = None, started: int | None = None) -> "SandboxInit | None":
        """The init whose host pid is ``pid``, checked to be the init of the PID namespace ``pidns``
        (its inode number, as bwrap reports it), with ``parent`` a child of that process (the bwrap
        that started it), with ``started`` started then (clock ticks since boot, as ``started``
        records it); None if that process is gone (and with it its namespace) or ``pid`` is now
        another process."""
        if not isinstance(pid, int) or pid <= 0 or (pidns is None and parent is None):
            return None
        try:
            fd = os.pidfd_open(pid)
        except OSError:
            return None
        try:
            status = Path(f"/proc/{pid}/status").read_text()
            fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
            began = int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19])
            ok = fields.get("NSpid", "").split()[-1:] == ["1"]            # the init of its own namespace
            if pidns is not None:
                ok = ok and os.readlink(f"/proc/{pid}/ns/pid") == f"pid:[{pidns}]"
            if parent is not None:
                ok = ok and int(fields.get("PPid", "0")) == parent
            if started is not None:
                ok = ok and began == started
            # still alive after those reads: the pid was not reused meanwhile, they were about this process
            signal.pidfd_send_signal(fd, 0)
        except (OSError, ValueError, IndexError):
            ok = False
        if not ok:
            os.close(fd)
            return None
        return cls(fd, pid, pidns, began)

    def kill(self, wait: float = 10.0) -> None:
        """SIGKILL the init, and so its namespace; return once it is gone (``wait`` seconds at most)."""
        if self.fd is None:
            return
        try:
            signal.pidfd_send_signal(self.fd, signal.SIGKILL)
        except ProcessLookupError:
            pass
        # a pidfd reads as ready once its process has exited; a namespace's init exits only after
        # every other process of the namespace is dead and reaped
        _wait_readable(self.fd, wait)
        self.close()

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def _wait_readable(fd: int, timeout: float) -> bool:
    poller = select.poll()          # not select.select: it cannot take a descriptor above 1023
    poller.register(fd, select.POLLIN)
    return bool(poller.poll(max(timeout, 0) * 1000))


def _read_info(fd: int, timeout: float = 30.0) -> dict:
    """What bwrap wrote on its ``--info-fd`` (it closes it right after cloning the sandbox's init,
    before the init may go on), or {} if it ended first; closes ``fd``."""
    data, deadline = b"", time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            if not _wait_readable(fd, deadline - time.monotonic()):
                break
            chunk = os.read(fd, 4096)
            if not chunk:
                break
            data += chunk
    finally:
        os.close(fd)
    try:
        info = json.loads(data)
    except ValueError:
        return {}
    return info if isinstance(info, dict) else {}


def start_sandbox(build, program: list[str], memory: int | None = None,
                  **popen) -> tuple[subprocess.Popen, SandboxInit | None]:
    """Start ``build(info_fd) + program`` (``build`` makes a bwrap command line around the given
    ``--info-fd``) and learn its sandbox's init: (the bwrap process, its ``SandboxInit``, or None if
    bwrap ended before it made a sandbox). Takes milliseconds: bwrap reports the init as soon as it
    has cloned it, and holds it until then, so the init is known even if the sandbox is killed while
    it is still being set up.

    ``memory``: bytes that the whole sandbox may use, every process and its tmpfs pages together,
    where the host lets this process make a memory cgroup (``MemoryCgroup``): bwrap starts inside
    it, so nothing of the sandbox is ever outside. ``end_sandbox`` removes it."""
    group = MemoryCgroup.make(memory) if memory else None
    r, w = os.pipe()
    try:
        args = build(w) + program
        if group is not None:        # join the group, then become bwrap: its every child is born inside
            args = ["/bin/sh", "-c", 'echo $$ > "$0" && exec "$@"', str(group.procs)] + args
        proc = subprocess.Popen(args, pass_fds=(w,), **popen)
    except BaseException:
        os.close(r)
        if group is not None:
            group.remove()
        raise
    finally:
        os.close(w)
    proc.pusht_cgroup = group
    info = _read_info(r)
    return proc, SandboxInit.open(info.get("child-pid"), info.get("pid-namespace"), parent=proc.pid)


def sandbox_bytes(limits: dict | None) -> int:
    """The memory cap of a whole sandbox under ``limits`` (``DEFAULT_LIMITS`` where it says none)."""
    return int({**DEFAULT_LIMITS, **(limits or {})}["sandbox_bytes"])


class MemoryCgroup:
    """A memory cgroup of one sandbox (cgroup v1's memory controller, or v2 where ``memory`` is
    delegated), under ``<hierarchy>/<this process's group>/pusht-grading/``, limited to its bytes.

    RLIMIT_AS caps one process's address space, not a sandbox's: 256 processes of 6 GiB each, or a
    tmpfs filled to its size, are not bounded by it. The kernel charges every page a process in the
    group touches, tmpfs pages included, to the group, and kills a process in it, never outside, once
    the group is over its limit. Where no group can be made (not root, no writable hierarchy),
    ``make`` returns None and the sandbox runs with the per-process limits only
    (docs/grader.md, "Student code is treated as hostile")."""

    FOLDER = "pusht-grading"

    def __init__(self, path: Path, kind: str):
        self.path, self.kind = path, kind
        self.procs = path / "cgroup.procs"

    @classmethod
    def make(cls, limit: int) -> "MemoryCgroup | None":
        found = _memory_hierarchy()
        if found is None:
            return None
        parent, kind = found
        path = parent / f"s{os.getpid()}-{time.monotonic_ns()}"
        try:
            path.mkdir()
            if kind == "v1":
                (path / "memory.limit_in_bytes").write_text(str(int(limit)))
                try:                                   # no swap beyond the limit either, where there is swap
                    (path / "memory.memsw.limit_in_bytes").write_text(str(int(limit)))
                except OSError:
                    pass
            else:
                (path / "memory.max").write_text(str(int(limit)))
                try:
                    (path / "memory.swap.max").write_text("0")
                except OSError:
                    pass
        except OSError:
            try:
                path.rmdir()
            except OSError:
                pass
            return None
        return cls(path, kind)

    def remove(self, wait: float = 5.0) -> None:
        """Remove the group once its processes are gone (they were killed with the sandbox)."""
        deadline = time.monotonic() + wait
        while True:
            try:
                self.path.rmdir()
                return
            except FileNotFoundError:
                return
            except OSError:
                if time.monotonic() > deadline:
                    return
                time.sleep(0.02)


@lru_cache(maxsize=1)
def _memory_hierarchy() -> tuple[Path, str] | None:
    """(the folder sandboxes' memory cgroups are made in, "v1" or "v2"), or None where there is none."""
    if not sys.platform.startswith("linux") or os.geteuid() != 0:
        return None
    try:
        mounts = Path("/proc/self/mountinfo").read_text().splitlines()
        own = dict(line.split(":", 2)[1:] for line in Path("/proc/self/cgroup").read_text().splitlines()
                   if line.count(":") >= 2)
    except OSError:
        return None
    found = []
    for line in mounts:
        pre, _, post = line.partition(" - ")
        fields, rest = pre.split(), post.split()
        if len(fields) < 5 or len(rest) < 3:
            continue
        root, mount, fstype, opts = fields[3], Path(fields[4]), rest[0], rest[2].split(",")
        if fstype == "cgroup" and "memory" in opts:
            found.append((mount, root, own.get("memory", "/"), "v1"))
        elif fstype == "cgroup2":
            found.append((mount, root, own.get("", "/"), "v2"))
    for mount, root, mine, kind in found:
        rel = mine[len(root):] if mine.startswith(root) else ""
        for parent in (mount / rel.lstrip("/"), mount):
            try:
                if kind == "v2" and "memory" not in (parent / "cgroup.subtree_control").read_text().split():
                    continue
                folder = parent / MemoryCgroup.FOLDER
                folder.mkdir(exist_ok=True)
                if kind == "v2":
                    (folder / "cgroup.subtree_control").write_text("+memory")
                trial = folder / f"probe-{os.getpid()}"
                trial.mkdir(exist_ok=True)
                trial.rmdir()
                return folder, kind
            except OSError:
                continue
    return None


def end_sandbox(proc: subprocess.Popen, init: SandboxInit | None) -> None:
    """Kill the sandbox ``start_sandbox`` started, everything in it and nothing else, and return once
    it is all gone: its init first (and so its namespace), then bwrap, which reaps the init and ends
    on its own (killed first, it would leave the init a zombie for the host's init to reap)."""
    try:
        if init is not None:
            init.kill()
            try:
                proc.wait(timeout=5)
                return
            except subprocess.TimeoutExpired:
                pass
        proc.kill()
        proc.wait()
    finally:
        group = getattr(proc, "pusht_cgroup", None)
        if group is not None:
            group.remove()


def launch(settings_file: str, connection_file: str) -> int:
    """Run ipykernel confined; kill the whole sandbox when the wall clock runs out.

    Where the grading worker keeps a kernel factory for this student (``Zygote``), the kernel is
    forked from it, inside its sandbox; otherwise (or where the factory cannot be reached) this
    starts a sandbox of its own."""
    die_with_parent()
    s = json.loads(Path(settings_file).read_text())
    workdir = Path.cwd()
    conn = Path(connection_file).resolve()
    if s.get("uid") is not None:
        os.chmod(conn, 0o644)          # the kernel reads its own connection file (key included)
    if s.get("zygote_state"):
        code = _launch_via_zygote(s, conn, workdir)
        if code is not None:
            return code
    proc, init = start_sandbox(lambda fd: _confinement(s, workdir, [conn], info_fd=fd),
                               [sys.executable, "-m", "ipykernel_launcher", "-f", str(conn),
                                "--HistoryManager.hist_file=:memory:"], memory=sandbox_bytes(s.get("limits")))

    def kill():
        end_sandbox(proc, init)     # its PID namespace: every process inside, nothing outside

    def stop(*_):
        kill()
        sys.exit(1)

    signal.signal(signal.SIGTERM, stop)
    try:
        return proc.wait(timeout=_wall(s))
    except subprocess.TimeoutExpired:
        kill()
        print(WALL_MESSAGE, file=sys.stderr)
        return 137


WALL_MESSAGE = "sandbox: the notebook ran out of its wall-clock limit and was stopped"
ZYGOTE_WAIT_S = 120        # how long a kernel waits for its factory to listen (it imports torch first)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _first_reply(sock: socket.socket, replies, state: dict) -> bytes:
    """The factory's first line on ``sock`` ("pid N"), b"" if none came: it answers once it has
    imported everything (``ZYGOTE_WAIT_S`` at most) and while its sandbox lives."""
    deadline = time.monotonic() + ZYGOTE_WAIT_S
    while not _wait_readable(sock.fileno(), 0.2):
        if time.monotonic() > deadline or not _alive(state["pid"]):
            return b""
    sock.settimeout(30)
    return replies.readline()


def _launch_via_zygote(s: dict, conn: Path, workdir: Path) -> int | None:
    """Have this student's kernel factory fork the kernel; wait for it under the wall clock.
    Returns its exit code, or None where no factory could take the request (nothing started).

    The factory's socket is in a folder that no sandbox sees (``Zygote``): what answers there is
    the factory, not a kernel in its place, and the factory serves only a requester from outside
    its sandbox, so nothing in the request is a secret."""
    try:
        state = json.loads(Path(s["zygote_state"]).read_text())
    except (OSError, ValueError):
        return None
    if Path(state["workdir"]) != Path(os.path.realpath(workdir)) or not _alive(state["pid"]):
        return None                    # not the folder the factory's sandbox holds
    _hand_over(s, workdir)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        # at once, even while the factory still imports: the grader made the socket listening
        # before it started the factory, which accepts once it is ready (``_first_reply`` waits)
        sock.connect(state["socket"])
    except OSError:
        sock.close()
        return None
    # the factory's sandbox sees a folder of connection files (jupyter keeps its own runtime folder
    # private, 0700): a copy of this kernel's goes there, readable by the student's uid
    visible = Path(s["connections_dir"]) / conn.name
    shutil.copyfile(conn, visible)
    os.chmod(visible, 0o644)
    request = {"connection_file": str(visible), "cwd": str(workdir)}
    with sock, sock.makefile("rb") as replies:
        try:
            socket.send_fds(sock, [json.dumps(request).encode()], [0, 1, 2])
            first = _first_reply(sock, replies, state)
        except OSError:
            first = b""
        if not first.startswith(b"pid "):
            return None                # refused before forking anything (or no factory answered)
        sock.settimeout(max(_wall(s), 0.01))     # the notebook's wall clock, from its fork on
        try:
            last = replies.readline()
        except (socket.timeout, TimeoutError):
            _kill_factory(state)
            print(WALL_MESSAGE, file=sys.stderr)
            return 137
        except OSError:
            last = b""
    if last.startswith(b"exit "):
        code = int(last.split()[1])
        return code if code >= 0 else 128 - code
    print("sandbox: the kernel factory stopped while the notebook ran", file=sys.stderr)
    return 1


def _kill_factory(state: dict) -> None:
    """Kill the factory's sandbox, everything in it and nothing else: its PID namespace's init, as the
    state file names it (pid, namespace and start, checked before it is hit). If that init is gone, so is the
    sandbox. Only a state file without one (bwrap reported none) falls back to the bwrap process."""
    if state.get("init") is not None:
        init = SandboxInit.open(state["init"], state.get("pidns"), started=state.get("init_started"))
        if init is not None:
            init.kill()
        return
    try:
        os.kill(state["pid"], signal.SIGKILL)    # --die-with-parent: its sandbox follows it
    except ProcessLookupError:
        pass


ZYGOTE_SOCKET = "zygote.sock"
BIND_OPTIONS = ("--bind", "--bind-try", "--ro-bind", "--ro-bind-try", "--dev-bind", "--dev-bind-try")


def _private_folder(near: Path) -> Path:
    """A new folder only this process's uid may enter (0700), for the factory's socket: in ``near``
    (the state file's folder), or in the system's temporary folder where a socket path in ``near``
    would be too long for a Unix socket (107 bytes)."""
    import tempfile

    for base in (near, None):
        folder = Path(tempfile.mkdtemp(prefix="zygote-", dir=base))
        if len(os.fsencode(folder / ZYGOTE_SOCKET)) < 100:
            return folder
        os.rmdir(folder)
    raise RuntimeError("no folder for the kernel factory's socket has a path short enough")


def _remove(path: Path) -> None:
    """Remove ``path``, whatever it is (a link is not followed), if it is there."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def _check_unbound(cmd: list[str], folder: Path) -> list[str]:
    """``cmd`` (a bwrap command line) if it binds neither ``folder`` nor a folder above it into the
    sandbox; raises otherwise: a kernel could then reach the factory's socket."""
    real = Path(os.path.realpath(folder))
    for option, source in zip(cmd, cmd[1:]):
        if option in BIND_OPTIONS:
            src = Path(os.path.realpath(source))
            if src == real or src in real.parents:
                raise RuntimeError(f"the kernel factory's socket folder {real} would be visible in its "
                                   f"sandbox ({option} {source}): put the state file elsewhere")
    return cmd


class Zygote:
    """One student's kernel factory (``pusht.grader.zygote``) in a sandbox like a kernel's, around the
    folder all of that student's notebooks run in. ``launch`` forks each notebook's kernel from
    it, which skips starting Python, ipykernel and importing torch for every notebook.

    ``settings`` as for ``write_kernelspec``, with ``zygote_state`` (a file outside every sandbox
    where the factory's pid, sandbox and socket are written for ``launch``) and ``connections_dir``
    (where ``launch`` puts a copy of each kernel's connection file: bound read-only).

    Only the grader can have the factory fork, and no secret says so (a forked kernel is a copy of
    the factory's memory, so any secret there is the student's too; see ``pusht.grader.zygote``): the
    listening socket is made here, at a path in a new 0700 folder next to the state file that the
    sandbox does not bind (checked on its command line), and handed to the factory as a descriptor,
    sent over a socket pair that is its standard input, so that bwrap's own processes never hold it.
    The factory serves only peers outside its sandbox's PID namespace, closes the socket in every
    kernel it forks, and is not dumpable. The factory's ``READY`` file, ``socket_dir/zygote``, says
    it has imported everything and listens (``ensure`` waits for it)."""

    def __init__(self, settings: dict, workdir: Path):
        self.s = settings
        self.workdir = Path(os.path.realpath(workdir))
        self.state_file = Path(settings["zygote_state"])
        self.proc: subprocess.Popen | None = None
        self.init: SandboxInit | None = None
        self._ready, self._waited, self._folder = None, True, None

    def start(self) -> None:
        """Start the factory, or start it again if it is gone (a notebook ran out of time), without
        waiting for it: it imports torch, ipykernel and the package (about 2 s) while the caller
        goes on (the worker imports nbgrader meanwhile). ``ensure`` waits for it."""
        if self.proc is not None and self.proc.poll() is None:
            return
        self.stop()
        ready = Path(self.s["socket_dir"]) / "zygote"
        _remove(ready)            # a kernel of the last sandbox may have left anything there
        conns = Path(self.s["connections_dir"])
        conns.mkdir(mode=0o755, parents=True, exist_ok=True)
        self._folder = _private_folder(self.state_file.parent)
        path = self._folder / ZYGOTE_SOCKET
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            listener.bind(str(path))
            listener.listen(16)
            # -P: the folder it starts in (the student's) is not put on sys.path for its own imports
            self.proc, self.init = start_sandbox(
                lambda fd: _check_unbound(_confinement(self.s, self.workdir, [conns], info_fd=fd), self._folder),
                [sys.executable, "-P", "-m", "pusht.grader.zygote", str(ready)], memory=sandbox_bytes(self.s.get("limits")),
                stdin=theirs.fileno(), stdout=subprocess.DEVNULL)
            theirs.close()
            try:
                socket.send_fds(ours, [b"listen"], [listener.fileno()])
            except OSError:      # it ended at once; ensure() notices, stop() cleans up
                pass
        except BaseException:
            shutil.rmtree(self._folder, ignore_errors=True)
            self._folder = None
            raise
        finally:
            for sock in (listener, ours, theirs):
                sock.close()
        self._ready, self._waited = ready, False
        tmp = self.state_file.with_suffix(".tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w") as f:
            json.dump({"pid": self.proc.pid, "socket": str(path), "workdir": str(self.workdir),
                       "init": self.init and self.init.pid, "pidns": self.init and self.init.pidns,
                       "init_started": self.init and self.init.started}, f)
        os.replace(tmp, self.state_file)

    def _wait_listening(self) -> None:
        # the factory serves once it has imported everything (its READY file appears)
        if self.proc is None or self._waited:
            return
        deadline = time.monotonic() + ZYGOTE_WAIT_S
        while not self._ready.exists() and self.proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        self._waited = True

    def ensure(self) -> None:
        """Start the factory if it is not running (``start``), and return once it listens."""
        self.start()
        self._wait_listening()

    def stop(self) -> None:
        """Kill the factory's sandbox, with every process in it and no other: its PID namespace's
        init (``SandboxInit``), known from the moment bwrap made it, so a sandbox still being set
        up dies whole too. Returns once everything in it is gone, and its socket with it."""
        self.state_file.unlink(missing_ok=True)
        if self.proc is not None:
            end_sandbox(self.proc, self.init)
        self.proc, self.init = None, None
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)
            self._folder = None
        if self._ready is not None:
            _remove(self._ready)


if __name__ == "__main__":
    sys.exit(launch(sys.argv[1], sys.argv[2]))
