"""The front door and the pages behind it stay whole: README.md is short, every page of docs/ is
reachable from it, no relative link or anchor is dead, and the map of modules in docs/developers.md
names every Python module that exists, and nothing that does not.

The map is checked against the files present (not a list kept here), so a module added, moved or
removed without a line in the map fails this test, and so does a line left for a module that is gone.
"""

from __future__ import annotations

import re
from collections import deque
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
MAP_PAGE = DOCS / "developers.md"
MAP_START, MAP_END = "<!-- map:start", "<!-- map:end -->"
# Every Python file under these folders, subpackages included, must have its line in the map.
MAPPED = ("pusht", "autograde", "chapter_site", "scripts")
README_MAX_LINES = 150

FENCE = re.compile(r"^\s*(```|~~~)")
CODE_SPAN = re.compile(r"`+[^`]*`+")
LINK = re.compile(r"\]\(\s*<?([^()\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
MAP_ROW = re.compile(r"^\|\s*`([^`]+\.py)`\s*\|")
PY_PATH = re.compile(r"`([\w./-]+/[\w.-]+\.py)`")


def pages() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


def prose_lines(text: str):
    """The lines of a Markdown text outside fenced code blocks, with their code spans removed."""
    fenced = False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield CODE_SPAN.sub("", line)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)          # a link shows its text
    text = text.replace("`", "").lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading's anchor in a Markdown file, repeated headings numbered as GitHub numbers them."""
    seen: dict[str, int] = {}
    out = set()
    fenced = False
    for line in path.read_text().splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        m = None if fenced else HEADING.match(line)
        if m:
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f"{base}-{n}")
    return out


def relative_links(path: Path) -> list[str]:
    """The link targets of a Markdown file that point into this repository (no scheme, no mail)."""
    targets = [t for line in prose_lines(path.read_text()) for t in LINK.findall(line)]
    return [t for t in targets if not re.match(r"^[a-z][a-z0-9+.-]*:", t, re.I)]


def resolve(page: Path, target: str) -> tuple[Path, str]:
    """(the file a link points at, its anchor or '')."""
    where, _, anchor = target.partition("#")
    return ((page.parent / where).resolve() if where else page), anchor


def test_the_readme_is_a_front_door():
    n = len(README.read_text().splitlines())
    assert n <= README_MAX_LINES, f"README.md has {n} lines, more than {README_MAX_LINES}: move detail into docs/"


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_and_anchor_resolves(page):
    dead = []
    for target in relative_links(page):
        path, anchor = resolve(page, target)
        if not path.exists():
            dead.append(f"{target}: no such file")
        elif anchor and path.suffix == ".md" and anchor not in anchors(path):
            dead.append(f"{target}: no heading '#{anchor}' in {path.relative_to(ROOT)}")
    assert not dead, f"dead links in {page.relative_to(ROOT)}:\n" + "\n".join(dead)


def test_every_docs_page_is_reachable_from_the_readme():
    reached, todo = {README}, deque([README])
    while todo:
        page = todo.popleft()
        for target in relative_links(page):
            path, _ = resolve(page, target)
            if path.suffix == ".md" and path.exists() and path not in reached:
                reached.add(path)
                todo.append(path)
    orphans = [p.relative_to(ROOT).as_posix() for p in DOCS.glob("*.md") if p.resolve() not in reached]
    assert not orphans, f"docs pages no link from README.md leads to: {orphans}"


def map_block() -> str:
    text = MAP_PAGE.read_text()
    assert MAP_START in text and MAP_END in text, f"{MAP_PAGE.relative_to(ROOT)} has lost its map markers"
    return text.split(MAP_START, 1)[1].split(MAP_END, 1)[0]


def modules() -> set[str]:
    return {p.relative_to(ROOT).as_posix() for folder in MAPPED for p in (ROOT / folder).rglob("*.py")
            if "__pycache__" not in p.parts}


def test_the_map_names_every_module():
    named = {m.group(1) for line in map_block().splitlines() if (m := MAP_ROW.match(line))}
    missing = sorted(modules() - named)
    assert not missing, ("modules with no line in docs/developers.md's map (add one: "
                         f"| `path` | what it does |): {missing}")


def test_the_map_names_no_file_that_is_gone():
    gone = sorted({p for p in PY_PATH.findall(map_block()) if not (ROOT / p).exists()})
    assert not gone, f"docs/developers.md's map names files that do not exist: {gone}"


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_python_file_a_page_names_exists(page):
    # prose that names `pusht/zygote.py` after the module moved would send a reader nowhere
    gone = sorted({p for p in PY_PATH.findall(page.read_text()) if not (ROOT / p).exists()})
    assert not gone, f"{page.relative_to(ROOT)} names Python files that do not exist: {gone}"


def test_the_checks_themselves():
    # GitHub's anchors, as links to these pages spell them
    assert slug("Every sentence about your run is checked") == "every-sentence-about-your-run-is-checked"
    assert slug("`pusht/`: the package") == "pusht-the-package"
    assert slug("Beyond one machine: Dask") == "beyond-one-machine-dask"
    # a link inside code is not a link; a web address is not checked here
    fake = ROOT / "docs" / "x.md"
    assert resolve(fake, "#top") == (fake, "top")
    assert list(prose_lines("```\n[a](nowhere.md)\n```\nsee `[b](nowhere.md)` and [c](here.md)")) == \
        ["see  and [c](here.md)"]
