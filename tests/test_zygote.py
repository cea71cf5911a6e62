"""The grader's kernel factory: one sandbox per student, a fresh forked kernel per notebook.

``sandbox.Zygote`` starts ``pusht.zygote`` once in a student's sandbox; every kernel nbgrader asks
for is then forked from it by ``sandbox.launch`` (the kernel spec's command). These tests drive it
the way nbgrader does, with jupyter_client and the real bubblewrap sandbox, and check what must
stay true of a kernel of its own: nothing one notebook started lives into the next, the wall clock
still stops a notebook, kernels are not clones of each other, and the factory serves only its
grader.
"""

import json
import os
import socket
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "autograde"))

import sandbox  # noqa: E402

pytestmark = pytest.mark.skipif(not sandbox.available()[0], reason="no bubblewrap sandbox here")


def start_factory(tmp_path, monkeypatch, uid):
    root = tmp_path / "run"
    for d in ("sockets", "runtime", "grading/cases", "work"):
        (root / d).mkdir(parents=True)
    os.chmod(tmp_path, 0o755)
    settings = {"socket_dir": str(root / "sockets"), "grading_dir": str(root / "grading"),
                "uid": uid, "limits": {**sandbox.DEFAULT_LIMITS, "wall_seconds": 40},
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


def test_the_factory_cannot_be_read_or_commanded_from_a_kernel(factory):
    zygote, root = factory
    state = json.loads((root / "zygote.json").read_text())
    out = run_kernel(root, "import os, socket, json\n"
                           "z = [p for p in os.listdir('/proc') if p.isdigit() and int(p) not in (1, os.getpid())\n"
                           "     and b'pusht.zygote' in open(f'/proc/{p}/cmdline', 'rb').read()]\n"
                           "try:\n    open(f'/proc/{z[0]}/environ').read(); print('READ')\n"
                           "except OSError:\n    print('DENIED')\n"
                           "s = socket.socket(socket.AF_UNIX); s.connect(" + repr(state["socket"]) + ")\n"
                           "s.sendall(json.dumps({'token': 'guess', 'cwd': '/', 'connection_file': 'x'}).encode())\n"
                           "print('REFUSED' if s.recv(64) == b'' else 'SERVED')")
    assert out.split() == ["DENIED", "REFUSED"]
    assert state["token"] not in out


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


def test_a_request_without_the_token_starts_nothing(factory):
    zygote, root = factory
    state = json.loads((root / "zygote.json").read_text())
    deadline = time.monotonic() + 120
    while True:
        with socket.socket(socket.AF_UNIX) as s:
            try:
                s.connect(state["socket"])
                break
            except OSError:
                assert time.monotonic() < deadline, "the factory never listened"
                time.sleep(0.1)
    # a wrong token, then requests a hostile kernel could send that are not even well formed
    for request in (json.dumps({"token": "wrong", "cwd": "/", "connection_file": "x"}).encode(),
                    json.dumps([state["token"]]).encode(), json.dumps({"token": 12345}).encode(),
                    b"\xff not json"):
        with socket.socket(socket.AF_UNIX) as s:
            s.connect(state["socket"])
            socket.send_fds(s, [request], [0, 1, 2])
            assert s.recv(64) == b""                        # refused: the connection is just closed
    time.sleep(0.5)
    assert zygote.proc.poll() is None                       # and the factory still serves its grader
    assert run_kernel(root, "print(6 * 7)").strip() == "42"
