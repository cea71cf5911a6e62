"""The trained stages' cache on disk: a stage's file is named by everything it was computed from.

A stage (the expert data, the frozen world model, the trained agent, the real-data loop's rounds)
is saved as one file whose name is a hash of the config fields it reads and of the source of every
module of this package it can run: the module that builds it and, followed through their imports,
every module of the package that one imports (``sources``). The list is derived from the code,
never kept by hand, so editing any module a stage runs (the optimiser the world model trains with,
say) names a new file and the old one is never read again; editing a module the stage cannot reach
(a notebook's sentences, the site) keeps the file valid.

A file of the same name is therefore the same stage, which is what lets the grader compute the
stages no student can change once, with the instructor's notebooks, and hand them to every
student's kernel read-only (``SHARED_CACHE_ENV``; ``autograde/stages.py``).
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import re
from functools import lru_cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent          # pusht/
SHARED_CACHE_ENV = "PUSHT_SHARED_CACHE"            # a read-only folder of stages the grader computed once
KINDS = ("wm", "agent", "loop")                     # the stages cached as <kind>_<16 hex digits>.pt
# Every file this cache writes: the expert data (data.py) and the stages.
FILE_PATTERN = re.compile(r"^(expert_.*\.npz|(" + "|".join(KINDS) + r")_[0-9a-f]{16}\.pt)$")


def _module_file(name: str, package: Path) -> Path | None:
    """The file of module ``name`` (dotted, the package's name first) under ``package``, or None
    where it names no module of the package (a function or class imported from a package)."""
    parts = name.split(".")[1:]
    base = package.joinpath(*parts)
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def imports(name: str, package: Path = PACKAGE) -> set[str]:
    """The package's own modules that the module ``name`` imports anywhere in its code, at its top
    or inside a function: all of them could run while a stage is built."""
    path = _module_file(name, package)
    if path is None:
        raise ValueError(f"{name} is not a module of {package}")
    top = package.name
    here = name.split(".") if path.name != "__init__.py" else name.split(".") + ["_"]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            bases = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(here[: len(here) - node.level] + ([base] if base else []))
            # `from .nb import claims` imports a module, `from .config import Config` a name: both kept
            bases = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for b in bases:
            if b == top or b.startswith(top + "."):
                # importing pusht.a.b runs pusht/__init__.py and pusht/a/__init__.py too
                bits = b.split(".")
                found.update(".".join(bits[:i]) for i in range(1, len(bits) + 1))
    return {m for m in found if _module_file(m, package) is not None}


@lru_cache(maxsize=None)
def sources(module: str, package: Path = PACKAGE) -> tuple[Path, ...]:
    """Every file of the package that ``module`` (a dotted name such as ``"pusht.wm_stage"``) can
    run: itself and, transitively, every module of the package it imports. Sorted."""
    seen: dict[str, Path] = {}
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        path = _module_file(name, package)
        if path is None:
            raise ValueError(f"{name} is not a module of {package}")
        seen[name] = path
        todo.extend(imports(name, package) - set(seen))
    return tuple(sorted(seen.values()))


def key(cfg, fields, module: str, package: Path = PACKAGE) -> str:
    """The hash that names a stage: the values of ``cfg``'s ``fields`` and the source of every file
    ``module`` can run (``sources``)."""
    h = hashlib.sha256(json.dumps({n: str(getattr(cfg, n)) for n in fields}, sort_keys=True).encode())
    return _add_sources(h, module, package).hexdigest()[:16]


def stage_path(model_cache, kind: str, cfg, fields, module: str) -> Path | None:
    """Where stage ``kind`` of ``cfg`` is cached in the folder ``model_cache`` (None: no cache)."""
    if model_cache is None:
        return None
    if kind not in KINDS:
        raise ValueError(f"unknown stage kind {kind!r}; one of {KINDS}")
    return Path(model_cache) / f"{kind}_{key(cfg, fields, module)}.pt"


def source_hash(module: str, package: Path = PACKAGE) -> str:
    """A short hash of the source ``module`` can run (for files named otherwise, the expert data's)."""
    return _add_sources(hashlib.sha256(), module, package).hexdigest()[:12]


def _add_sources(h, module: str, package: Path):
    """``h`` updated with the name and bytes of every file ``module`` can run; returned."""
    for path in sources(module, package):
        h.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    return h


def cached_file(path: Path) -> Path | None:
    """Where a cache file named like ``path`` can be read: ``path`` itself, else a file of the same
    name in the read-only folder ``$PUSHT_SHARED_CACHE`` (set by the grader: stages computed once,
    by the instructor's own notebooks, for every student; see autograde/stages.py), else None."""
    if path.exists():
        return path
    shared = os.environ.get(SHARED_CACHE_ENV)
    if shared and (Path(shared) / path.name).is_file():
        return Path(shared) / path.name
    return None


def cached(path: Path | None, build):
    """The stage saved at ``path`` (or its shared copy), else ``build()``, saved there atomically."""
    import torch

    found = None if path is None else cached_file(path)
    if found is not None:
        return torch.load(found, weights_only=False)
    stage = build()
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")   # its own: run_many's workers share a cache
        torch.save(stage, tmp)
        os.replace(tmp, path)                                    # atomic: a half-written file is never read
    return stage
