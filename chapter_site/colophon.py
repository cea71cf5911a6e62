"""The colophon: every code region the notebooks show, with a fingerprint of the shown source.

The notebooks show the package's code with ``display(Code(inspect.getsource(X)))``. This module
finds every such ``inspect.getsource(...)`` call in the instructor notebooks by parsing their code
cells, resolves ``X`` through the cell imports the way the notebook's kernel would, and fingerprints
exactly the text the notebook displays (sha256 of ``inspect.getsource(X)``). The site lists them at
the commit it was built from, so a reader can check a shown region against the code.
"""

from __future__ import annotations

import ast
import hashlib
import importlib
import inspect
import json
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Region:
    notebook: str      # e.g. "04_imagination_gap"
    expression: str    # what the notebook passes to inspect.getsource
    module: str        # where the object is defined
    qualname: str      # its name there
    lines: str         # "first-last" line numbers in its file
    sha256: str        # of the shown source text, utf-8


def _imports(tree: ast.AST) -> dict[str, str]:
    """Name -> dotted path, for every import in ``tree`` (``import a.b`` binds ``a``)."""
    names: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                names[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                names[a.asname or a.name] = f"{node.module}.{a.name}"
    return names


def _resolve(dotted: str):
    """The object a dotted path names: the longest importable module prefix, then attributes."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for p in parts[i:]:
            obj = getattr(obj, p)
        return obj
    raise ImportError(f"cannot resolve {dotted!r}")


def _dotted(node: ast.AST) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value)
        return f"{base}.{node.attr}" if base else None
    return None


def shown_expressions(nb_path: Path) -> list[str]:
    """Every argument of ``inspect.getsource(...)`` in the notebook's code cells, in order."""
    cells = [c["source"] if isinstance(c["source"], str) else "".join(c["source"])
             for c in json.loads(nb_path.read_text())["cells"] if c["cell_type"] == "code"]
    found = []
    for src in cells:
        try:
            tree = ast.parse(src)
        except SyntaxError:          # IPython magics: such a cell shows no package code
            continue
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and _dotted(node.func) == "inspect.getsource" and node.args):
                expr = _dotted(node.args[0])
                if expr is None:
                    raise ValueError(f"{nb_path.name}: inspect.getsource of {ast.unparse(node.args[0])!r}, "
                                     "which the colophon cannot resolve; show a module-level name")
                found.append(expr)
    return found


def regions(notebooks_dir: Path = ROOT / "solutions") -> list[Region]:
    """The colophon of every notebook in ``notebooks_dir``."""
    out = []
    for nb in sorted(notebooks_dir.glob("*.ipynb")):
        text = json.loads(nb.read_text())
        imports: dict[str, str] = {}
        for c in text["cells"]:
            if c["cell_type"] == "code":
                try:
                    imports.update(_imports(ast.parse("".join(c["source"]))))
                except SyntaxError:
                    continue
        for expr in shown_expressions(nb):
            head, _, rest = expr.partition(".")
            if head not in imports:
                raise ValueError(f"{nb.name}: {head!r} in inspect.getsource({expr}) is not imported in the notebook")
            obj = _resolve(imports[head] + (f".{rest}" if rest else ""))
            source = inspect.getsource(obj)
            lines, first = inspect.getsourcelines(obj)
            out.append(Region(nb.stem, expr, obj.__module__, obj.__qualname__,
                              f"{first}-{first + len(lines) - 1}",
                              hashlib.sha256(source.encode()).hexdigest()))
    return out
