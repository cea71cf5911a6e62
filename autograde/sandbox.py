"""Confine a student's kernel: bubblewrap, a throw-away user id, resource limits, one wall clock.

nbgrader runs every submission in an ordinary Jupyter kernel as the grading user; its FAQ points
to containers for anything stricter. We wire confinement in the same way a container-backed
kernel is wired: through a *kernel spec*. ``write_kernelspec`` writes ``pusht-sandbox``, whose
command is this file; nbgrader (``Execute.kernel_name``) starts it for each notebook with the
notebook's folder as working directory, and this launcher starts ipykernel inside ``bwrap``:

* the filesystem is empty but for, read-only, the system's ``/usr``, the Python installation, the
  venv and the ``pusht`` package, and, writable, the student's own working folder, the folder
  the kernel's Unix sockets live in and the grading folder's ``results/`` (``cases/`` read-only);
  a private ``/tmp``. No other submission, no gradebook, no solutions, no manual grades;
* new network, PID, IPC and UTS namespaces: no network at all (the kernel talks to nbgrader over
  Unix sockets), and when the kernel ends every process it started dies with it, including those
  that left its session with ``setsid``;
* a dedicated unprivileged user id per student (when grading runs as root), no capabilities, no
  new privileges; rlimits on address space, process count, CPU seconds and file size;
* a wall clock per notebook: the launcher kills the sandbox when it runs out.

Why bubblewrap: it is a small, audited, well-kept tool (it is the sandbox under Flatpak), packaged
by Debian (``apt-get install bubblewrap``), needs no daemon, no image and no root-owned service,
and starts in milliseconds; a container per notebook would need a container runtime the CI
machine and most instructors' laptops do not have.

Where bwrap is missing (an instructor's laptop), ``available()`` says why and grading falls back
to an ordinary kernel, with a loud warning that submissions are NOT confined.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

import pusht

KERNEL_NAME = "pusht-sandbox"
SHARED_CACHE_ENV = "PUSHT_SHARED_CACHE"   # the same name as pusht.data.SHARED_CACHE_ENV (tested)
PACKAGE_DIR = Path(pusht.__file__).resolve().parent
DEFAULT_LIMITS = {
    "memory_bytes": 6 * 2 ** 30,      # address space per process (torch reserves a lot of it)
    "processes": 256,                 # per student uid: threads count too
    "cpu_seconds": 900,               # per process
    "file_bytes": 512 * 2 ** 20,      # largest file it may write
    "wall_seconds": 600,              # per notebook, then the sandbox is killed
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


def student_uid(index: int) -> int | None:
    """A throw-away uid per student (root only): rlimits on processes then count that student."""
    return 61000 + (index % 900) if os.geteuid() == 0 else None


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
                  readonly: list[Path] = (), limits: dict | None = None, env: dict | None = None) -> list[str]:
    """The command line (without the program to run) of a sandbox around ``workdir``."""
    limits = {**DEFAULT_LIMITS, **(limits or {})}
    cmd = ["bwrap", "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
           "--unshare-cgroup-try", "--die-with-parent", "--clearenv"]
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
    cmd += ["--proc", "/proc", "--dev", "/dev", "--perms", "1777", "--tmpfs", "/tmp"]
    made.add(Path("/tmp"))
    for p in _ro_paths() + [Path(os.path.realpath(r)) for r in readonly]:
        cmd += _parents(p, made) + ["--ro-bind", str(p), str(p)]
    for p in writable:
        p = Path(os.path.realpath(p))
        cmd += _parents(p, made) + ["--bind", str(p), str(p)]
    if workdir != Path("/"):
        w = Path(os.path.realpath(workdir))
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


PASS_ENV = ("NBGRADER_EXECUTION", "PUSHT_GRADING_DIR", "TQDM_DISABLE", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
            "MKL_CBWR", "OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "PUSHT_SMOKE")


def write_kernelspec(dest: Path, settings: dict) -> Path:
    """Write the ``pusht-sandbox`` kernel spec under ``dest/kernels``; put ``dest`` on JUPYTER_PATH.

    ``settings``: ``socket_dir`` (where the kernel's Unix sockets are made), ``grading_dir``,
    ``uid``, ``limits``, ``shared_cache`` (a folder of stages shared by the batch, bound read-only,
    or None).
    """
    spec_dir = dest / "kernels" / KERNEL_NAME
    spec_dir.mkdir(parents=True, exist_ok=True)
    (spec_dir / "settings.json").write_text(json.dumps(settings))
    (spec_dir / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, str(Path(__file__).resolve()), str(spec_dir / "settings.json"),
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


def launch(settings_file: str, connection_file: str) -> int:
    """Run ipykernel confined; kill the whole sandbox when the wall clock runs out."""
    die_with_parent()
    s = json.loads(Path(settings_file).read_text())
    workdir = Path.cwd()
    grading = Path(s["grading_dir"])
    uid = s.get("uid")
    results = grading / "results"
    results.mkdir(parents=True, exist_ok=True)
    if uid is not None:
        for p in (workdir, results, Path(s["socket_dir"])):
            _chown_tree(p, uid)
    env = {k: os.environ[k] for k in PASS_ENV if k in os.environ}
    env["PUSHT_GRADING_DIR"] = str(grading)
    readonly = [Path(connection_file).resolve(), grading / "cases"]
    if s.get("shared_cache"):
        env[SHARED_CACHE_ENV] = s["shared_cache"]
        readonly.append(Path(s["shared_cache"]))
    conn = Path(connection_file).resolve()
    if uid is not None:
        os.chmod(conn, 0o644)          # the kernel reads its own connection file (key included)
    cmd = bwrap_command(workdir, [Path(s["socket_dir"]), results], uid,
                        readonly=readonly, limits=s.get("limits"), env=env)
    cmd += [sys.executable, "-m", "ipykernel_launcher", "-f", str(conn),
            "--HistoryManager.hist_file=:memory:"]
    proc = subprocess.Popen(cmd)

    def stop(*_):
        proc.kill()
        sys.exit(1)

    signal.signal(signal.SIGTERM, stop)
    try:
        return proc.wait(timeout=float(s.get("limits", {}).get("wall_seconds", DEFAULT_LIMITS["wall_seconds"])))
    except subprocess.TimeoutExpired:
        proc.kill()          # bwrap dies, and with its PID namespace every process inside
        proc.wait()
        print("sandbox: the notebook ran out of its wall-clock limit and was stopped", file=sys.stderr)
        return 137


if __name__ == "__main__":
    sys.exit(launch(sys.argv[1], sys.argv[2]))
