"""The package as the probe process sees it: every exercise's implementation replaced by a raise.

The probe process (``probe.py``) runs a student's definitions with this copy of ``pusht`` bound
over the real one, so the chapter's own ``reward_from_obs``, ``lambda_return``,
``actor_critic_losses``, ``dream``, ``block_disagreement`` and ``cem_update`` do not exist there in any form: not
as a guarded function, not as a closure, a ``__wrapped__``, a code object, a ``.pyc`` or source
text on disk. A submission that calls them gets ``ReferenceRefused`` by construction, whatever
name, wrapper or run-time lookup it reaches them through.

A function is an implementation of an exercise when it carries ``@reference(...)``
(``pusht.reference.reference``); every such function in every module of the package is found from
the source (``ast``), and its body becomes one ``raise`` (signature and decorator kept, so imports
and ``inspect.signature`` still work). Everything else is copied as it is, compiled once.
"""

from __future__ import annotations

import ast
import atexit
import compileall
import hashlib
import os
import shutil
import tempfile
from functools import lru_cache
from pathlib import Path

import pusht

from . import cellcode

PACKAGE_DIR = Path(pusht.__file__).resolve().parent


def _is_reference(node) -> str | None:
    """The exercise named by a ``@reference("...")`` decorator of ``node``, else None."""
    for d in getattr(node, "decorator_list", []):
        if isinstance(d, ast.Call) and getattr(d.func, "id", getattr(d.func, "attr", None)) == "reference" \
                and d.args and isinstance(d.args[0], ast.Constant) and isinstance(d.args[0].value, str):
            return d.args[0].value
    return None


class _Strip(ast.NodeTransformer):
    def __init__(self, module: str):
        self.module, self.found = module, []

    def _fn(self, node):
        exercise = _is_reference(node)
        if exercise is None:
            return self.generic_visit(node)
        self.found.append(node.name)
        msg = (f"{self.module}.{node.name} is the package's own solution to {exercise}; while grading it is "
               f"not available: your function must compute the result itself")
        node.body = [cellcode.python_tree(f"from pusht.reference import ReferenceRefused\nraise ReferenceRefused({msg!r})").body[0],
                     cellcode.python_tree(f"raise ReferenceRefused({msg!r})").body[0]]
        return node

    visit_FunctionDef = visit_AsyncFunctionDef = _fn


def strip_source(text: str, module: str) -> tuple[str, list[str]]:
    """(the module's source with every ``@reference`` function's body replaced, their names)."""
    tree = cellcode.python_tree(text)
    t = _Strip(module)
    tree = ast.fix_missing_locations(t.visit(tree))
    return (ast.unparse(tree) + "\n" if t.found else text), t.found


def references() -> dict[str, list[str]]:
    """{module: [function names]} of every implementation the stripped copy removes."""
    out = {}
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        module = ".".join(("pusht",) + path.relative_to(PACKAGE_DIR).with_suffix("").parts).removesuffix(".__init__")
        _, found = strip_source(path.read_text(encoding="utf-8"), module)
        if found:
            out[module] = found
    return out


def build(dest: Path) -> Path:
    """Write the stripped package into ``dest/pusht`` (readable by anyone, compiled); returns it."""
    target = dest / "pusht"
    for path in sorted(PACKAGE_DIR.rglob("*")):
        rel = path.relative_to(PACKAGE_DIR)
        if "__pycache__" in rel.parts or path.is_symlink():
            continue
        out = target / rel
        if path.is_dir():
            out.mkdir(parents=True, exist_ok=True)
            continue
        out.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".py":
            module = ".".join(("pusht",) + rel.with_suffix("").parts).removesuffix(".__init__")
            out.write_text(strip_source(path.read_text(encoding="utf-8"), module)[0], encoding="utf-8")
        else:
            shutil.copyfile(path, out)
    compileall.compile_dir(str(target), quiet=1, workers=1)
    for root, _dirs, files in os.walk(dest):
        os.chmod(root, 0o755)
        for f in files:
            os.chmod(os.path.join(root, f), 0o644)
    return target


def _fingerprint() -> str:
    h = hashlib.sha256()     # the package's code and its words (pusht/nb/text/*.md), which it copies
    for path in sorted(PACKAGE_DIR.rglob("*.py")) + sorted(PACKAGE_DIR.rglob("*.md")):
        if "__pycache__" not in path.parts:
            h.update(str(path.relative_to(PACKAGE_DIR)).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:16]


@lru_cache(maxsize=None)
def _built(fingerprint: str) -> Path:
    folder = Path(tempfile.mkdtemp(prefix=f"pusht-stripped-{fingerprint}-"))
    atexit.register(shutil.rmtree, folder, True)
    return build(folder)


def package() -> Path:
    """This process's stripped copy of the package (made once per process and package source)."""
    return _built(_fingerprint())
