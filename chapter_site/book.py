"""Assemble the chapter site's source from a ``make chapter`` run and build it with Jupyter Book 1.

    python -m chapter_site --run runs/chapter --out runs/site       # make site
    python -m chapter_site --run runs/chapter-smoke --out runs/site-smoke

The source folder (``<out>/src``) gets ``book/``'s files, the generated landing page
(``index.md``), the reading list and one page per executed notebook. A notebook page shows the
*student* release's code for every graded cell (the instructor's solutions stay unpublished) above
the outputs the instructor's run produced, and folds away (JavaScript on) the outputs that would
answer a predict-then-run exercise before the reader has predicted. Jupyter Book 1.x (Sphinx) then
builds ``<out>/html`` offline: nothing is fetched at build time, and the pages load nothing from
another host.
"""

from __future__ import annotations

import argparse
import ast
import re
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import yaml

from . import landing, provenance

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
RELEASE = ROOT / "notebooks"
JUPYTER_BOOK = "import sys; from jupyter_book.cli.main import main; sys.argv[0] = 'jupyter-book'; main()"
REVEALS = ("run_exercise(", "reconcile(")      # a cell that runs an exercise or reconciles it
# A stylesheet an HTML output pulls from another host: matplotlib's animation player links
# Font Awesome 4 from a CDN. The site's theme ships Font Awesome itself, and the site loads nothing
# from elsewhere, so such a link is dropped from the published page (the notebook keeps it).
# Plumbing (issue 42, item 4). A notebook page shows the lesson: the Colab install cell, which does
# nothing anywhere but Colab, is left out of the page (``remove-cell``; the page opens with a Colab
# link instead), and a cell that only calls the notebook's helpers to show something (a sentence
# from the package, the package's code, a self-check's question, an exercise's reconciliation)
# keeps its output with its code folded (``hide-input``: a <details>, which opens with JavaScript
# off too). A cell with any other statement shows its code: that is the code being taught.
HELPERS = frozenset({"display", "reconcile", "time_note", "ask"})
FOREIGN_STYLESHEET = re.compile(r"<link[^>]*href=[\"']https?://[^>]*>", re.IGNORECASE)


def _grade_id(cell) -> str | None:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


def is_install_cell(cell) -> bool:
    """The Colab install cell: a code cell that mentions ``google.colab`` (scripts/release.py writes it)."""
    return cell.cell_type == "code" and "google.colab" in cell.source


def is_helper_cell(cell) -> bool:
    """A code cell whose every statement is an import or a call of one of :data:`HELPERS`
    (``display(Markdown(nb04.exploitation_text(...)))``, ``reconcile("ex1", ...)``)."""
    if cell.cell_type != "code" or not cell.source.strip():
        return False
    try:
        body = ast.parse(cell.source).body
    except SyntaxError:            # IPython magics: not a helper call
        return False
    calls = [s for s in body if not isinstance(s, (ast.Import, ast.ImportFrom))]
    return bool(calls) and all(isinstance(s, ast.Expr) and isinstance(s.value, ast.Call)
                               and isinstance(s.value.func, ast.Name) and s.value.func.id in HELPERS
                               for s in calls)


def _tag(cell, tag: str) -> None:
    tags = cell.metadata.setdefault("tags", [])
    if tag not in tags:
        tags.append(tag)


def publishable(executed: Path, release: Path) -> nbformat.NotebookNode:
    """The executed instructor notebook with each graded cell's source replaced by the student
    release's (matched by nbgrader's ``grade_id``), a Colab link on top, the reveals folded, and
    papermill's injected parameters (the run's own paths) left out; the install cell is removed and
    the helper cells' code folded (:data:`HELPERS`)."""
    nb = nbformat.read(executed, as_version=4)
    student = {_grade_id(c): c for c in nbformat.read(release, as_version=4).cells if _grade_id(c)}
    cells = []
    for cell in nb.cells:
        if "injected-parameters" in cell.get("metadata", {}).get("tags", []):
            continue                  # papermill's cell: the run's own paths, not the learner's notebook
        if is_install_cell(cell):
            _tag(cell, "remove-cell")
        elif is_helper_cell(cell):
            _tag(cell, "hide-input")
        gid = _grade_id(cell)
        if gid:
            if gid not in student:
                raise ValueError(f"{executed.name}: graded cell {gid!r} is not in the student release "
                                 f"{release}; run make release")
            cell.source = student[gid].source
            if cell.cell_type == "code" and cell.get("outputs"):
                _tag(cell, "hide-output")
        elif cell.cell_type == "code" and any(r in cell.source for r in REVEALS):
            _tag(cell, "hide-output")
        for output in cell.get("outputs", []):
            html = output.get("data", {}).get("text/html")
            if html:
                output["data"]["text/html"] = FOREIGN_STYLESHEET.sub("", html if isinstance(html, str) else "".join(html))
        cells.append(cell)
    link = nbformat.v4.new_markdown_cell(
        f"[Open this notebook in Colab]({landing.colab_url(executed.name)}) (the student version, "
        "with its exercises to do). Below: the instructor's run of it, with the exercises' code "
        "left for you to write and the outputs that answer an exercise folded away.")
    title = next((i for i, c in enumerate(cells) if c.cell_type == "markdown"
                  and c.source.lstrip().startswith("# ")), None)
    cells.insert(0 if title is None else title + 1, link)
    nb.cells = cells
    return nb


def assemble(run: Path, src: Path, commit: str) -> list[str]:
    """Write the site's source into ``src`` from the run in ``run``. Returns the notebook names."""
    if src.exists():
        shutil.rmtree(src)
    shutil.copytree(BOOK, src)
    notebooks = sorted(p.name for p in run.glob("0*.ipynb"))
    if not notebooks:
        raise SystemExit(f"no executed notebooks in {run}: run make chapter first")
    scrubber = run / "site" / "scrubber.json"
    if not scrubber.exists():
        raise SystemExit(f"{scrubber} is missing: make chapter writes it (scripts/chapter.py)")
    (src / "notebooks").mkdir()
    for name in notebooks:
        nbformat.write(publishable(run / name, RELEASE / name), src / "notebooks" / name)
    shutil.copy(scrubber, src / "_static" / "scrubber.json")     # the data, downloadable as it was exported
    meta = yaml.safe_load((ROOT / "meta.yaml").read_text())
    data = json.loads(scrubber.read_text())
    (src / "index.md").write_text(landing.page(meta, data, notebooks, commit))
    toc = {"format": "jb-book", "root": "index",
           "chapters": [{"file": f"notebooks/{Path(n).stem}"} for n in notebooks] + [{"file": "reading"}]}
    (src / "_toc.yml").write_text(yaml.safe_dump(toc, sort_keys=False))
    return notebooks


def weight(html: Path, page: str = "index.html") -> dict:
    """Bytes of the whole site, and of one page with every local file it references."""
    import re

    total = sum(p.stat().st_size for p in html.rglob("*") if p.is_file())
    text = (html / page).read_text()
    refs = {m for m in re.findall(r'(?:src|href)="([^"#?]+)', text) if "://" not in m and not m.startswith("mailto:")}
    files = {(html / page).resolve()} | {(html / r).resolve() for r in refs
                                         if (html / r).is_file() and not r.endswith(".html")}
    return {"site_bytes": total, "page_bytes": sum(f.stat().st_size for f in files), "page_files": len(files)}


def build(run: Path, out: Path) -> dict:
    """Assemble and build the site; returns the build's time and weight."""
    t0 = time.perf_counter()
    src, html = out / "src", out / "html"
    assemble(run, src, provenance.commit())
    build_dir = out / "jb"
    if build_dir.exists():
        shutil.rmtree(build_dir)
    # Jupyter Book's command through this interpreter, not its script in bin/: a venv made or moved
    # elsewhere leaves the script's first line naming a Python that no longer exists
    cmd = [sys.executable, "-c", JUPYTER_BOOK, "build", str(src), "--path-output", str(build_dir), "--quiet"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"jupyter-book failed ({done.returncode}):\n{done.stdout[-4000:]}\n{done.stderr[-4000:]}")
    if html.exists():
        shutil.rmtree(html)
    shutil.copytree(build_dir / "_build" / "html", html)
    report = {"seconds": round(time.perf_counter() - t0, 1), **weight(html)}
    (out / "build.json").write_text(json.dumps(report, indent=1) + "\n")
    return report


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run", type=Path, default=ROOT / "runs" / "chapter", help="a make chapter output folder")
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "site")
    args = p.parse_args(argv)
    r = build(args.run.resolve(), args.out.resolve())
    run_commit = json.loads((args.run / "site" / "scrubber.json").read_text()).get("commit")
    if run_commit != provenance.commit() or run_commit.endswith("-dirty"):
        print(f"note: the run was made at {run_commit}, the site built at {provenance.commit()}: the page says "
              f"so under the colophon; rebuild both from one clean commit (make site) to publish")
    print(f"site built in {r['seconds']} s -> {args.out / 'html' / 'index.html'}\n"
          f"landing page: {r['page_bytes'] / 1024:.0f} KB in {r['page_files']} files; "
          f"whole site {r['site_bytes'] / 1e6:.1f} MB")
    return 0
