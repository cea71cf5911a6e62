"""Generate the student release (notebooks/) from the instructor notebooks (solutions/) with nbgrader.

    python -m scripts.release           # regenerate notebooks/ (and refresh the Colab install cells)
    python -m scripts.release --check   # CI: fail if notebooks/ is stale or leaks a solution

notebooks/ is never edited by hand. The release is nbgrader's `generate_assignment` output plus one
badge cell at the top (Open in Colab, Binder), with the address taken from course.yaml.

The Colab install cell (the first code cell of every notebook) has one source, INSTALL_CELL below:
this script writes it, rendered with course.yaml's address, into every solutions/*.ipynb, and
`--check` fails when a notebook's cell differs from it. Edit it here, then run `make release` and
`make pair`.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import string
import sys
import tempfile
from pathlib import Path

import nbformat

from autograde.course import COURSE, binder_url, colab_url, install_url, nbgrader
# (one way to run nbgrader, shared with the grader; the course's public addresses, one place)

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS, RELEASE = ROOT / "solutions", ROOT / "notebooks"
MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION", "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS",
           "BEGIN MARK SCHEME", "END MARK SCHEME")


# The Colab install cell of every notebook ($install_url: install_url()). In Colab it installs the
# chapter's package next to Colab's own torch and numpy (pyproject.toml's ranges are loose for that)
# and prints what pip installed (pip's --report). If that ever includes torch or numpy at another
# version than the one Colab came with, it says so, tells the learner to restart the runtime, and
# raises, which stops a "Run all". Elsewhere (a laptop, Binder, CI) it does nothing.
# tests/test_install_cell.py runs both branches with a fake pip; `make colab-check`
# (scripts/colab_check.py) runs it for real on Colab's stack.
INSTALL_CELL = string.Template("""\
# Colab only (elsewhere this does nothing): install this chapter's package, pusht-dreamer, from GitHub,
# next to Colab's own torch and numpy. Should the install ever change those, this cell says so and stops.
import sys

if "google.colab" in sys.modules:
    import json, subprocess, tempfile
    from importlib.metadata import version

    package = "pusht-dreamer @ $install_url"
    print(f"Installing {package}")
    loaded = {name: version(name) for name in ("torch", "numpy")}   # the versions Colab came with
    report = f"{tempfile.gettempdir()}/pusht-install.json"          # pip writes what it installed here
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--report", report, package],
                   check=True)
    with open(report) as f:
        new = {p["metadata"]["name"].lower(): p["metadata"]["version"] for p in json.load(f)["install"]}
    print("Installed:", ", ".join(f"{name} {v}" for name, v in new.items()) or "nothing new")
    changed = [f"{name} {loaded[name]} -> {new[name]}" for name in loaded
               if name in new and new[name] != loaded[name]]
    if changed:
        print(f"The install replaced Colab's {', '.join(changed)}: Python must restart to use it.")
        raise RuntimeError("Restart the runtime (Runtime > Restart session), then run this notebook again.")
    print(f"Colab's torch {loaded['torch']} and numpy {loaded['numpy']} are unchanged.")""")


def install_cell() -> str:
    """The Colab install cell's source, with course.yaml's address."""
    return INSTALL_CELL.substitute(install_url=install_url())


def install_cell_index(cells) -> int | None:
    """Index of a notebook's Colab install cell: its first code cell that mentions google.colab."""
    return next((i for i, c in enumerate(cells)
                 if c["cell_type"] == "code" and "google.colab" in "".join(c["source"])), None)


def badge_cell(name: str):
    text = (f"[![Open In Colab](https://colab.research.google.com/assets/colab-badge.svg)]({colab_url(name)}) "
            f"[![Binder](https://mybinder.org/badge_logo.svg)]({binder_url(name)})")
    cell = nbformat.v4.new_markdown_cell(text, metadata={"release_badges": True})
    cell.id = "release-badges"           # fixed, so a regenerated release is byte-identical
    return cell


def refresh_install_cells() -> list[Path]:
    """Write install_cell() into every solution notebook's Colab install cell."""
    changed = []
    for path in sorted(SOLUTIONS.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        i = install_cell_index(nb.cells)
        if i is not None and nb.cells[i].source != install_cell():
            nb.cells[i].source = install_cell()
            nbformat.write(nb, path)
            changed.append(path)
    return changed


def generate() -> dict[str, str]:
    """Run nbgrader in a scratch course; return {notebook name: release JSON text}."""
    assignment = COURSE["assignment"]
    with tempfile.TemporaryDirectory() as tmp:
        course = Path(tmp)
        (course / "source" / assignment).mkdir(parents=True)
        for path in sorted(SOLUTIONS.glob("*.ipynb")):
            shutil.copy(path, course / "source" / assignment / path.name)
        shutil.copy(ROOT / "autograde" / "nbgrader_config.py", course / "nbgrader_config.py")
        proc = nbgrader(course, "generate_assignment", assignment, "--force")
        if proc.returncode != 0:
            sys.exit(f"nbgrader generate_assignment failed:\n{proc.stdout}\n{proc.stderr}")
        out = {}
        for path in sorted((course / "release" / assignment).glob("*.ipynb")):
            nb = nbformat.read(path, as_version=4)
            nb.cells.insert(0, badge_cell(path.name))
            out[path.name] = nbformat.writes(nb) + "\n"
        return out


README = ROOT / "README.md"
TABLE_START, TABLE_END = "<!-- notebooks:start", "<!-- notebooks:end -->"


def readme_with_table(names) -> str:
    """README.md with its notebook table rendered from course.yaml."""
    rows = ["| notebook | open |", "| --- | --- |"]
    for name in names:
        title = name[:-len(".ipynb")].replace("_", " ")
        rows.append(f"| [{title}](notebooks/{name}) | "
                    f"[![Open In Colab](https://colab.research.google.com/assets/colab-badge.svg)]({colab_url(name)}) "
                    f"[![Binder](https://mybinder.org/badge_logo.svg)]({binder_url(name)}) |")
    return splice(README, TABLE_START, TABLE_END, "\n".join(rows))


def splice(path: Path, start: str, end: str, body: str) -> str:
    """The Markdown file ``path`` with the generated block between the ``start`` marker line and
    ``end`` replaced (the README's notebook table and headline, docs/results.md's tables)."""
    head, rest = path.read_text().split(start, 1)
    marker_line, _ = rest.split("\n", 1)
    _, tail = rest.split(end, 1)
    return head + start + marker_line + "\n" + body + "\n" + end + tail


BLOCK_RE = re.compile(r"### BEGIN (?:SOLUTION|HIDDEN TESTS)\n(.*?)### END (?:SOLUTION|HIDDEN TESTS)", re.S)


def leaks(name: str, text: str) -> list[str]:
    """Solution code, hidden tests or markers of ``name`` that appear in its release text.

    A line counts as a leak only if it is inside a solution or hidden-test block of the source
    and nowhere else in it (a visible test may legitimately share a line with a hidden one).
    """
    found = [m for m in MARKERS if m in text]
    source = nbformat.read(SOLUTIONS / name, as_version=4)
    released = {line.strip() for c in nbformat.reads(text, as_version=4).cells
                for line in c.source.splitlines()}
    public = {line.strip() for c in source.cells for line in BLOCK_RE.sub("", c.source).splitlines()}
    for cell in source.cells:
        for block in BLOCK_RE.findall(cell.source):
            for line in block.splitlines():
                line = line.strip()
                if len(line) > 12 and not line.startswith("#") and line in released - public:
                    found.append(f"solution/hidden line: {line[:60]}")
    return found


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="compare with notebooks/ instead of writing")
    args = p.parse_args(argv)
    if not args.check:
        for path in refresh_install_cells():
            print(f"refreshed the Colab install cell in {path.relative_to(ROOT)}")
    release = generate()
    problems = []
    for name, text in release.items():
        problems += [f"{name}: leaks {what}" for what in leaks(name, text)]
    if args.check:
        committed = {p.name for p in RELEASE.glob("*.ipynb")}
        for name in sorted(committed - set(release)):
            problems.append(f"notebooks/{name} has no source in solutions/")
        for name, text in release.items():
            path = RELEASE / name
            if not path.exists():
                problems.append(f"notebooks/{name} is missing: run `make release`")
            elif path.read_text() != text:
                problems.append(f"notebooks/{name} is stale: run `make release`")
        if README.read_text() != readme_with_table(sorted(release)):
            problems.append("README.md's notebook table is stale: run `make release`")
        for path in SOLUTIONS.glob("*.ipynb"):
            nb = json.loads(path.read_text())
            if any(c.get("outputs") for c in nb["cells"]):
                problems.append(f"solutions/{path.name} has outputs committed: clear them")
            i = install_cell_index(nb["cells"])
            if i is None:
                problems.append(f"solutions/{path.name} has no Colab install cell")
            elif "".join(nb["cells"][i]["source"]) != install_cell():
                problems.append(f"solutions/{path.name}: Colab install cell differs from INSTALL_CELL in "
                                "scripts/release.py (with course.yaml's address): run `make release`")
    if problems:
        print("\n".join(problems))
        return 1
    if not args.check:
        RELEASE.mkdir(exist_ok=True)
        for path in RELEASE.glob("*.ipynb"):
            if path.name not in release:
                path.unlink()
        for name, text in release.items():
            (RELEASE / name).write_text(text)
        README.write_text(readme_with_table(sorted(release)))
        print(f"wrote {len(release)} notebooks to {RELEASE.relative_to(ROOT)}/")
    else:
        print(f"notebooks/ is in sync with solutions/ ({len(release)} notebooks, no leaks)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
