"""The wall-clock table: one row per hardware tier, rendered from ``benchmarks/wallclock.csv``.

A tier shows its latest measured figure for one seed of the chapter's pipeline (the default config,
a fresh process, median of the runs ``make bench`` made), with the machine, the date and the
commit it was measured on. A tier with no such row says "pending": a figure is never invented.
"""

from __future__ import annotations

import csv
from html import escape
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CSV = ROOT / "benchmarks" / "wallclock.csv"
FIGURE = "pipeline_cold_wall"      # one seed, default config, fresh process (benchmarks/bench.py)

# The tiers the chapter is meant for, in the order the page lists them. ``make bench`` writes
# tier "cpu"; a row with any other tier name in the csv is shown too, after these.
TIERS = {
    "cpu": "a CPU: a laptop, Binder or this course's CI host",
    "t4": "Colab's free GPU (NVIDIA T4)",
    "mps": "Apple silicon (PyTorch's MPS backend)",
    "4090": "a desktop GPU (NVIDIA RTX 4090)",
}


def latest(path: Path = CSV, figure: str = FIGURE) -> dict[str, dict]:
    """Tier -> its most recent row for ``figure``."""
    rows: dict[str, dict] = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["figure"] != figure:
                continue
            if row["tier"] not in rows or row["measured_at"] > rows[row["tier"]]["measured_at"]:
                rows[row["tier"]] = row
    return rows


def table_html(path: Path = CSV) -> str:
    """The table as HTML (static: no script)."""
    rows = latest(path)
    tiers = list(TIERS) + sorted(t for t in rows if t not in TIERS)
    body = []
    for tier in tiers:
        what = escape(TIERS.get(tier, tier))
        r = rows.get(tier)
        if r is None:
            body.append(f'<tr class="pending" data-tier="{escape(tier)}"><th scope="row">{escape(tier)}</th>'
                        f"<td>{what}</td><td>pending</td><td>not yet measured</td></tr>")
            continue
        seconds = float(r["value"])
        commit = f", commit {escape(r['commit'])}" if r.get("commit") else ""
        body.append(f'<tr class="measured" data-tier="{escape(tier)}"><th scope="row">{escape(tier)}</th>'
                    f"<td>{what}</td><td>{seconds:.1f} s ({seconds / 60:.2f} min)</td>"
                    f"<td>{escape(r['machine'])}; {escape(r['measured_at'][:10])}{commit}; "
                    f"{escape(r['notes'])}</td></tr>")
    return ('<table class="wallclock"><caption>One seed of the chapter\'s pipeline at the default config, '
            f"fresh process (<code>{FIGURE}</code> in <code>benchmarks/wallclock.csv</code>, written by "
            "<code>make bench</code>)</caption><thead><tr><th>tier</th><th>hardware</th>"
            "<th>wall-clock</th><th>measured on</th></tr></thead><tbody>" + "".join(body) + "</tbody></table>")
