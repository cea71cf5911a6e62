"""The grading worker (``grade.py --worker ...``) with two timers, for ``bench_student.py``.

    python _worker_timing.py OUT.json grade.py --worker ARGS

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
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "autograde"))
import sandbox  # noqa: E402  (the module grade.py imports: the same object, patched once here)

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
sys.argv = sys.argv[2:]
try:
    runpy.run_path(sys.argv[0], run_name="__main__")
finally:
    if timing["ready"] is None:           # no factory (not confined): all of it was before grading
        timing["ready"] = 0.0
    out.write_text(json.dumps(timing))
