"""House rules that keep the code readable by its next editor (issue 40, item 7).

A module past ``BUDGET`` lines is one nobody reads end to end: each Python file tracked in the
folders below stays within it, unless ``OVERSIZED`` names it with the reason it is allowed to be
(today: what it does that should be split out). Splitting a file under the budget takes its entry
out too: a stale entry fails here, so the list only ever says what is true.
"""

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUDGET = 600                       # lines per file
FOLDERS = ("pusht", "autograde", "chapter_site", "scripts", "benchmarks")

# path -> why it is over the budget for now. Add a file here only with a reason a reviewer accepts.
OVERSIZED = {
    "autograde/intake.py": "to be split: reading the download (zip limits, names) and deciding whose file it is",
    "autograde/classes/variants.py": "a test class: forty-odd honest rewrites of the graded functions, each a short "
                                     "source template; long by nature, read one variant at a time",
    "autograde/sandbox.py": "to be split: the bubblewrap command, uid leases, cgroups and the kernel spec",
    "autograde/gradescope.py": "to be split: building the bundle, and grading one hand-in inside Gradescope",
    "autograde/class_report.py": "to be split: the class's figures, and the HTML page around them",
    "autograde/delegation.py": "one analysis (does the graded function reach the package's own code?), its "
                               "cases read together; split when it grows",
}


def tracked_python_files() -> list[str]:
    """The .py files under FOLDERS that git tracks (every file there where this is not a clone)."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", *(f"{d}/*.py" for d in FOLDERS)], cwd=ROOT,
                             capture_output=True, check=True, text=True).stdout
        files = [f for f in out.split("\0") if f]
    except (OSError, subprocess.CalledProcessError):
        files = []
    if not files:
        files = [p.relative_to(ROOT).as_posix() for d in FOLDERS for p in (ROOT / d).rglob("*.py")]
    return sorted(files)


def line_count(path: str) -> int:
    with open(ROOT / path, "rb") as f:
        return sum(1 for _ in f)


def over_budget(budget: int = BUDGET) -> dict[str, int]:
    return {f: n for f in tracked_python_files() if (ROOT / f).exists() and (n := line_count(f)) > budget}


def test_the_folders_hold_python_files():
    """The check below checks something: it finds this file's neighbours."""
    files = tracked_python_files()
    assert "autograde/grade.py" in files and any(f.startswith("pusht/") for f in files)


def test_no_python_file_grows_past_the_budget_unless_listed_with_a_reason():
    big = over_budget()
    unlisted = {f: n for f, n in big.items() if f not in OVERSIZED}
    assert not unlisted, (
        f"over {BUDGET} lines: {unlisted}. Split the module (a newcomer should find their room from the "
        f"file names), or add it to OVERSIZED in {Path(__file__).name} with the reason it must stay whole")


def test_every_listed_file_is_still_over_the_budget():
    stale = sorted(set(OVERSIZED) - set(over_budget()))
    assert not stale, f"within {BUDGET} lines now (or gone): take {stale} out of OVERSIZED"


def test_every_listed_file_says_why():
    assert all(len(reason.split()) >= 3 for reason in OVERSIZED.values())
