"""The grading worker (``python -m autograde.worker ARGS``) with two timers, for ``bench_student.py``.

    python _worker_timing.py OUT.json -m autograde.worker ARGS

Writes to OUT.json how long the worker took from here to its first notebook (``ready``: imports and
setup; the interpreter's own start is not in it) and each wait in ``sandbox.Zygote.ensure`` for the
student's kernel factory (``factory_wait``). Nothing else about the worker changes.
"""

import json
import runpy
import sys
import time
from pathlib import Path

t0 = time.perf_counter()
out = Path(sys.argv[1])
from autograde import sandbox  # noqa: E402  after t0: its import is part of what `ready` measures

timing = {"ready": None, "factory_wait": []}
_ensure = sandbox.Zygote.ensure


def ensure(self):
    t = time.perf_counter()
    if timing["ready"] is None:
        timing["ready"] = t - t0
    try:
        return _ensure(self)
    finally:
        timing["factory_wait"].append(time.perf_counter() - t)


sandbox.Zygote.ensure = ensure
sys.argv = sys.argv[3:]          # after "-m autograde.worker": ARGS, as the worker reads them
try:
    runpy.run_module("autograde.worker", run_name="__main__", alter_sys=True)
finally:
    if timing["ready"] is None:           # no factory (not confined): all of it was before grading
        timing["ready"] = 0.0
    out.write_text(json.dumps(timing))
