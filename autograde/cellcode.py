"""A notebook's code cells as the Python that IPython would run, parsed, never executed.

The receipts check (``receipts.py``) asks which functions a cell calls, and the delegation check
(``delegation.py``) follows what a graded function reaches; both read cells the way the kernel
does. A cell is not plain Python: magics (``%time``, ``%%capture``), shell escapes (``x = !ls``)
and help syntax (``f?``) are turned into Python by IPython's own input transformer first, and the
body of a cell magic that runs Python in the learner's namespace (``%%time``, ``%%capture``...)
is parsed as the code it is. A cell that does not parse is one that raises when run: it binds and
calls nothing.
"""

from __future__ import annotations

import ast
import re
import threading
from functools import lru_cache

# Magics whose argument (line) or body (cell) is Python run in the learner's namespace.
PYTHON_MAGICS = {"time", "timeit", "capture", "prun"}


def text(value) -> str:
    """A saved text field (a cell's source, an output's text) as one string, whatever the saving
    program or a hand edit put there: a string, a list of strings, or something else."""
    if isinstance(value, list):
        return "".join(v if isinstance(v, str) else str(v) for v in value)
    return value if isinstance(value, str) else "" if value is None else str(value)


def source(cell) -> str:
    """A cell's text; "" for anything a hand-in holds there that is not text."""
    s = cell.get("source", "") if isinstance(cell, dict) else ""
    return text(s) if isinstance(s, (str, list)) else ""


def gid(cell) -> str | None:
    """The nbgrader grade id of a cell, or None (also where a hand-in's metadata is not a mapping)."""
    meta = cell.get("metadata") if isinstance(cell, dict) else None
    nbg = meta.get("nbgrader") if isinstance(meta, dict) else None
    g = nbg.get("grade_id") if isinstance(nbg, dict) else None
    return g if isinstance(g, str) else None


@lru_cache(maxsize=1)
def _transformer():
    try:
        from IPython.core.inputtransformer2 import TransformerManager
    except ImportError:             # no IPython: magics and shell lines are blanked instead
        return None
    return TransformerManager()


def _python(src: str) -> str:
    if not any(c in src for c in "%!?"):         # no magic, shell escape or help: plain Python
        return src
    tm = _transformer()
    if tm is not None:
        try:
            return tm.transform_cell(src)
        except Exception:           # noqa: BLE001  IPython refuses it: so would the kernel
            return ""
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in src.splitlines())


MAX_CELL_CHARS = 200_000      # a cell's code that is parsed at all: a chapter cell is under 5,000

# CPython 3.11 up to 3.11.8 keeps one recursion counter for turning a parse into ``ast`` objects; two
# grading threads parsing at once can trip it ("SystemError: AST constructor recursion depth
# mismatch", seen when two tasks started together). Every parse of the grader goes through here.
_PARSE_LOCK = threading.RLock()


def python_tree(text: str) -> ast.Module:
    """``ast.parse(text)``, one thread at a time (see ``_PARSE_LOCK``)."""
    with _PARSE_LOCK:
        return ast.parse(text)


@lru_cache(maxsize=4096)
def parse(src: str) -> ast.Module | None:
    """The cell's code as the kernel runs it, or None where it would not compile. The same text
    gives the same tree object (a hand-in's cells are read by several checks): do not change it.
    A cell longer than ``MAX_CELL_CHARS`` is not parsed (None): its syntax tree would take about
    600 times its size in the grader's memory."""
    if len(src) > MAX_CELL_CHARS:
        return None
    try:
        tree = python_tree(_python(src))
    except (SyntaxError, ValueError, RecursionError, MemoryError):   # the kernel would refuse it too
        return None
    body = []
    for node in tree.body:
        inner = _magic_body(node)
        body.extend(inner.body if inner is not None else [node])
    tree.body = body
    return tree


def _magic_body(node) -> ast.Module | None:
    """``get_ipython().run_cell_magic('time', '', BODY)`` (or a Python line magic): BODY parsed."""
    call = node.value if isinstance(node, (ast.Expr, ast.Assign)) else None
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute)
            and call.func.attr in ("run_cell_magic", "run_line_magic") and len(call.args) >= 2
            and all(isinstance(a, ast.Constant) and isinstance(a.value, str) for a in call.args)):
        return None
    name = call.args[0].value
    text = call.args[-1].value if call.func.attr == "run_cell_magic" else call.args[1].value
    if name not in PYTHON_MAGICS:
        return None
    if call.func.attr == "run_line_magic":
        text = re.sub(r"^(\s*-\w+(\s+\d+)?)*\s*", "", text)     # options first: %timeit -n 3 f()
    return parse(text)


def top_level_calls(tree: ast.Module | None) -> set[str]:
    """Names of the functions a cell calls when it runs: ``f(...)``, ``mod.f(...)``, a function
    handed to a call as an argument (``map(f, xs)``), and what the functions and lambdas that the
    cell defines call, where the cell calls them. ``x.run(...)`` counts as ``run`` only on the
    package (``dreamer.run``, ``pusht.dreamer.run``): ``subprocess.run`` and friends are not the
    chapter's."""
    if tree is None:
        return set()
    defined = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}
    out: set[str] = set()
    todo, seen = list(tree.body), set()
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        if isinstance(node, ast.Lambda):
            continue
        todo.extend(ast.iter_child_nodes(node))
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        if isinstance(f, ast.Lambda):                        # (lambda: experiment())()
            todo.append(f.body)
        elif isinstance(f, ast.Name):
            out.add(f.id)
            if f.id in defined and f.id not in seen:       # a function of this cell, called here
                seen.add(f.id)
                todo.extend(defined[f.id].body)
        elif isinstance(f, ast.Attribute) and (f.attr != "run" or _on_package(f.value)):
            out.add(f.attr)
        out |= {a.id for a in list(node.args) + [k.value for k in node.keywords] if isinstance(a, ast.Name)}
    return out


def _on_package(node) -> bool:
    """Is ``node`` (the object a method is called on) spelled as the chapter's package?"""
    try:
        text = ast.unparse(node)
    except Exception:            # noqa: BLE001
        return False
    return text.startswith("pusht") or "dreamer" in text
