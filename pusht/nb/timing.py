"""How long each notebook takes, measured: the line a notebook prints under its title.

``make times`` (``scripts/chapter.py --record-times``) runs the six notebooks in order at the
default config and writes ``times.json`` beside this module: per notebook, the seconds the whole
notebook took and the seconds of each predict-then-run experiment cell (papermill's per-cell
``duration``), with the host, the date and the commit. Nothing here is typed in; a notebook whose
times were never recorded says so.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

TIMES = Path(__file__).with_name("times.json")
EXERCISE = re.compile(r"""run_exercise\(\s*["'](ex\d+)["']""")


def _minutes(seconds: float) -> str:
    if seconds < 60:
        return f"{max(1, round(seconds / 5) * 5):.0f} s"
    return f"{seconds / 60:.0f} min" if seconds >= 570 else f"{seconds / 60:.1f} min"


def measure(executed_notebook) -> dict:
    """{"seconds": whole notebook, "exercises": {"ex1": seconds of its experiment cell}} from an
    executed notebook (an ``nbformat`` node) that papermill ran."""
    total, exercises = 0.0, {}
    for cell in executed_notebook.cells:
        d = cell.get("metadata", {}).get("papermill", {}).get("duration")
        if d is None:
            continue
        total += float(d)
        m = EXERCISE.search(cell.source) if cell.cell_type == "code" else None
        if m:
            exercises[m.group(1)] = round(float(d), 1)
    return {"seconds": round(total, 1), "exercises": exercises}


def estimate(notebook: str, path: Path = TIMES) -> str:
    """The time line for ``notebook`` ("04_imagination_gap"), in markdown."""
    try:
        data = json.loads(path.read_text())
        rec = data["notebooks"][notebook]
    except (OSError, ValueError, KeyError):
        return "*Time: not measured yet for this notebook (`make times` records it).*"
    ex = "".join(f"; Exercise {k[2:]}'s experiment cell about {_minutes(v)}" for k, v in rec["exercises"].items())
    return (f"**Time:** about **{_minutes(rec['seconds'])}** of computing to run top to bottom at the default "
            f"config{ex}, measured on {data['host']} ({data['measured_at'][:10]}, commit {data['commit']}), "
            "with nothing else running on it, and running the notebooks in order so that each reuses the models "
            "the earlier ones trained and cached. That is a quiet machine's figure. On a busy or shared one (a "
            "class server, a laptop compiling something, a free Colab runtime on shared hardware) it takes "
            "longer, and can take many times as long: the training here is arithmetic on the CPU, every other "
            "program that wants those cores takes its share of them, and the notebooks that train several runs "
            "side by side in worker processes (05, and 06 most of all) lose far more than their share when the "
            "cores are already busy. More cores train seeds side "
            "by side and go faster; `SMOKE = True` runs in seconds. Your own reading and writing time comes on "
            "top.")


def here() -> str:
    """"on this machine (Intel Xeon, 2 cores)": where a time printed in a notebook was measured, since a
    wall-clock time means nothing without its machine (and what else was running on it)."""
    from ..host import cores, cpu_model

    cpu = cpu_model()
    n = cores()
    return f"on this machine ({cpu}, {n} core{'s' if n != 1 else ''}, with whatever else runs on it)"


def time_note(notebook: str):
    """The time line as a displayable Markdown object (a notebook cell's last expression)."""
    from IPython.display import Markdown

    return Markdown(estimate(notebook))
