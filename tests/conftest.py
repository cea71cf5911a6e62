"""Shared, expensive fixtures: each chapter notebook is executed once per test session."""

import os
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "solutions").glob("*.ipynb"))


# `slow` (declared in pyproject.toml): what `make test` runs and `make test-fast` leaves out. A test is
# marked here by what it asks for: a fixture below (its own, or one a fixture it asks for asks for),
# or the mark `lane`. Other slow tests (a class graded in the sandbox, a model trained for long)
# carry @pytest.mark.slow themselves.
SLOW_FIXTURES = {
    "executed_notebooks": "executes every chapter notebook",
    "executed_solutions": "executes every chapter notebook",
    "icu": "needs PyICU, built against the system's ICU (tests/test_intake.py)",
    "browser": "needs Chromium and Playwright (tests/test_feedback_browser.py)",
}


@pytest.hookimpl(tryfirst=True)          # before `-m` deselects by marks
def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("lane") or SLOW_FIXTURES.keys() & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def executed_notebooks(tmp_path_factory):
    """Run every instructor notebook headless in smoke mode, in order, sharing one OUT folder as
    `make chapter` does. Returns (folder of executed notebooks, {name: error message or None})."""
    import os

    import papermill as pm
    from scripts.chapter import execute

    if os.environ.get("PUSHT_EXECUTED_NOTEBOOKS"):      # while developing: reuse a folder of executed notebooks
        out = Path(os.environ["PUSHT_EXECUTED_NOTEBOOKS"])
        return out, {p.name: None if (out / p.name).exists() else "not executed" for p in NOTEBOOKS}
    out = tmp_path_factory.mktemp("executed")
    errors = {}
    for path in NOTEBOOKS:
        try:
            execute(path, out, smoke=True)
            errors[path.name] = None
        except pm.PapermillExecutionError as e:
            errors[path.name] = (f"{path.name}: cell {e.cell_index} (execution count {e.exec_count}) "
                                 f"raised {e.ename}: {e.evalue}")
    return out, errors


@pytest.fixture(scope="session")
def executed_solutions(executed_notebooks):
    """The folder of the executed solution notebooks; a test that needs them is skipped where one
    of them fails on its own (tests/test_notebooks.py says why)."""
    executed, errors = executed_notebooks
    if any(errors.values()):
        pytest.skip("a notebook fails on its own; see test_notebooks")
    return executed


def pytest_report_header(config):
    """Say, at the top of every test run, what tests/test_reproduce.py compares seed 0 against here."""
    try:
        import yaml
        from scripts.record_meta import comparison_line

        return comparison_line(yaml.safe_load((ROOT / "meta.yaml").read_text()))
    except Exception as e:  # noqa: BLE001  a broken meta.yaml fails its own tests, not the header
        return f"reproduce: could not compare the platform with meta.yaml ({type(e).__name__}: {e})"


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """The same line at the end, where `pytest -q` (which drops the header) shows it too."""
    if any(Path(str(item.fspath)).name == "test_reproduce.py" for item in terminalreporter.stats.get(
            "passed", []) + terminalreporter.stats.get("failed", [])):
        terminalreporter.write_line(pytest_report_header(config))


def running_as(uids) -> list:
    """(pid, the start of its command line) of every process whose real uid is in ``uids``, read from
    /proc directly: a test that checks the sandbox cleaned up must not ask the code under test."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            status = Path(f"/proc/{pid}/status").read_text()
            if int(status.split("Uid:")[1].split()[0]) in uids:
                found.append((pid, Path(f"/proc/{pid}/cmdline").read_bytes()[:80]))
        except OSError:
            continue
    return found


@pytest.fixture
def processes_of():
    """``running_as`` for a test: ``processes_of({uid, ...})`` -> [(pid, command line start)]."""
    return running_as


def _parent(pid) -> int:
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return 0


def _descends_from(pid, ancestor: int) -> bool:
    """Whether process ``pid`` is ``ancestor`` or runs under it (its parents, read from /proc)."""
    pid, seen = int(pid), set()
    while pid > 1 and pid not in seen:
        if pid == ancestor:
            return True
        seen.add(pid)
        pid = _parent(pid)
    return False


def leftovers_of(uids, settle: float = 10.0) -> list:
    """(pid, the start of its command line) of every process left running as one of ``uids``, the
    uids a grading run of this test leased and has given back (``sandbox.recording_leases``).

    Another grading run on this host (a second section, a regrade) may lease the same uids once
    this run is done, and its kernels then rightly run as them; those are not this run's
    leftovers. So, uid by uid, as ``allocate_uid`` decides what a uid's processes are: where no
    grading task holds the uid's lock (this check takes it, so none can lease it meanwhile),
    every process of the uid is a leftover; where a task holds it, every process of the uid that
    does not run under that task's process (the pid its lock file names) is one. A process is
    reported only if it is still there after ``settle`` seconds of looking again (the other run's
    own clean-up may orphan its processes for a moment before it kills them)."""
    import fcntl

    from autograde import sandbox

    folder = sandbox.uid_lock_dir()
    deadline = time.monotonic() + settle
    while True:
        found = []
        for uid in sorted(set(uids)):
            fd = os.open(folder / f"{uid}.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    holder = None                     # nobody's now: nothing may run as it
                except BlockingIOError:
                    text = os.pread(fd, 32, 0).decode(errors="replace").strip()
                    holder = int(text) if text.isdigit() else 0     # 0: its holder has not said who yet
                found += [(pid, cmd) for pid, cmd in running_as({uid})
                          if holder is None or not _descends_from(pid, holder)]
            finally:
                os.close(fd)                          # drops the lock if this check took it
        if not found or time.monotonic() > deadline:
            return found
        time.sleep(0.25)


@pytest.fixture
def leftovers():
    """``leftovers_of`` for a test: ``leftovers(uids)`` -> [(pid, command line start)]."""
    return leftovers_of
