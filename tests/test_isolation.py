"""Grading runs that share a host cannot reach each other's students.

Two sections graded at once, a regrade started beside a batch, several Dask workers on one host:
each grading task leases its student's uid for itself on the whole host (``sandbox.allocate_uid``),
a sandbox is killed through its own PID namespace and nothing outside it (``sandbox.SandboxInit``),
and one course folder is graded by one run at a time (``autograde.course.course_lock``). What these tests
check about processes they read from /proc directly, not through the code under test.
"""

import fcntl
import logging
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from autograde import sandbox
from conftest import running_as

pytestmark = pytest.mark.slow          # leases uids and starts sandboxes

ROOT = Path(__file__).resolve().parents[1]


ROOT_ONLY = pytest.mark.skipif(os.geteuid() != 0, reason="student uids are switched (and leased) only as root")
BWRAP = pytest.mark.skipif(not sandbox.available()[0], reason="no bubblewrap sandbox here")
FORK = multiprocessing.get_context("fork")


# --- helpers: what runs on the host, from /proc ------------------------------------------------------
def cmdlines_with(text: str) -> list[int]:
    """Pids of every process on the host whose command line contains ``text``."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            if text.encode() in Path(f"/proc/{pid}/cmdline").read_bytes():
                found.append(int(pid))
        except OSError:
            continue
    return found


def factory_pid(sock: str) -> int:
    """The pid of the kernel factory listening on ``sock`` (not the bwrap processes around it)."""
    for pid in cmdlines_with(sock):
        argv = Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
        if argv[1:5] == ["-P", "-m", "pusht.grader.zygote", sock]:
            return pid
    raise AssertionError(f"no factory on {sock}")


def _started(pid) -> str | None:
    """When process ``pid`` started (clock ticks since boot), or None if there is none: a pid with
    the same start is the same process."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


def in_pid_namespace(ns: str) -> dict:
    """Every process on the host in the PID namespace ``ns`` ("pid:[...]"): {pid: its start}."""
    found = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            if os.readlink(f"/proc/{pid}/ns/pid") == ns:
                found[int(pid)] = _started(pid)
        except OSError:
            continue
    return found


def still_there(processes: dict) -> list[int]:
    """Which of ``processes`` ({pid: start}, from ``in_pid_namespace``) still exist, zombies included.
    (Not "what is in that namespace now": a namespace's number is reused once it is gone.)"""
    return [pid for pid, start in processes.items() if _started(pid) == start]


def lock_is_free(uid: int) -> bool:
    """Whether a fresh open of ``uid``'s lock file can lock it now (nobody holds it)."""
    fd = os.open(sandbox.uid_lock_dir() / f"{uid}.lock", os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False
    finally:
        os.close(fd)


def run_as(uid: int, *cmd: str) -> subprocess.Popen:
    """A plain process running as ``uid`` outside every sandbox, once it is running as it."""
    proc = subprocess.Popen(["setpriv", f"--reuid={uid}", f"--regid={uid}", "--clear-groups", "--", *cmd])
    deadline = time.monotonic() + 10
    while str(proc.pid) not in [p for p, _ in running_as({uid})]:
        assert time.monotonic() < deadline and proc.poll() is None, "setpriv did not start"
        time.sleep(0.01)
    return proc


def factory_settings(root: Path, uid) -> dict:
    for d in ("sockets", "runtime", "grading/cases", "work"):
        (root / d).mkdir(parents=True)
    return {"socket_dir": str(root / "sockets"), "grading_dir": str(root / "grading"), "uid": uid,
            "limits": dict(sandbox.DEFAULT_LIMITS), "shared_cache": None,
            "zygote_state": str(root / "zygote.json"), "connections_dir": str(root / "connections")}


# --- the uid allocator ----------------------------------------------------------------------------------
def _hold(queue, release):
    with sandbox.allocate_uid() as lease:
        queue.put(lease.uid)
        release.wait(30)


@ROOT_ONLY
def test_processes_and_threads_allocating_at_once_get_distinct_uids():
    queue, release = FORK.Queue(), FORK.Event()
    procs = [FORK.Process(target=_hold, args=(queue, release)) for _ in range(6)]
    for p in procs:
        p.start()
    leases, lock = [], threading.Lock()

    def take():
        lease = sandbox.allocate_uid()
        with lock:
            leases.append(lease)
    threads = [threading.Thread(target=take) for _ in range(4)]
    for t in threads:
        t.start()
    try:
        uids = [queue.get(timeout=30) for _ in procs]
        for t in threads:
            t.join()
        uids += [lease.uid for lease in leases]
        assert len(set(uids)) == len(uids) == 10, uids
        assert all(u in sandbox.STUDENT_UIDS for u in uids)
        assert not any(lock_is_free(u) for u in uids)          # every one is still held
    finally:
        release.set()
        for p in procs:
            p.join(10)
        for lease in leases:
            lease.close()


def _hold_until_killed(queue):
    lease = sandbox.allocate_uid()
    queue.put(lease.uid)
    time.sleep(60)


@ROOT_ONLY
def test_a_holder_that_dies_frees_its_uid():
    queue = FORK.Queue()
    holder = FORK.Process(target=_hold_until_killed, args=(queue,))
    holder.start()
    uid = queue.get(timeout=30)
    assert not lock_is_free(uid)
    os.kill(holder.pid, signal.SIGKILL)             # no clean-up of its own: the kernel drops its lock
    holder.join(10)
    assert lock_is_free(uid)


@ROOT_ONLY
def test_a_uid_some_process_still_runs_as_is_not_handed_out():
    with sandbox.allocate_uid() as first:
        uid = first.uid
    leftover = run_as(uid, "sleep", "60")          # as a crashed run's process would
    try:
        with sandbox.allocate_uid() as other:
            assert other.uid != uid
            leftover.kill()
            leftover.wait()
            with sandbox.allocate_uid() as again:   # gone: the uid is free again
                assert again.uid == uid
    finally:
        leftover.kill()
        leftover.wait()


@ROOT_ONLY
def test_the_lease_is_not_inherited_by_children():
    lease = sandbox.allocate_uid()
    child = subprocess.Popen(["sleep", "30"], close_fds=False)     # even where fds are passed on
    try:
        assert not os.get_inheritable(lease.fd)
        held = [os.readlink(f"/proc/{child.pid}/fd/{fd}") for fd in os.listdir(f"/proc/{child.pid}/fd")]
        assert str(lease.path) not in held
        lease.close()
        assert lock_is_free(lease.uid)                             # the child does not hold it
    finally:
        child.kill()
        child.wait()
        lease.close()


@ROOT_ONLY
def test_all_uids_taken_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(sandbox, "STUDENT_UIDS", range(61897, 61900))
    held = []
    try:
        while True:
            try:
                held.append(sandbox.allocate_uid())
            except RuntimeError as e:
                assert "are taken on this host" in str(e) and str(sandbox.uid_lock_dir()) in str(e)
                break
            assert len(held) <= 3
    finally:
        for lease in held:
            lease.close()


@ROOT_ONLY
def test_the_lock_folder_must_be_roots_alone(tmp_path, monkeypatch):
    open_dir = tmp_path / "open"
    open_dir.mkdir(mode=0o777)
    os.chmod(open_dir, 0o777)
    monkeypatch.setattr(sandbox, "UID_LOCK_DIRS", ((str(tmp_path), "open"),))
    with pytest.raises(RuntimeError, match="refusing"):
        sandbox.uid_lock_dir()
    theirs = tmp_path / "theirs"
    theirs.mkdir(mode=0o700)
    os.chown(theirs, 1000, 1000)
    monkeypatch.setattr(sandbox, "UID_LOCK_DIRS", ((str(tmp_path), "theirs"),))
    with pytest.raises(RuntimeError, match="refusing"):
        sandbox.uid_lock_dir()
    monkeypatch.setattr(sandbox, "UID_LOCK_DIRS", ((str(tmp_path / "nowhere"), "x"), (str(tmp_path), "new/uids")))
    made = sandbox.uid_lock_dir()                  # the first base that exists and can be written
    assert made == tmp_path / "new" / "uids" and (made.stat().st_mode & 0o777) == 0o700


def _hold_on_worker(folder: str, others: int):
    from autograde import sandbox as sb

    with sb.allocate_uid() as lease:
        Path(folder, str(os.getpid())).write_text(str(lease.uid))
        deadline = time.monotonic() + 30
        while len(os.listdir(folder)) < others and time.monotonic() < deadline:   # all hold theirs at once
            time.sleep(0.02)
        return os.getpid(), lease.uid


@ROOT_ONLY
def test_dask_workers_on_one_host_lease_distinct_uids(tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  preload=["autograde.dask_preload"],
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as client:
        workers = list(client.scheduler_info()["workers"])
        assert len(workers) == 2
        futures = [client.submit(_hold_on_worker, str(tmp_path), 2, workers=[w], allow_other_workers=False,
                                 pure=False) for w in workers]
        got = client.gather(futures)
    pids, uids = zip(*got)
    assert len(set(pids)) == 2                                  # two worker processes on this host
    assert len(set(uids)) == 2 and all(u in sandbox.STUDENT_UIDS for u in uids), got


# --- killing one sandbox kills that sandbox and nothing else ---------------------------------------
@BWRAP
def test_stopping_one_runs_sandbox_leaves_another_runs_sandbox_alone(tmp_path):
    os.chmod(tmp_path, 0o755)
    with sandbox.allocate_uid() as lease1, sandbox.allocate_uid() as lease2:
        zygotes = [sandbox.Zygote(factory_settings(tmp_path / name, lease.uid), tmp_path / name / "work")
                   for name, lease in (("run1", lease1), ("run2", lease2))]
        try:
            for z in zygotes:
                z.start()
            for z in zygotes:
                z.ensure()
            socket1, socket2 = (str(tmp_path / n / "sockets" / "zygote") for n in ("run1", "run2"))
            f1, f2 = factory_pid(socket1), factory_pid(socket2)
            ns1, ns2 = (os.readlink(f"/proc/{f}/ns/pid") for f in (f1, f2))
            assert ns1 != ns2
            run1, run2 = in_pid_namespace(ns1), in_pid_namespace(ns2)
            assert f1 in run1 and f2 in run2
            if lease1.uid is not None:
                assert running_as({lease1.uid}) and running_as({lease2.uid})
                uid2_before = running_as({lease2.uid})
            zygotes[0].stop()
            assert still_there(run1) == [] and cmdlines_with(socket1) == []     # nothing of run 1 left
            assert still_there(run2) == list(run2)                             # run 2 untouched
            assert zygotes[1].proc.poll() is None
            if lease1.uid is not None:
                assert running_as({lease1.uid}) == [] and running_as({lease2.uid}) == uid2_before
        finally:
            for z in zygotes:
                z.stop()
        assert still_there(run2) == [] and cmdlines_with(socket2) == []


@BWRAP
@ROOT_ONLY
def test_a_process_of_the_same_uid_outside_the_sandbox_survives_its_clean_up(tmp_path):
    """The bug of issue 27: a student's clean-up killed every process of the student's uid on the
    host, and so the kernels of another run that had the same uid. Clean-up now ends the sandbox's
    own PID namespace, whatever else runs as that uid."""
    os.chmod(tmp_path, 0o755)
    with sandbox.allocate_uid() as lease:
        outsider = run_as(lease.uid, "sleep", "60")       # another run's process with this uid
        zygote = sandbox.Zygote(factory_settings(tmp_path / "run", lease.uid), tmp_path / "run" / "work")
        try:
            zygote.ensure()
            inside = [int(p) for p, _ in running_as({lease.uid}) if int(p) != outsider.pid]
            assert inside                                  # the factory runs as the uid, in its sandbox
            zygote.stop()
            assert outsider.poll() is None, "the sandbox's clean-up killed a process outside it"
            assert [int(p) for p, _ in running_as({lease.uid})] == [outsider.pid]
        finally:
            zygote.stop()
            outsider.kill()
            outsider.wait()


@ROOT_ONLY
def test_a_run_records_the_uids_it_leased_and_no_others():
    held = sandbox.allocate_uid()                     # leased before recording: not this run's
    try:
        with sandbox.recording_leases() as leased:
            got = []
            threads = [threading.Thread(target=lambda: got.append(sandbox.allocate_uid())) for _ in range(3)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        after = sandbox.allocate_uid()                # after recording: not this run's either
        assert sorted(leased) == sorted(lease.uid for lease in got) and held.uid not in leased
        assert after.uid not in leased
        for lease in got + [after]:
            lease.close()
    finally:
        held.close()


@ROOT_ONLY
def test_a_runs_leftovers_are_its_own_uids_processes_that_no_holder_accounts_for(leftovers):
    """conftest.leftovers_of, which test_grading_hostile's leftovers check uses: a process of a uid the
    run leased is a leftover unless a grading task that holds the uid now runs it (another run on this
    host that leased the uid once this run gave it back)."""
    lease = sandbox.allocate_uid()                    # another run's task holds the uid (this process)
    uid = lease.uid
    theirs = run_as(uid, "sleep", "60")              # that task's kernel: a child of the holder
    orphan = None
    try:
        assert leftovers([uid], settle=0) == []
        # a process of the uid that left its task (reparented away from the holder): a leftover
        subprocess.run(["setsid", "-f", "setpriv", f"--reuid={uid}", f"--regid={uid}", "--clear-groups", "--",
                        "sleep", "61"], check=True)
        deadline = time.monotonic() + 10
        while orphan is None and time.monotonic() < deadline:
            orphan = next((int(p) for p, cmd in running_as({uid}) if cmd.startswith(b"sleep\x0061")), None)
            time.sleep(0.01)
        assert orphan and [int(p) for p, _ in leftovers([uid], settle=0)] == [orphan]
        os.kill(orphan, signal.SIGKILL)
        deadline = time.monotonic() + 10
        while leftovers([uid], settle=0) and time.monotonic() < deadline:
            time.sleep(0.01)
        assert leftovers([uid], settle=0) == []
        lease.close()                                 # now nobody holds it: whatever runs as it is left over
        assert [int(p) for p, _ in leftovers([uid], settle=0)] == [theirs.pid]
    finally:
        lease.close()
        theirs.kill()
        theirs.wait()
        if orphan:
            try:
                os.kill(orphan, signal.SIGKILL)
            except ProcessLookupError:
                pass


@BWRAP
def test_a_sandbox_stopped_at_any_moment_of_its_start_leaves_nothing(tmp_path):
    os.chmod(tmp_path, 0o755)
    with sandbox.allocate_uid() as lease:
        for i, delay in enumerate((0, 0.002, 0.01, 0.03, 0.1, 0.3, 1.0)):
            root = tmp_path / f"run{i}"
            zygote = sandbox.Zygote(factory_settings(root, lease.uid), root / "work")
            zygote.start()
            time.sleep(delay)
            zygote.stop()
            # bwrap, the sandbox's init, prlimit, setpriv, the factory: all carry this folder's path
            assert cmdlines_with(str(root / "sockets")) == [], f"left running after a stop at {delay}s"
            if lease.uid is not None:
                assert running_as({lease.uid}) == []


@BWRAP
def test_the_wall_clock_kills_a_kernels_own_sandbox_whole(tmp_path, monkeypatch):
    """``launch`` without a factory: its sandbox, a process that left its session included, is
    killed through the sandbox's PID namespace when the wall clock runs out."""
    from jupyter_client import KernelManager

    os.chmod(tmp_path, 0o755)
    with sandbox.allocate_uid() as lease:
        root = tmp_path / "run"
        settings = factory_settings(root, lease.uid)
        settings["limits"]["wall_seconds"] = 8
        del settings["zygote_state"], settings["connections_dir"]
        monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(root / "runtime"))
        sandbox.write_kernelspec(root / "jupyter", settings)
        monkeypatch.setenv("JUPYTER_PATH", str(root / "jupyter"))
        km = KernelManager(kernel_name=sandbox.KERNEL_NAME, transport="ipc", ip=str(root / "sockets" / "k"))
        km.start_kernel(cwd=str(root / "work"))
        kc = km.client()
        kc.start_channels()
        try:
            kc.wait_for_ready(timeout=90)
            kc.execute("import subprocess, sys, time\n"
                       "subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)', "
                       "'stray-of-the-walled-kernel'], start_new_session=True)\n"
                       "while True: time.sleep(1)")
            deadline = time.monotonic() + 60
            while not cmdlines_with("stray-of-the-walled-kernel") and time.monotonic() < deadline:
                time.sleep(0.05)
            assert cmdlines_with("stray-of-the-walled-kernel"), "the kernel did not start its stray process"
            while km.is_alive() and time.monotonic() < deadline:
                time.sleep(0.1)
            assert not km.is_alive(), "the notebook outlived its wall clock"
            time.sleep(0.2)
            assert cmdlines_with("stray-of-the-walled-kernel") == []
            assert cmdlines_with(str(root / "sockets")) == []
            if lease.uid is not None:
                assert running_as({lease.uid}) == []
        finally:
            kc.stop_channels()
            km.shutdown_kernel(now=True)


# --- one grading run per course folder ------------------------------------------------------------
def _hold_course(course, conn):
    from autograde.course import course_lock

    with course_lock(Path(course), log=lambda *_: None):
        conn.send("held")
        conn.poll(30)                      # until released (or the test is gone)


@pytest.fixture()
def course_holder(tmp_path):
    """Another process holding the course folder ``tmp_path / 'course'``: (its pid, release it)."""
    import autograde.course  # noqa: F401  imported before forking

    course = tmp_path / "course"
    ours, theirs = FORK.Pipe()
    holder = FORK.Process(target=_hold_course, args=(str(course), theirs))
    holder.start()
    assert ours.poll(30) and ours.recv() == "held"
    yield course, holder, lambda: ours.send("release")
    if holder.is_alive():
        ours.send("release")
        holder.join(10)
    if holder.is_alive():
        holder.kill()


def test_a_second_run_on_the_same_course_waits_for_the_first(course_holder):
    from autograde.course import COURSE_LOCK, course_lock

    course, holder, release = course_holder
    logs, got = [], []

    def second():
        with course_lock(course, log=logs.append):
            got.append(time.monotonic())
    t = threading.Thread(target=second)
    t.start()
    time.sleep(1.0)
    assert not got, "the second run did not wait"
    assert len(logs) == 1 and f"pid {holder.pid} " in logs[0] and str(course / COURSE_LOCK) in logs[0]
    released = time.monotonic()
    release()
    t.join(30)
    assert got and got[0] >= released
    assert not (course / COURSE_LOCK).exists()         # each holder removes it when done


def test_a_run_goes_on_when_the_holder_dies(course_holder):
    from autograde.course import COURSE_LOCK, course_lock

    course, holder, _ = course_holder
    os.kill(holder.pid, signal.SIGKILL)
    holder.join(10)
    logs = []
    with course_lock(course, log=logs.append):
        assert (course / COURSE_LOCK).read_text().startswith(f"pid {os.getpid()} ")
    assert logs == []


class Waited(Exception):
    pass


def test_grade_class_takes_the_course_lock_before_anything_else(course_holder, tmp_path):
    from autograde import grade
    from autograde.course import COURSE_LOCK

    course, holder, _ = course_holder

    def log(line):
        if line.startswith("waiting for another grading run"):
            raise Waited(line)

    before = sorted(p.name for p in course.iterdir())
    with pytest.raises(Waited, match=f"pid {holder.pid} "):
        grade.grade_class(tmp_path / "no-submissions", course, log=log, progress=False)
    assert sorted(p.name for p in course.iterdir()) == before == [COURSE_LOCK]   # nothing touched


# --- one sandbox's memory, all of it ---------------------------------------------------------------
CGROUP = pytest.mark.skipif(sandbox._memory_hierarchy() is None,
                            reason="no memory cgroup can be made here (not root, or no writable hierarchy)")


def _in_sandbox(tmp_path, code: str, memory: int, **limits):
    limits = {**sandbox.DEFAULT_LIMITS, **limits}
    proc, init = sandbox.start_sandbox(
        lambda fd: sandbox.bwrap_command(tmp_path, [], None if os.geteuid() else 61998, limits=limits, info_fd=fd,
                                         scratch=True),
        [sys.executable, "-c", code], memory=memory, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    group = proc.pusht_cgroup
    try:
        out, _ = proc.communicate(timeout=120)
    finally:
        sandbox.end_sandbox(proc, init)
    return proc.returncode, out, group


@BWRAP
@CGROUP
def test_a_sandbox_is_killed_at_its_memory_cap_however_it_spends_it(tmp_path):
    """256 MiB for the whole sandbox: one process touching 1 GiB, eight processes of 100 MiB each (each
    under its own address-space limit), and 600 MiB written into its tmpfs all end there; a sandbox
    that stays under the cap runs to its end. The cgroup is gone afterwards."""
    cap = 256 << 20
    one = "x = bytearray(1 << 30)\nfor i in range(0, len(x), 4096): x[i] = 1\nprint('SURVIVED')"
    many = ("import os, time\nkids = []\nfor _ in range(8):\n    pid = os.fork()\n    if pid == 0:\n"
            "        x = bytearray(100 << 20)\n        for i in range(0, len(x), 4096): x[i] = 1\n"
            "        time.sleep(5); os._exit(0)\n    kids.append(pid)\n"
            "if all(os.waitpid(k, 0)[1] == 0 for k in kids): print('SURVIVED')")
    fill = ("block = b'x' * (16 << 20)\nwith open('/tmp/fill', 'wb') as f:\n    for _ in range(40):\n"
            "        f.write(block); f.flush()\nprint('SURVIVED')")
    for code in (one, many, fill):
        rc, out, group = _in_sandbox(tmp_path, code, cap, tmp_bytes=2 << 30)
        assert group is not None and "SURVIVED" not in out, (code, rc, out[-300:])
        assert not group.path.exists()
    rc, out, _ = _in_sandbox(tmp_path, "x = bytearray(64 << 20)\nprint('SURVIVED')", cap)
    assert rc == 0 and "SURVIVED" in out, out[-300:]
