"""Where one student's grading time goes, with the batch's stages shared, as a table.

    python -m benchmarks.bench_student [--executed DIR] [--repeats 3]

Grades a class of SHARE_FROM correct students once (``grade.grade_class``, so the stages are shared
as in a real batch), then grades one of them again ``--repeats`` times with ``task.grade_task``
alone, one at a time, with the batch's shared stages. Each time, the grading worker runs under a
small timing shim (``benchmarks/_worker_timing.py``: the same ``python -m autograde.worker``, with timers
around its imports and its waits for the kernel factory). It reads each notebook's cell times from
the autograded notebook (nbclient records when every cell started and ended). Then it times
nbgrader's feedback for one student in a warm process. Prints one table of medians. The figures
belong to this host.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
import zipfile
from datetime import datetime
from pathlib import Path

from autograde import feedback, grade, sandbox, stages, task
from autograde.course import course_bundle

from benchmarks.bench import host_description
from benchmarks.bench_class import class_zip
from benchmarks.bench_grading import command_line, executed_notebooks

ROOT = Path(__file__).resolve().parents[1]


SHIM = Path(__file__).resolve().parent / "_worker_timing.py"


def _cells_seconds(notebook_json: str) -> float:
    """First cell's start to last cell's end, from nbclient's execution metadata."""
    def ts(s):
        return datetime.fromisoformat(s.replace("Z", "+00:00")).timestamp()
    nb = json.loads(notebook_json)
    times = [ts(c["metadata"]["execution"][k]) for c in nb["cells"] if "execution" in c.get("metadata", {})
             for k in ("iopub.execute_input", "shell.execute_reply") if k in c["metadata"]["execution"]]
    return max(times) - min(times) if times else 0.0


def graded_once(course: Path, zip_path: Path, student: str, timing_file: Path) -> dict:
    """grade_task for ``student`` with the worker under the timing shim; its phases in seconds."""
    with zipfile.ZipFile(zip_path) as zf:
        notebooks = {n[len(student) + 1:]: zf.read(n).decode() for n in zf.namelist() if n.startswith(student + "_")}
    popen = subprocess.Popen

    class Timed(popen):                      # only the worker's command line changes
        def __init__(self, cmd, *a, **k):
            if isinstance(cmd, list) and "autograde.worker" in cmd:
                cmd = [cmd[0], str(SHIM), str(timing_file)] + cmd[1:]
            super().__init__(cmd, *a, **k)

    task.subprocess.Popen = Timed
    try:
        t = time.perf_counter()
        out = task.grade_task(course_bundle(course), student, notebooks, 120, sandbox.available()[0],
                               dict(sandbox.DEFAULT_LIMITS), str(course / stages.SHARED_DIR))
        total = time.perf_counter() - t
    finally:
        task.subprocess.Popen = popen
    shim = json.loads(timing_file.read_text())
    autograde = sum(e.get("seconds", 0.0) for e in out["results"].values())
    cells = sum(_cells_seconds(text) for text in out["autograded"].values())
    return {"grade_task": total, "worker: imports and setup, to its first notebook": shim["ready"],
            "waiting for the kernel factory": sum(shim["factory_wait"]), "six nbgrader autogrades": autograde,
            "  their cells (first to last)": cells, "  the rest: kernel starts, nbgrader's passes": autograde - cells,
            "everything else (results, cleanup, judging)": total - shim["ready"] - sum(shim["factory_wait"]) - autograde}


def main(argv=None) -> int:
    args, tmp = command_line(__doc__, argv, 3, "bench-student-")
    zip_path = tmp / "class.zip"
    student = class_zip(executed_notebooks(args.executed, tmp), 1, zip_path)[0]    # a correct hand-in
    one = tmp / "correct.zip"
    with zipfile.ZipFile(zip_path) as src, zipfile.ZipFile(one, "w") as zf:
        for i in range(stages.SHARE_FROM):    # enough correct students for the batch to share its stages
            for name in src.namelist():
                zf.writestr(name.replace(student, f"{student}-{i}", 1) if i else name, src.read(name))
    course = tmp / "course"
    grade.grade_class(one, course, log=lambda *a: None, progress=False)
    if not (course / stages.SHARED_DIR).is_dir():
        print("the batch shared no stages; nothing to measure", file=sys.stderr)
        return 1
    print(f"host: {host_description()}; one correct student, stages shared, graded alone {args.repeats} times",
          flush=True)
    rows = [graded_once(course, one, student, tmp / f"timing{i}.json") for i in range(args.repeats)]
    t = time.perf_counter()
    feedback._feedback_for(course, [student])                         # a cold process: nbgrader's imports
    cold = time.perf_counter() - t
    warm = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        feedback._feedback_for(course, [student])
        warm.append(time.perf_counter() - t)
    for name in rows[0]:
        values = [r[name] for r in rows]
        print(f"  {name:48s} {statistics.median(values):6.2f} s   ({', '.join(f'{v:.2f}' for v in values)})")
    print(f"  {'feedback, one student, warm process':48s} {statistics.median(warm):6.2f} s   "
          f"(first in this process {cold:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
