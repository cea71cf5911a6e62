"""The grader's kernel factory: one sandbox per student, a fresh forked kernel per notebook.

``sandbox.Zygote`` starts ``pusht.grader.zygote`` once in a student's sandbox; every kernel nbgrader asks
for is then forked from it by ``sandbox.launch`` (the kernel spec's command). These tests drive it
the way nbgrader does, with jupyter_client and the real bubblewrap sandbox, and check what must
stay true of a kernel of its own: nothing one notebook started lives into the next, the wall clock
still stops a notebook, kernels are not clones of each other, and the factory serves only its
grader: a kernel, which starts as a copy of the factory's memory and controls everything in its
sandbox, finds nothing there that makes the factory fork for it.
"""

import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from autograde import sandbox

ROOT = Path(__file__).resolve().parents[1]


pytestmark = [pytest.mark.skipif(not sandbox.available()[0], reason="no bubblewrap sandbox here"), pytest.mark.slow]


def start_factory(tmp_path, monkeypatch, uid, wall=40):
    root = tmp_path / "run"
    for d in ("sockets", "runtime", "grading/cases", "work"):
        (root / d).mkdir(parents=True)
    os.chmod(tmp_path, 0o755)
    settings = {"socket_dir": str(root / "sockets"), "grading_dir": str(root / "grading"),
                "uid": uid, "limits": {**sandbox.DEFAULT_LIMITS, "wall_seconds": wall},
                "shared_cache": None, "zygote_state": str(root / "zygote.json"),
                "connections_dir": str(root / "connections")}
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(root / "runtime"))
    sandbox.write_kernelspec(root / "jupyter", settings)
    monkeypatch.setenv("JUPYTER_PATH", str(root / "jupyter"))
    zygote = sandbox.Zygote(settings, root / "work")
    zygote.ensure()
    return zygote, root


@pytest.fixture()
def uid():
    """A student uid leased for this test as a grading task leases one (None where not root)."""
    with sandbox.allocate_uid() as lease:
        yield lease.uid


@pytest.fixture()
def factory(tmp_path, monkeypatch, uid):
    zygote, root = start_factory(tmp_path, monkeypatch, uid)
    yield zygote, root
    zygote.stop()


def run_kernel(root, code, timeout=90):
    """Start a kernel as nbgrader does, run ``code``, return its stdout (or None if it died)."""
    from jupyter_client import KernelManager

    km = KernelManager(kernel_name=sandbox.KERNEL_NAME, transport="ipc", ip=str(root / "sockets" / "k"))
    km.start_kernel(cwd=str(root / "work"))
    kc = km.client()
    kc.start_channels()
    out = []
    try:
        kc.wait_for_ready(timeout=timeout)
        reply = kc.execute_interactive(code, timeout=timeout, output_hook=lambda m: out.append(
            m["content"].get("text", "")) if m["msg_type"] == "stream" else None)
        if reply["content"]["status"] != "ok":
            out.append("ERROR " + reply["content"].get("evalue", ""))
    except (RuntimeError, TimeoutError):
        return None
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)
    return "".join(out)


def test_kernels_are_forked_fresh_and_leave_nothing_behind(factory):
    zygote, root = factory
    first = run_kernel(root, "import os, subprocess, numpy as np\n"
                             "p = subprocess.Popen(['sleep', '300'], start_new_session=True)\n"
                             "print(os.getcwd(), p.pid, np.random.randint(1 << 30))")
    cwd, stray, draw1 = first.split()
    assert cwd == str((root / "work").resolve())
    second = run_kernel(root, "import os, numpy as np\n"
                              f"try:\n    os.kill({stray}, 0); print('ALIVE', end=' ')\n"
                              "except ProcessLookupError:\n    print('GONE', end=' ')\n"
                              "print(np.random.randint(1 << 30), 'torch' in __import__('sys').modules)")
    verdict, draw2, preloaded = second.split()
    assert verdict == "GONE"                 # the first notebook's background process was killed
    assert draw1 != draw2                     # each kernel has its own random state, not the factory's
    assert preloaded == "True"                # the point of the factory: torch is already imported
    assert zygote.proc.poll() is None         # one factory served both


def test_a_kernel_keeps_the_graders_thread_setting(tmp_path, monkeypatch, uid):
    # grade.worker sets OMP_NUM_THREADS=1 (one grading task per core); torch is imported in the
    # factory before any kernel exists, so the setting must already be there when the factory starts
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    monkeypatch.setenv("MKL_NUM_THREADS", "1")
    zygote, root = start_factory(tmp_path, monkeypatch, uid)
    try:
        out = run_kernel(root, "import torch\nprint(torch.get_num_threads())")
        assert out.strip() == "1"
        assert zygote.proc.poll() is None            # it came from the factory
    finally:
        zygote.stop()


# What a student's kernel runs against the factory (``SOCKDIR``, ``GUESSED`` are set before it): it
# prints "REPORT {json}". Everything a kernel may do, it does; where it cannot, it says why.
ATTACK = r'''
import ctypes, gc, json, os, re, select, socket, stat, struct, sys, time, warnings
warnings.simplefilter("ignore")
libc = ctypes.CDLL(None, use_errno=True)
me, factory = os.getpid(), os.getppid()            # the kernel was forked by the factory
report = {"served": [], "replies": [], "from_factory": [], "from_others": [], "denied": {},
          "channels": [], "inodes": [], "paths": []}

# --- (a) everything in this process that looks like a token: every frame's locals (all threads, the
# factory's frames it was forked in among them), every object the collector knows, its memory
found = {}
HEXLIKE = re.compile(r"[0-9a-fA-F]{16,128}")
B64LIKE = re.compile(r"(?=.*[0-9])(?=.*[a-z])(?=.*[A-Z])[A-Za-z0-9_\-]{22,86}={0,2}")
def consider(value, where):
    if isinstance(value, (bytes, bytearray)):
        try:
            value = bytes(value).decode("ascii")
        except UnicodeDecodeError:
            return
    if isinstance(value, str) and (HEXLIKE.fullmatch(value) or B64LIKE.fullmatch(value)):
        found.setdefault(value, where)
def consider_all(obj, where):
    consider(obj, where)
    if isinstance(obj, dict):
        for k, v in list(obj.items()):
            consider(k, where)
            consider(v, where + "." + str(k)[:40])
    elif isinstance(obj, (list, tuple, set, frozenset)):
        for v in list(obj):
            consider(v, where)
for frame in sys._current_frames().values():
    while frame is not None:
        for name, value in list(frame.f_locals.items()):
            consider_all(value, "frame " + frame.f_code.co_name + "." + name)
        frame = frame.f_back
for obj in gc.get_objects():
    if isinstance(obj, (dict, list, tuple, set, frozenset)):
        consider_all(obj, "object")
    elif type(obj).__name__ == "frame":
        for name, value in list(obj.f_locals.items()):
            consider_all(value, "frame " + obj.f_code.co_name + "." + name)
# its memory: every writable mapping (heap, stacks, anonymous, data), where anything made at run
# time lives; the read-only ones are the files mapped (the interpreter, libraries) as on disk
HEX = re.compile(rb"(?<![0-9a-f])[0-9a-f]{32}(?![0-9a-f])")
scanned = 0
with open("/proc/self/maps") as maps, open("/proc/self/mem", "rb", buffering=0) as mem:
    for line in maps:
        fields = line.split()
        lo, hi = (int(x, 16) for x in fields[0].split("-"))
        if fields[1][:2] != "rw" or fields[-1] in ("[vvar]", "[vsyscall]"):
            continue
        try:
            mem.seek(lo)
            chunk = mem.read(hi - lo)
        except (OSError, ValueError, OverflowError):
            continue
        scanned += len(chunk)
        for m in HEX.finditer(chunk):
            found.setdefault(m.group().decode(), "memory")
SUGGESTIVE = re.compile(r"token|secret|key|auth|cookie|pass", re.I)
# an attacker's order: what is named like a secret, then what frames and objects hold, then memory
tokens = sorted(found, key=lambda v: (not SUGGESTIVE.search(found[v]), found[v] == "memory", len(v) != 32, found[v]))[:32]
report.update(candidates=len(found), scanned_mb=scanned >> 20, first=[(found[v], v[:6]) for v in tokens[:6]])

# --- (b) forged requests, as the grader's launcher sends them, with its own descriptors (0, 1, 2)
pending, count = [], 0
def forge_on(sock, token, label):
    global count
    count += 1
    body = {"connection_file": f"{SOCKDIR}/forged-{count}.json", "cwd": "/tmp"}   # a kernel forked for it creates this file
    if token is not None:
        body["token"] = token
    try:
        socket.send_fds(sock, [json.dumps(body).encode()], [0, 1, 2])
        pending.append((sock, label))
    except OSError:
        sock.close()

# every descriptor it holds, and every one it can take from another process of the sandbox
def socket_info(fd):
    s = socket.socket(fileno=os.dup(fd))
    info = {"family": s.family}
    try:
        info["listening"] = bool(s.getsockopt(socket.SOL_SOCKET, socket.SO_ACCEPTCONN))
        info["name"] = str(s.getsockname())
        info["peer_pid"] = struct.unpack("3i", s.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, 12))[0]
    except OSError:
        pass
    return s, info
def use(fd, label):
    """Try descriptor ``fd`` as a way to the factory: accept on it, or send it forged requests."""
    s, info = socket_info(fd)
    if info.get("peer_pid") == factory:
        report["channels"].append(label)
    # not this kernel's own ZeroMQ sockets (jupyter's ipc transport) or its own event loop's pipe
    if info.get("name", "").startswith(SOCKDIR + "/k-") or info.get("peer_pid") == me:
        s.close()
        return
    if info.get("listening"):
        s.setblocking(False)
        try:
            s.accept()[0].close()
            report["served"].append("accepted a connection on " + label)
        except OSError:
            pass
        s.close()
    elif info["family"] == socket.AF_UNIX:
        for token in [None] + tokens[:8]:
            forge_on(socket.socket(fileno=os.dup(fd)), token, label)
        s.close()
for name in os.listdir("/proc/self/fd"):
    try:
        if stat.S_ISSOCK(os.fstat(int(name)).st_mode):
            report["inodes"].append(os.readlink(f"/proc/self/fd/{name}"))
            use(int(name), "own fd " + name)
    except OSError:
        pass
for pid in [int(p) for p in os.listdir("/proc") if p.isdigit() and int(p) != me]:
    who = "factory" if pid == factory else f"pid {pid}"
    for what in ("fd", "mem", "environ", "maps"):
        try:
            if what == "fd":
                os.listdir(f"/proc/{pid}/fd")
            else:
                open(f"/proc/{pid}/{what}", "rb").read(1)
            report["denied"][f"{who} /proc/{what}"] = "READ"
        except OSError as e:
            report["denied"][f"{who} /proc/{what}"] = type(e).__name__
    if libc.ptrace(16, pid, 0, 0) == 0:                    # PTRACE_ATTACH
        report["denied"][f"{who} ptrace"] = "ATTACHED"
        time.sleep(0.05)
        libc.ptrace(17, pid, 0, 0)                         # PTRACE_DETACH
    else:
        report["denied"][f"{who} ptrace"] = os.strerror(ctypes.get_errno())
    try:
        pidfd = os.pidfd_open(pid)
    except OSError:
        continue
    for target in range(256):
        fd = libc.syscall(438, pidfd, target, 0)            # pidfd_getfd: a copy of its descriptor
        if fd < 0:
            report["denied"].setdefault(f"{who} pidfd_getfd", os.strerror(ctypes.get_errno()))
            continue
        label = f"fd {target} of {who}"
        (report["from_factory"] if pid == factory else report["from_others"]).append(label)
        try:
            if stat.S_ISSOCK(os.fstat(fd).st_mode):
                report["inodes"].append(os.readlink(f"/proc/self/fd/{fd}"))
                use(fd, label)
        finally:
            os.close(fd)
    os.close(pidfd)

# every Unix socket it can name: the whole filesystem it sees, /proc/net/unix, and the factory's
# own socket path, as if the student had guessed it
paths = {GUESSED}
def walk(top):
    try:
        entries = list(os.scandir(top))
    except OSError:
        return
    for e in entries:
        try:
            if e.is_dir(follow_symlinks=False):
                if e.path not in ("/proc", "/sys"):
                    walk(e.path)
            elif not e.is_file(follow_symlinks=False) and not e.is_symlink():
                if stat.S_ISSOCK(e.stat(follow_symlinks=False).st_mode):
                    paths.add(e.path)
        except OSError:
            pass
walk("/")
with open("/proc/net/unix") as f:
    for line in list(f)[1:]:
        parts = line.split()
        if len(parts) >= 8:
            paths.add("\0" + parts[7][1:] if parts[7].startswith("@") else parts[7])
report["paths"] = sorted(p.replace("\0", "@") for p in paths)
for path in paths:
    for token in [None] + tokens:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            s.connect(path)
        except OSError as e:
            s.close()
            report["denied"]["connect " + path.replace("\0", "@")] = type(e).__name__
            break
        forge_on(s, token, "connect " + path.replace("\0", "@"))

# --- did anything answer as the factory does ("pid N")?
poller, by_fd = select.poll(), {s.fileno(): (s, label) for s, label in pending}
for fd in by_fd:
    poller.register(fd, select.POLLIN)
deadline = time.monotonic() + 3
while by_fd and time.monotonic() < deadline:
    for fd, _ in poller.poll(200):
        s, label = by_fd.pop(fd)
        poller.unregister(fd)
        try:
            data = s.recv(64)
        except OSError:
            data = b""
        if data.startswith(b"pid "):
            report["served"].append(label)
        elif data and label not in report["replies"]:
            report["replies"].append(label)
        s.close()
for s, _ in by_fd.values():
    s.close()
report["forged"] = count
time.sleep(1)
report["markers"] = sorted(n for n in os.listdir(SOCKDIR) if n.startswith("forged-"))
print("REPORT " + json.dumps(report))
'''


def listener_inode(path: str) -> str | None:
    """The inode of the listening Unix socket bound at ``path`` in this network namespace, or None."""
    with open("/proc/net/unix") as f:
        for line in list(f)[1:]:
            parts = line.split()
            if len(parts) >= 8 and parts[7] == path and int(parts[3], 16) & 0x10000:    # __SO_ACCEPTCON
                return parts[6]
    return None


def socket_inodes_of(pid: int) -> set | None:
    """The sockets process ``pid`` holds ("socket:[inode]"), or None where this process may not look."""
    try:
        return {os.readlink(f"/proc/{pid}/fd/{fd}") for fd in os.listdir(f"/proc/{pid}/fd")}
    except OSError:
        return None


def test_a_kernel_finds_no_secret_and_no_way_to_make_the_factory_fork(tmp_path, monkeypatch, uid):
    """What a student's kernel can do, all of it: search its own memory (every thread's frames, the
    factory's frames it was forked in among them, every object, /proc/self/mem) for anything like a
    token; connect to every Unix socket it can name (the filesystem, /proc/net/unix, the factory's
    real socket path as if guessed) and send forged requests with every token it found and its own
    descriptors; use every descriptor it holds, and every one it can take from another process of
    the sandbox (pidfd_getfd); read or trace the factory. The factory must fork for none of it (a
    forged request names a connection file a forked kernel would create), the kernel must live on
    (the factory ends the current kernel before it forks another), and the grader still gets its
    kernels. On the old design (a token in the factory's memory) the first thing the search found was
    the token, in the request the kernel was forked for (a local of the frame ``_child``), and the
    factory forked for it."""
    zygote, root = start_factory(tmp_path, monkeypatch, uid, wall=300)    # a slow search on a busy host
    try:
        state = json.loads((root / "zygote.json").read_text())
        sockdir = str(root / "sockets")
        out = run_kernel(root, f"SOCKDIR, GUESSED = {sockdir!r}, {state['socket']!r}\n" + ATTACK, timeout=200)
        assert out is not None, "the kernel died mid-attack: the factory ended it, to fork for a forged request"
        assert "REPORT " in out, out
        report = json.loads(out.split("REPORT ", 1)[1])
        forged = sorted(p.name for p in (root / "sockets").glob("forged-*"))
        assert report["served"] == [] and report["markers"] == [] and forged == [], (report["served"], forged)
        assert report["candidates"] > 0 and report["paths"]             # it did search, and it did find sockets
        assert report["denied"]["connect " + state["socket"]] == "FileNotFoundError"   # a path it cannot see
        # (where grading is not root, bwrap's init is the student's uid and dumpable: the kernel takes
        # copies of its descriptors, "from_others", and they lead nowhere, as "served" says)
        assert report["from_factory"] == [] and report["channels"] == []  # no descriptor of, or to, the factory
        for what in ("fd", "mem", "environ", "maps"):
            assert report["denied"][f"factory /proc/{what}"] != "READ"
        assert report["denied"]["factory ptrace"] != "ATTACHED"
        assert "token" not in state                                       # nothing secret to hand around
        listening = f"socket:[{listener_inode(state['socket'])}]"
        assert listening not in report["inodes"]                          # no kernel holds the factory's socket
        for pid in (state["pid"], state["init"]):                         # nor bwrap, nor the sandbox's init
            held = socket_inodes_of(pid)
            assert held is None or listening not in held, pid
        assert zygote.proc.poll() is None                                 # the same factory, unharmed,
        assert run_kernel(root, "print(6 * 7)").strip() == "42"            # still serves its grader
    finally:
        zygote.stop()


def test_the_wall_clock_stops_a_notebook_and_the_next_one_still_runs(factory):
    zygote, root = factory
    settings_file = root / "jupyter" / "kernels" / sandbox.KERNEL_NAME / "settings.json"
    s = json.loads(settings_file.read_text())
    s["limits"]["wall_seconds"] = 3
    settings_file.write_text(json.dumps(s))
    from jupyter_client import KernelManager

    km = KernelManager(kernel_name=sandbox.KERNEL_NAME, transport="ipc", ip=str(root / "sockets" / "k"))
    km.start_kernel(cwd=str(root / "work"))
    kc = km.client()
    kc.start_channels()
    kc.wait_for_ready(timeout=90)
    kc.execute("import time\nwhile True: time.sleep(1)")
    started = time.monotonic()
    while km.is_alive() and time.monotonic() - started < 30:
        time.sleep(0.2)
    assert not km.is_alive(), "the notebook outlived its wall clock"
    kc.stop_channels()
    km.shutdown_kernel(now=True)
    assert zygote.proc.wait(timeout=10) is not None        # the launcher killed the factory's sandbox
    s["limits"]["wall_seconds"] = 40
    settings_file.write_text(json.dumps(s))
    zygote.ensure()                                         # the grader starts it again
    assert run_kernel(root, "print(6 * 7)").strip() == "42"


def test_a_factory_stopped_while_it_still_starts_leaves_nothing_behind(tmp_path, processes_of, uid):
    """The worker starts the factory before it imports nbgrader (``start`` does not wait for it); a
    worker that fails at once stops a factory still importing torch, and nothing of it may survive."""
    root = tmp_path / "run"
    for d in ("sockets", "runtime", "grading/cases", "work"):
        (root / d).mkdir(parents=True)
    os.chmod(tmp_path, 0o755)
    settings = {"socket_dir": str(root / "sockets"), "grading_dir": str(root / "grading"), "uid": uid,
                "limits": dict(sandbox.DEFAULT_LIMITS), "shared_cache": None,
                "zygote_state": str(root / "zygote.json"), "connections_dir": str(root / "connections")}
    zygote = sandbox.Zygote(settings, root / "work")
    started = time.monotonic()
    zygote.start()
    assert time.monotonic() - started < 1.0 and not (root / "sockets" / "zygote").exists()   # not waited for
    zygote.stop()
    assert processes_of({uid}) == [] and zygote.proc is None and not (root / "zygote.json").exists()


def test_a_kernel_starts_its_own_sandbox_when_the_factory_is_gone(factory):
    zygote, root = factory
    zygote.stop()
    assert run_kernel(root, "import os\nprint(os.getcwd())").strip() == str((root / "work").resolve())


def test_a_malformed_request_from_the_grader_starts_nothing(factory):
    zygote, root = factory
    state = json.loads((root / "zygote.json").read_text())
    assert os.stat(Path(state["socket"]).parent).st_mode & 0o077 == 0     # the grader's alone
    zygote.ensure()
    for request, fds in ((json.dumps({"cwd": "/"}).encode(), [0, 1, 2]),
                         (json.dumps(["/", "x"]).encode(), [0, 1, 2]),
                         (json.dumps({"cwd": 5, "connection_file": "x"}).encode(), [0, 1, 2]),
                         (json.dumps({"cwd": "/", "connection_file": "x"}).encode(), [0]),
                         (b"\xff not json", [0, 1, 2])):
        with socket.socket(socket.AF_UNIX) as s:
            s.connect(state["socket"])
            socket.send_fds(s, [request], fds)
            s.settimeout(30)
            assert s.recv(64) == b""                        # refused: the connection is just closed
    time.sleep(0.5)
    assert zygote.proc.poll() is None                       # and the factory still serves its grader
    assert run_kernel(root, "print(6 * 7)").strip() == "42"


@pytest.mark.skipif(os.geteuid() != 0 or not shutil.which("nsenter"), reason="entering a PID namespace needs root")
def test_a_request_from_inside_the_sandbox_is_refused_even_on_the_right_socket(factory):
    """The second lock: were a process of the sandbox ever to reach the factory's socket, its peer
    credentials give it away (a nonzero pid in the factory's PID namespace; the grader's is 0).
    Here a process joins the sandbox's PID namespace but keeps the host's files, so it can connect,
    and sends a request the grader would send."""
    zygote, root = factory
    state = json.loads((root / "zygote.json").read_text())
    zygote.ensure()
    marker = root / "sockets" / "forged-nsenter.json"
    code = ("import json, os, socket, sys\n"
            "s = socket.socket(socket.AF_UNIX); s.connect(sys.argv[1]); s.settimeout(30)\n"
            "try:\n"
            "    socket.send_fds(s, [json.dumps({'connection_file': sys.argv[2], 'cwd': '/tmp'}).encode()], [0, 1, 2])\n"
            "    reply = s.recv(64)\n"
            "except (BrokenPipeError, ConnectionResetError):\n"      # closed before it even sent
            "    reply = b''\n"
            "print(os.getpid(), 'REFUSED' if reply == b'' else reply)")
    done = subprocess.run(["nsenter", f"--target={state['init']}", "--pid", "--", sys.executable, "-c", code,
                           state["socket"], str(marker)], capture_output=True, text=True, timeout=60)
    assert done.stdout.split()[1:] == ["REFUSED"], done
    assert int(done.stdout.split()[0]) > 1                     # it was in the sandbox's PID namespace
    time.sleep(1)
    assert not marker.exists() and zygote.proc.poll() is None
    assert run_kernel(root, "print(6 * 7)").strip() == "42"


def test_the_factorys_socket_is_never_where_its_sandbox_sees_it(processes_of, uid):
    """A state file (and so the socket's folder) inside a folder the sandbox binds is refused
    before anything starts."""
    root = Path(tempfile.mkdtemp(prefix="z", dir="/tmp"))      # short: the socket's path must fit (107 bytes)
    try:
        for d in ("sockets", "runtime", "grading/cases", "work"):
            (root / d).mkdir(parents=True)
        os.chmod(root, 0o755)
        settings = {"socket_dir": str(root / "sockets"), "grading_dir": str(root / "grading"), "uid": uid,
                    "limits": dict(sandbox.DEFAULT_LIMITS), "shared_cache": None,
                    "zygote_state": str(root / "sockets" / "zygote.json"),
                    "connections_dir": str(root / "connections")}
        zygote = sandbox.Zygote(settings, root / "work")
        with pytest.raises(RuntimeError, match="visible"):
            zygote.start()
        zygote.stop()
        assert zygote.proc is None and list((root / "sockets").glob("zygote-*")) == []
        assert uid is None or processes_of({uid}) == []
    finally:
        shutil.rmtree(root, ignore_errors=True)
