"""Copies of the answer key that ships in the package, found by a normalised comparison.

The package a learner installs holds the chapter's own implementation of every exercise (that is
how the chapter runs). Pasting it into the answer cell earns points in the probe process (the
code is the learner's cell's now), so the grader compares each graded function with the
package's implementation of it and flags a copy for the instructor, with where it is. A flag
never changes a score, in either direction: the same few lines are also what a learner who
understood the exercise may write, and only a person can tell the two apart.

The comparison is on what the code does, not how it is spelled: both functions are parsed, their
docstrings, annotations, decorators and comments dropped, every name (arguments, locals, globals
and module aliases) renamed in order of first use, and each top-level statement of the body
printed. Every function defined above the test cell is compared, not only the graded one (a copy
renamed and called from the graded function, or assigned to its name, is still found). A function
is flagged when the package's statements all appear in it, in the same order (a copy with prints,
asserts or comments added is still a copy); renaming variables, reformatting or re-commenting the
key does not hide it. Reordering independent statements or rewriting an
expression does, which is then the learner's own work.
"""

from __future__ import annotations

import ast
import inspect
import textwrap
from functools import lru_cache

from . import cellcode, checks

MIN_STATEMENTS = 3          # a key shorter than this is one line anyone would write


class _Rename(ast.NodeTransformer):
    def __init__(self):
        self.names: dict[str, str] = {}

    def _name(self, name: str) -> str:
        return self.names.setdefault(name, f"v{len(self.names)}")

    def visit_Name(self, node):
        return ast.copy_location(ast.Name(id=self._name(node.id), ctx=node.ctx), node)

    def visit_arg(self, node):
        return ast.copy_location(ast.arg(arg=self._name(node.arg), annotation=None), node)


def _without_docstring(body: list) -> list:
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        return body[1:]
    return body


def normalised(fn: ast.FunctionDef) -> list[str]:
    """The function's body as printed statements after dropping what does not run and renaming."""
    fn = cellcode.python_tree(ast.unparse(fn)).body[0]        # a copy
    fn.decorator_list, fn.returns = [], None
    for node in ast.walk(fn):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            node.body = _without_docstring(node.body) or [ast.Pass()]
    renamer = _Rename()
    for a in fn.args.posonlyargs + fn.args.args + fn.args.kwonlyargs:
        renamer._name(a.arg)
    fn = renamer.visit(fn)
    return [ast.dump(s, annotate_fields=False) for s in fn.body]


@lru_cache(maxsize=None)
def key(test_id: str) -> tuple[str, ...]:
    """The package's implementation of a test's function, normalised."""
    fn = checks.reference_function(checks.TESTS[test_id])
    tree = cellcode.python_tree(textwrap.dedent(inspect.getsource(fn)))
    return tuple(normalised(tree.body[0]))


def _in_order(needle: tuple, hay: list) -> bool:
    it = iter(hay)
    return all(any(h == n for h in it) for n in needle)


def definitions(cells, test):
    """(cell number, definition) of every function defined in the cells above the test cell, at any
    depth: the graded function, and any helper, alias target or method it may hand its work to."""
    for i, cell in enumerate(cells):
        if cellcode.gid(cell) == test.test_id and cell.get("cell_type") == "code":
            return
        if cell.get("cell_type") != "code":
            continue
        tree = cellcode.parse(cellcode.source(cell))
        for node in ast.walk(tree) if tree is not None else []:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield i + 1, node


def copies(cells, test) -> str | None:
    """A line for the instructor where a function above the test cell holds the package's
    implementation of the tested one (the graded function itself, or a helper it may call under
    any name), else None."""
    want = key(test.test_id)
    if len(want) < MIN_STATEMENTS:
        return None
    module, name = test.reference.split(":")
    for cell, fn in definitions(cells, test):
        mine = normalised(fn)
        if not _in_order(want, mine):
            continue
        how = ("the same statements" if len(mine) == len(want) else
               f"all {len(want)} of its statements, in order, among {len(mine)}")
        return (f"`{fn.name}` (cell {cell}) holds the package's own `{module}.{name}` ({how}, names aside): "
                f"a copy of the answer key, or the same steps written independently. Its score stands; read it")
    return None
