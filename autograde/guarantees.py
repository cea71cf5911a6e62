"""What a grading run guarantees, said at its start: which of the sandbox's protections hold here.

    record = guarantees.of_run(confine, why, limits, scheduler)     # grade_class calls it first
    for line in guarantees.lines(record): log(line)

docs/grader.md ("Student code is treated as hostile") lists what confines a student's code. Not all of
it holds everywhere: without bubblewrap nothing is confined; graded as an ordinary user, kernels
run as that user's uid in a user namespace, the sockets folder is never handed back to root and no
memory cgroup is made. A run used to say only the first. Now each run works out, for the host that
grades (every Dask worker's, where it grades on Dask), which of these hold:

* ``confinement``: each kernel and probe in a bubblewrap sandbox (``sandbox.available``);
* ``uid lease``: a throw-away student uid leased for the task alone (``sandbox.allocate_uid``: root);
* ``memory cgroup``: one sandbox's memory capped as a whole (``sandbox.MemoryCgroup``: root and a
  writable memory hierarchy);
* ``locked sockets``: the kernel's sockets folder root's once the grader has connected
  (``sandbox.lock_sockets``: root);
* ``tmpfs caps``: the kernel writes only into size-capped tmpfs of its own (bwrap ``--size``).

The record (``Guarantee``: name, held, detail) is printed at the start of the run, one line each,
written at the top of ``report.csv`` (rows whose student_id is ``RUN_ROW``) and shown near the top
of the class report. A guarantee that does not hold says why, and plainly what a student's code
could do here because of it.
"""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass

from . import sandbox

NAMES = ("confinement", "uid lease", "memory cgroup", "locked sockets", "tmpfs caps")
RUN_ROW = "(this run)"       # report.csv's student_id of the rows that describe the run, not a student


@dataclass(frozen=True)
class Guarantee:
    name: str          # one of NAMES
    held: bool
    detail: str        # held: what holds; else why not, and what a student's code could do without it

    def line(self) -> str:
        return f"{self.name}: {'held' if self.held else 'NOT HELD'}: {self.detail}"


def _size(n) -> str:
    n = int(n)
    return f"{n / (1 << 30):g} GiB" if n >= 1 << 30 else f"{n / (1 << 20):g} MiB"


def host_facts() -> dict:
    """What decides the guarantees on this host (runs here, or on a Dask worker): who grades,
    whether a sandbox starts, and (root only) the memory cgroup hierarchy and the uid lock folder."""
    import pwd

    euid = os.geteuid()
    try:
        user = pwd.getpwuid(euid).pw_name
    except KeyError:
        user = f"uid {euid}"
    ok, why = sandbox.available()
    facts = {"host": socket.gethostname(), "root": euid == 0, "user": user, "uid": euid,
             "sandbox": bool(ok), "sandbox_why": why, "cgroup": None, "uid_locks": None, "uid_locks_why": ""}
    if euid == 0:
        found = sandbox._memory_hierarchy()
        if found is not None:
            facts["cgroup"] = f"cgroup {found[1]}, {found[0]}"
        try:
            facts["uid_locks"] = str(sandbox.uid_lock_dir())
        except (OSError, RuntimeError) as e:
            facts["uid_locks_why"] = str(e)
    return facts


def record(confine: bool, why: str, facts: dict, limits: dict | None = None) -> list[Guarantee]:
    """The guarantees of a run that grades with ``confine`` (``why``: why not, where it does not)
    under ``limits`` on a host with ``facts`` (``host_facts``). Pure: the unit tests feed it facts."""
    lim = {**sandbox.DEFAULT_LIMITS, **(limits or {})}
    you = f"as you ({facts['user']})" if not facts["root"] else "as root"
    per_process = (f"{_size(lim['memory_bytes'])} of address space in each of up to {lim['processes']} "
                   f"processes, plus its working folder and /tmp ({_size(lim['work_bytes'])} and "
                   f"{_size(lim['tmp_bytes'])} of RAM)")
    if not confine:
        why = why or "confinement switched off"
        return [
            Guarantee("confinement", False,
                      f"student code is NOT confined ({why}): it runs {you} with the network, every file you can "
                      f"read or write (this course's gradebook, the solutions and hidden tests, other students' "
                      f"notebooks) and no limit but the cell timeout; a student could read the hidden tests, "
                      f"change files of this course and leave processes running after grading"),
            Guarantee("uid lease", False, f"no uid is switched: student code runs {you}"),
            Guarantee("memory cgroup", False,
                      "nothing caps the memory of student code: it can use this host's memory until the OOM "
                      "killer steps in, which may kill another student's kernel or the grader"),
            Guarantee("locked sockets", False,
                      f"no folder is kept from the kernel: it runs {you} and can write everything the grader can"),
            Guarantee("tmpfs caps", False,
                      "no private tmpfs: student code writes wherever you can, on this host's disk, up to the "
                      "free space"),
        ]
    out = [Guarantee("confinement", True,
                     f"each kernel and probe runs in a bubblewrap sandbox: no network, its own PID, IPC and UTS "
                     f"namespaces, the system, the venv and the package read-only, nothing of the course; "
                     f"per process {_size(lim['memory_bytes'])} of address space, {lim['cpu_seconds']} s of CPU, "
                     f"files up to {_size(lim['file_bytes'])}; {lim['processes']} processes; "
                     f"{lim['wall_seconds']} s per notebook")]
    if facts["root"] and facts["uid_locks"]:
        out.append(Guarantee("uid lease", True,
                             f"each task runs its student's kernels as a uid of {sandbox.STUDENT_UIDS.start}-"
                             f"{sandbox.STUDENT_UIDS.stop - 1} leased for that task alone on this host (lock files "
                             f"in {facts['uid_locks']}), with no rights; whatever still runs as it when the task "
                             f"ends is killed"))
    else:
        reason = (f"grading runs as {facts['user']}, not root" if not facts["root"] else
                  f"no uid lock folder: {facts['uid_locks_why']}")
        out.append(Guarantee("uid lease", False,
                             f"{reason}: kernels run as your own uid ({facts['uid']}) inside a user namespace, not "
                             f"as a throw-away one. The sandboxes still keep students apart, but a process that "
                             f"got out of its sandbox (a flaw in bubblewrap or the kernel) would have all your "
                             f"rights, and no sweep by uid ends it after its task"))
    if facts["cgroup"]:
        out.append(Guarantee("memory cgroup", True,
                             f"all of one sandbox's memory, its processes and tmpfs pages together, is capped at "
                             f"{_size(lim['sandbox_bytes'])} ({facts['cgroup']}): past it the kernel's OOM killer "
                             f"ends a process of that sandbox, never one outside"))
    else:
        reason = (f"grading runs as {facts['user']}, not root" if not facts["root"] else
                  "no memory cgroup can be made here (cgroup v1's memory controller, or v2 with memory delegated)")
        out.append(Guarantee("memory cgroup", False,
                             f"{reason}: only the per-process limits hold, so one student's sandbox can use "
                             f"{per_process}: this host's memory can run out, and the OOM killer may then end "
                             f"another student's kernel or the grader instead"))
    if facts["root"]:
        out.append(Guarantee("locked sockets", True,
                             "once the grader has connected to a kernel's sockets, before any cell runs, their "
                             "folder is root's and read-only to the kernel: it cannot put a link where the "
                             "grader's ZeroMQ would reconnect"))
    else:
        out.append(Guarantee("locked sockets", False,
                             f"grading runs as {facts['user']}, not root: a kernel's sockets folder stays writable "
                             f"to it while its notebook runs, so it can replace its sockets with links, and a "
                             f"reconnecting grader (ZeroMQ) follows them, with your rights, to another Unix socket "
                             f"on this host"))
    out.append(Guarantee("tmpfs caps", True,
                         f"a kernel writes only into its working folder and /tmp, tmpfs of its own in RAM of "
                         f"{_size(lim['work_bytes'])} and {_size(lim['tmp_bytes'])}; files up to "
                         f"{_size(lim['file_bytes'])}; nothing reaches this host's disk"))
    return out


def merge(records: dict) -> list[Guarantee]:
    """One record for several hosts ({host: record}, e.g. every Dask worker): a guarantee holds only
    where it holds on all of them; where hosts differ, the record says which ones lack it."""
    recs = list(records.values())
    if not recs:
        return []
    if all(r == recs[0] for r in recs):
        return recs[0]
    out = []
    for i, name in enumerate(NAMES):
        lacking = sorted(h for h, r in records.items() if not r[i].held)
        if not lacking:
            out.append(recs[0][i])
            continue
        first = records[lacking[0]][i]
        out.append(Guarantee(name, False, f"on {', '.join(lacking)} of {len(records)} hosts: {first.detail}"))
    return out


def of_run(confine: bool, why: str = "", limits: dict | None = None, scheduler=None) -> list[Guarantee]:
    """The guarantees of a run that grades with ``confine`` here, or on the Dask ``scheduler``'s
    workers (an address or a ``distributed.Client``): then each worker's host is asked."""
    if scheduler is None:
        return record(confine, why, host_facts(), limits)
    from distributed import Client

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        facts = client.run(host_facts)
    finally:
        if not isinstance(scheduler, Client):
            client.close()
    by_host = {}
    for f in facts.values():
        by_host.setdefault(f["host"], f)
    return merge({h: record(confine, why, f, limits) for h, f in by_host.items()})


def lines(record: list[Guarantee]) -> list[str]:
    """What the run prints first: a heading, then one plain line per guarantee."""
    off = [g.name for g in record if not g.held]
    head = ("guarantees of this run: " + ("all held" if not off else f"{len(off)} of {len(record)} NOT held "
                                          f"({', '.join(off)})")
            + " (docs/grader.md: 'Student code is treated as hostile')")
    return [head] + [f"  {g.line()}" for g in record]


def csv_rows(record: list[Guarantee]) -> list[list[str]]:
    """report.csv's rows for the run (student_id ``RUN_ROW``, score and max_score empty)."""
    return [[RUN_ROW, "", "", f"guarantee {g.line()}"] for g in record]
