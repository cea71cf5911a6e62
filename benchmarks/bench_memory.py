"""Peak kernel memory of each chapter notebook at the default config, against Binder's 2 GB.

    python -m benchmarks.bench_memory [--out DIR] [--reuse DIR]

Runs the solution notebooks as `make chapter` does (scripts/chapter.py, default config, a
fresh output folder, so nothing is cached and every model is trained), which measures each
notebook's kernel while it runs (VmHWM, its resident-memory high-water mark, from /proc) and writes
<out>/memory.json. With --reuse DIR it reads the memory.json of a chapter run already done instead,
and says so in the record. Writes benchmarks/notebook_memory.txt with the host it was measured on.
Exits 1 if a notebook's kernel went over 1.5 GB (1500 MB, MB = 10**6 bytes) or a notebook failed;
where memory cannot be measured (no /proc) the record says so and it exits 0.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
from importlib import metadata
from pathlib import Path

from scripts import chapter

ROOT = Path(__file__).resolve().parents[1]

RECORD = ROOT / "benchmarks" / "notebook_memory.txt"


def host() -> list[str]:
    from pusht.host import cores, cpu_model

    cpu, usable = cpu_model(), cores()
    ram = ""
    try:
        kb = int(Path("/proc/meminfo").read_text().split("MemTotal:")[1].split()[0])
        ram = f", {kb * 1024 / 1e9:.0f} GB RAM"
    except (OSError, IndexError, ValueError):
        pass
    versions = []
    for pkg in ("torch", "numpy", "ipykernel", "papermill"):
        try:
            versions.append(f"{pkg} {metadata.version(pkg)}")
        except metadata.PackageNotFoundError:
            versions.append(f"{pkg} not installed")
    return [f"host: {cpu}, {os.cpu_count()} cores ({usable} usable){ram}, {sys.platform}, "
            f"python {platform.python_version()}", "versions: " + ", ".join(versions)]


def commit() -> str:
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + (" with uncommitted changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown commit"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, help="where the chapter runs (default: a fresh temporary folder)")
    p.add_argument("--reuse", type=Path, help="read DIR/memory.json of a chapter run instead of running")
    p.add_argument("--record", type=Path, default=RECORD)
    args = p.parse_args(argv)
    today = datetime.date.today().isoformat()
    if args.reuse:
        out, rc = args.reuse.resolve(), 0
        when = datetime.datetime.fromtimestamp((out / "memory.json").stat().st_mtime)
        source = (f"reused {out}/memory.json of `scripts/chapter.py --out {out}` "
                  f"(written {when:%Y-%m-%d %H:%M}); the chapter was not re-run by this script")
    else:
        out = (args.out or Path(tempfile.mkdtemp(prefix="bench-memory-"))).resolve()
        rc = chapter.main(["--out", str(out)])
        source = f"`scripts/chapter.py --out {out}` run by this script, from an empty folder"
    data = json.loads((out / "memory.json").read_text())
    records, limit = data["notebooks"], data["limit_mb"]
    expected = [nb.name for nb in sorted((ROOT / "solutions").glob("*.ipynb"))]
    lines = [f"# benchmarks/bench_memory.py, {today}, commit {commit()}, {data['config']} config",
             f"# {source}", *(f"# {h}" for h in host()),
             f"# peak resident memory of each notebook's kernel, {data['unit']}; limit {limit:.0f} MB "
             f"(Binder gives 2 GB)", f"# how: {data['method']}", chapter.memory_table(records)]
    problems = []
    if data["config"] != "default":
        problems.append(f"the run used the {data['config']} config, not the default one")
    for name in expected:
        r = records.get(name)
        if r is None:
            problems.append(f"{name} did not run (an earlier notebook failed)")
        elif not r["status"].startswith("ok"):
            problems.append(f"{name} {r['status']}")
        elif r.get("measured") and r["peak_rss_mb"] > limit:
            problems.append(f"{name}: kernel peak {r['peak_rss_mb']:.0f} MB is over {limit:.0f} MB")
    unmeasured = [n for n, r in records.items() if not r.get("measured")]
    if unmeasured:
        lines.append(f"not measured on this platform: {', '.join(unmeasured)} "
                     f"({records[unmeasured[0]].get('reason')})")
    measured = [r["peak_rss_mb"] for r in records.values() if r.get("measured")]
    if measured and not problems:
        lines.append(f"all {len(measured)} notebooks under {limit:.0f} MB; largest {max(measured):.0f} MB")
    lines += [f"PROBLEM: {p}" for p in problems]
    text = "\n".join(lines) + "\n"
    args.record.write_text(text)
    print(text, end="")
    print(f"written to {args.record}")
    if problems or rc:
        print("FAILED: " + "; ".join(problems or ["the chapter run failed"]), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
