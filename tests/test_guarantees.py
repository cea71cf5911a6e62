"""Every grading run states its guarantees (issue 37, item 4): which of the sandbox's protections held,
printed first, at the top of report.csv and in the class report; a run without some of them says what
a student's code could do there.

The record itself is tested from the facts that decide it (fast); then a real run graded as an
unprivileged user (a one-student class, about 15 s): where the tests run as root, the run drops to
``nobody`` with setpriv, in a private mount namespace that makes the interpreter reachable where it
lives in a folder only root may enter."""

import csv
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from autograde import guarantees, sandbox
from autograde.class_report import _guarantees_section
from autograde.guarantees import NAMES, RUN_ROW, Guarantee, record

from handins import ROOT, reward_handin, write_class

ROOT_FACTS = {"host": "h", "root": True, "user": "root", "uid": 0, "sandbox": True, "sandbox_why": "",
              "cgroup": "cgroup v2, /sys/fs/cgroup/x/pusht-grading", "uid_locks": "/run/pusht-grading/uids",
              "uid_locks_why": ""}
USER_FACTS = {**ROOT_FACTS, "root": False, "user": "ta", "uid": 1000, "cgroup": None, "uid_locks": None}


def by_name(rec):
    assert [g.name for g in rec] == list(NAMES)
    return {g.name: g for g in rec}


def test_as_root_with_a_cgroup_everything_holds():
    rec = by_name(record(True, "", ROOT_FACTS))
    assert all(g.held for g in rec.values())
    assert "4 GiB" in rec["memory cgroup"].detail and "/run/pusht-grading/uids" in rec["uid lease"].detail
    assert guarantees.lines(list(rec.values()))[0].startswith("guarantees of this run: all held")


def test_as_an_ordinary_user_three_are_off_and_it_says_what_a_student_could_do():
    rec = by_name(record(True, "", USER_FACTS))
    assert {n for n, g in rec.items() if not g.held} == {"uid lease", "memory cgroup", "locked sockets"}
    assert "your own uid (1000)" in rec["uid lease"].detail
    mem = rec["memory cgroup"].detail
    assert "6 GiB" in mem and "256 processes" in mem and "OOM killer" in mem     # the limits that still hold
    assert "links" in rec["locked sockets"].detail and "reconnect" in rec["locked sockets"].detail
    head = guarantees.lines(list(rec.values()))[0]
    assert "3 of 5 NOT held (uid lease, memory cgroup, locked sockets)" in head


def test_root_without_a_memory_hierarchy_says_so():
    rec = by_name(record(True, "", {**ROOT_FACTS, "cgroup": None}))
    assert not rec["memory cgroup"].held and "memory delegated" in rec["memory cgroup"].detail
    assert rec["uid lease"].held and rec["locked sockets"].held


def test_unconfined_nothing_holds_and_the_student_could_read_the_hidden_tests():
    rec = by_name(record(False, "bubblewrap is not installed", ROOT_FACTS))
    assert not any(g.held for g in rec.values())
    assert "bubblewrap is not installed" in rec["confinement"].detail
    assert "hidden tests" in rec["confinement"].detail and "as root" in rec["uid lease"].detail


def test_several_hosts_hold_a_guarantee_only_where_all_do():
    a, b = record(True, "", ROOT_FACTS), record(True, "", USER_FACTS)
    assert guarantees.merge({"a": a, "b": a}) == a
    merged = by_name(guarantees.merge({"a": a, "b": b}))
    assert merged["confinement"].held and not merged["memory cgroup"].held
    assert merged["memory cgroup"].detail.startswith("on b of 2 hosts:")


def test_the_rows_and_the_section_read_back():
    rec = record(True, "", USER_FACTS) + [Guarantee("x", False, "<script>alert(1)</script>")]
    path = Path(tempfile.mkdtemp()) / "report.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["student_id", "score", "max_score", "notes"])
        w.writerows(guarantees.csv_rows(rec))
        w.writerow(["alice", 4.0, 25.0, "fine"])
    rows = list(csv.DictReader(open(path, newline="")))
    assert [r["student_id"] for r in rows] == [RUN_ROW] * len(rec) + ["alice"]
    assert rows[1]["notes"].startswith("guarantee uid lease: NOT HELD: ")
    shutil.rmtree(path.parent)
    page = _guarantees_section(rec)
    assert "<script>" not in page and "4 of 6 did not hold" in page
    assert _guarantees_section(None) == ""


def test_this_host_is_read_as_it_is():
    facts = guarantees.host_facts()
    assert facts["root"] == (os.geteuid() == 0) and facts["sandbox"] == sandbox.available()[0]
    rec = by_name(guarantees.of_run(facts["sandbox"], facts["sandbox_why"]))
    assert rec["locked sockets"].held == (facts["sandbox"] and facts["root"])


# --- a real run, graded as an unprivileged user ------------------------------------------------------
NOBODY = 65534


def _blocked(paths) -> dict:
    """{folder an unprivileged user cannot enter: the names in it that ``paths`` go through}."""
    out: dict = {}
    for p in paths:
        p = Path(os.path.realpath(p))
        for parent in reversed(p.parents):
            if not os.stat(parent).st_mode & 0o001:
                child = p.relative_to(parent).parts[0]
                out.setdefault(parent, set()).add(child)
                break
    return out


def _as_nobody(cmd: list[str], hold: Path, env: dict) -> list[str]:
    """``cmd`` run as ``nobody``, in a private mount namespace where every folder the interpreter, the
    venv and the repository lie under can be entered (a 0755 tmpfs over a 0700 folder such as /root,
    the needed entries bound back into it). Nothing outside the namespace changes."""
    drop = ["setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups", "env", "-i",
            *(f"{k}={v}" for k, v in env.items())]
    blocked = _blocked([sys.executable, sys.prefix, sys.base_prefix, ROOT])
    if not blocked:
        return drop + cmd
    if any(a != b and a in b.parents for a in blocked for b in blocked):
        pytest.skip(f"nested folders an unprivileged user cannot enter: {sorted(map(str, blocked))}")
    if subprocess.run(["unshare", "--mount", "--", "true"], capture_output=True).returncode:
        pytest.skip(f"{sorted(map(str, blocked))} cannot be entered by an ordinary user, and no mount namespace "
                    f"can be made here to reach them")
    script = []
    for i, (folder, names) in enumerate(sorted(blocked.items())):
        names = {name: (folder / name).is_dir() for name in sorted(names)}
        for name, is_dir in names.items():
            keep = hold / str(i) / name
            make = "mkdir -p" if is_dir else "touch"
            script.append(f"mkdir -p '{keep.parent}' && {make} '{keep}' && mount --bind '{folder / name}' '{keep}'")
        script.append(f"mount -t tmpfs -o mode=755 none '{folder}'")
        for name, is_dir in names.items():
            make = "mkdir" if is_dir else "touch"
            script.append(f"{make} '{folder / name}' && mount --bind '{hold / str(i) / name}' '{folder / name}'")
    script.append('exec "$@"')
    return ["unshare", "--mount", "--propagation", "private", "--", "sh", "-c", " && ".join(script), "sh", *drop, *cmd]


@pytest.mark.slow                  # a grading run, as an ordinary user
def test_a_run_as_an_ordinary_user_prints_and_records_the_guarantees_that_were_off():
    if not sandbox.available()[0]:
        pytest.skip(f"no sandbox here ({sandbox.available()[1]}): such a run is unconfined, tested above")
    root = os.geteuid() == 0
    if root and not (shutil.which("setpriv") and shutil.which("unshare")):
        pytest.skip("setpriv and unshare (util-linux) drop to an ordinary user")
    work = Path(tempfile.mkdtemp(prefix="guarantees-", dir="/tmp"))
    try:
        os.chmod(work, 0o755)
        write_class(work / "class", {"alice": reward_handin()})
        course, home = work / "course", work / "home"
        course.mkdir()
        home.mkdir()
        cmd = [sys.executable, "-m", "autograde.grade", str(work / "class"), "--course", str(course), "--jobs", "1",
               "--timeout", "60"]
        env = {"HOME": str(home), "PATH": os.environ.get("PATH", "/usr/bin:/bin"), "LANG": "C.UTF-8"}
        if root:
            for p in (course, home):
                os.chown(p, NOBODY, NOBODY)
            cmd = _as_nobody(cmd, work / "hold", env)
        proc = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600,
                              env=None if root else {**os.environ, **env})
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        out = proc.stdout.splitlines()
        print("\n".join(out[:6]))
        first = next(i for i, line in enumerate(out) if line.startswith("guarantees of this run:"))
        said = dict(line.strip().split(": ", 2)[:2] for line in out[first + 1:first + 6])
        if said["confinement"] == "held":
            # bubblewrap starts for an ordinary user here (unprivileged user namespaces)
            expected = ["held", "NOT HELD", "NOT HELD", "NOT HELD", "held"]
            assert "3 of 5 NOT held (uid lease, memory cgroup, locked sockets)" in out[first]
        else:       # it does not: nothing is confined, and the run says that first of all
            expected = ["NOT HELD"] * 5
            assert "5 of 5 NOT held" in out[first] and "NOT confined" in out[first + 1]
        assert list(said) == list(NAMES) and list(said.values()) == expected, out[first:first + 6]
        rows = list(csv.DictReader(open(course / "report.csv", newline="")))
        run = [r["notes"] for r in rows if r["student_id"] == RUN_ROW]
        assert [n.split(": ")[1] for n in run] == expected
        assert "OOM killer" in run[2] and ("not root" in run[2] or expected[0] == "NOT HELD")
        alice = next(r for r in rows if r["student_id"] == "alice")
        assert float(alice["score"]) == 4.0, alice          # grading itself worked: the reward's points
        page = (course / "class_report.html").read_text()
        assert '<section id="guarantees">' in page and f"{expected.count('NOT HELD')} of 5 did not hold" in page
    finally:
        shutil.rmtree(work, ignore_errors=True)
