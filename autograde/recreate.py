"""Which of a hand-in's statements the probe runs to define a graded function as the kernel did.

The probe process (``probe.py``) defines the graded function again, from the hand-in's cells above
the test cell, away from the student's kernel. It must end with the function the kernel had:
an honest notebook that worked in Jupyter must never lose a function (or a constant, a table, a
class attribute it reads) in the re-creation. And it should not redo the notebook's work (training,
plotting), which costs time and proves nothing about the function.

The rule is an over-approximation, and it splits the statements in two:

* **The release's own statements** (the same text as a statement of the student release, outside
  its answer cells: we wrote them, and we know what they do) are kept where they bind or change a
  name the graded function needs, directly or through what it needs (their effects are read from
  their syntax: an assignment, a store into ``X[...]`` or ``X.attr``, a method called on ``X``).
* **The student's statements** are all kept, except one that provably cannot affect the function:
  every call in it is of an *inert* callee, it stores nothing into an object that is not inert, and
  the names it binds or the objects it changes are not needed. Inert callees are the chapter's
  package, plotting and display (``pusht``, ``matplotlib``, ``IPython``, ``tqdm``, ``time``,
  ``print``, ``len``...), and methods of values made only by such calls (``ax.plot(...)`` after
  ``fig, ax = plt.subplots()``), which change at most those values. A call of anything else (the
  notebook's own functions and classes, ``torch``, ``numpy``, ``open``, ``json``, ``setattr``...)
  may change any state, a file or the interpreter's settings, so its statement is kept.

Imports, function and class definitions are always kept (cheap, and a function may reach them at
run time by any name); what a definition reads is needed where its name is, and always where a
decorator the notebook made may file it away (``@register("f")`` into a table the function is then
read from). Statements are kept in notebook order, so a later definition replaces an
earlier one as in the kernel; the probe runs each under the ``__future__`` flags in force at that
point (``pusht.grader.probe_server``), and one that raises does not stop the others.

The package's functions are taken not to change the objects handed to them in a way the graded
function could see (the chapter's functions return new values). Everything is linear in the
notebook's statements: each statement is walked once, each name looked up once.
"""

from __future__ import annotations

import ast
import symtable

from . import cellcode

SETUP = (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)

# Modules whose functions change no state a graded function can read (the chapter's package, plots,
# display, progress bars, clocks). Their results are inert values (``ax``, ``stage``, ``cfg``).
INERT_MODULES = frozenset({"pusht", "matplotlib", "IPython", "tqdm", "time"})

# Builtins that run no notebook code worth keeping (unless the notebook rebinds the name).
INERT_BUILTINS = frozenset({
    "print", "display", "len", "range", "round", "abs", "min", "max", "sum", "sorted", "enumerate", "zip",
    "str", "repr", "format", "int", "float", "bool", "complex", "list", "tuple", "dict", "set", "frozenset",
    "isinstance", "issubclass", "type", "any", "all", "reversed", "hash", "id", "divmod", "pow", "bin",
    "hex", "oct", "chr", "ord", "ascii", "callable",
})

# Methods that write outside the value they are called on (a file): never inert, whatever the value.
WRITES = frozenset({"write", "write_text", "write_bytes", "writelines", "save", "savez", "savefig",
                    "dump", "to_csv", "to_json", "mkdir", "touch", "rename", "replace", "unlink",
                    "rmdir", "symlink_to", "chmod", "tofile", "to_pickle"})


# --- reading one statement --------------------------------------------------------------------------
def _base_name(node) -> str | None:
    """``X`` of ``X``, ``X.a.b`` or ``X[i][j]``: the name whose value an access starts from."""
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _module_root(node) -> list[tuple[str, str]]:
    """[(bound name, module's top package)] of an import statement."""
    if isinstance(node, ast.Import):
        return [((a.asname or a.name).split(".")[0], a.name.split(".")[0]) for a in node.names]
    root = (node.module or "").split(".")[0] if not node.level else ""
    return [(a.asname or a.name, root) for a in node.names if a.name != "*"]


def _executed(node):
    """The nodes of a statement that run when it runs: not the bodies of the functions and lambdas
    it defines (their decorators and defaults run; a class body runs)."""
    todo = [node]
    while todo:
        n = todo.pop()
        yield n
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
            todo.extend(n.decorator_list)
            todo.extend(d for d in n.args.defaults + n.args.kw_defaults if d is not None)
            todo.extend(a.annotation for a in n.args.args + n.args.kwonlyargs if a.annotation is not None)
            if n.returns is not None:
                todo.append(n.returns)
            continue
        if isinstance(n, ast.Lambda):
            continue
        todo.extend(ast.iter_child_nodes(n))


class _Reading:
    """What one top-level statement does, read from its syntax once."""

    __slots__ = ("binds", "store_bases", "calls", "lambdas", "plain", "value_names", "globals_")

    def __init__(self, node):
        self.binds: set[str] = set()          # names it binds or deletes
        self.store_bases: set[str] = set()    # X of a store into X[...] / X.attr (or a del of one)
        self.calls: list[ast.Call] = []       # the calls it makes when it runs
        self.lambdas = False                  # it makes a lambda (which something may call later)
        self.globals_ = False                 # it declares global/nonlocal at the top level
        # a plain ``A = B = expr`` (names, tuples of names): the expression, else None
        self.plain = node.value if (isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None
                                    and all(_plain_target(t) for t in _targets(node))) else None
        self.value_names: set[str] = set()    # names the plain expression reads outside call arguments
        if isinstance(node, SETUP):
            self.binds |= {n for n, _ in _module_root(node)} if isinstance(node, (ast.Import, ast.ImportFrom)) \
                else {node.name}
        for n in _executed(node):
            if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del)):
                self.binds.add(n.id)
            elif isinstance(n, ast.AugAssign) and isinstance(n.target, ast.Name):
                self.store_bases.add(n.target.id)      # ``x += [1]`` changes a list in place
            elif isinstance(n, (ast.Attribute, ast.Subscript)) and isinstance(n.ctx, (ast.Store, ast.Del)):
                self.store_bases.add(_base_name(n) or "")
            elif isinstance(n, ast.Call):
                self.calls.append(n)
            elif isinstance(n, ast.Lambda):
                self.lambdas = True
            elif isinstance(n, (ast.Global, ast.Nonlocal)):
                self.globals_ = True
            elif isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and n is not node:
                self.binds.add(n.name)
            elif isinstance(n, (ast.Import, ast.ImportFrom)) and n is not node:
                self.binds |= {b for b, _ in _module_root(n)}
            elif isinstance(n, (ast.MatchAs, ast.MatchStar)) and n.name:
                self.binds.add(n.name)
            elif isinstance(n, ast.ExceptHandler) and n.name:
                self.binds.add(n.name)
        if self.plain is not None:
            self.value_names = _names_outside_arguments(self.plain)


def _targets(node) -> list:
    return node.targets if isinstance(node, ast.Assign) else [node.target]


def _plain_target(t) -> bool:
    if isinstance(t, ast.Name):
        return True
    if isinstance(t, ast.Starred):
        return _plain_target(t.value)
    return isinstance(t, (ast.Tuple, ast.List)) and all(_plain_target(e) for e in t.elts)


def _names_outside_arguments(expr) -> set[str]:
    """The names an expression's value can be made of: every name it reads, except inside a call's
    arguments (a package call returns a new value, not its argument) and a comprehension's own."""
    out, todo = set(), [expr]
    while todo:
        n = todo.pop()
        if isinstance(n, ast.Call):
            todo.append(n.func)
            continue
        if isinstance(n, (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp, ast.Lambda)):
            out |= {x.id for x in ast.walk(n) if isinstance(x, ast.Name)}     # every name: conservative
            continue
        if isinstance(n, ast.Name):
            out.add(n.id)
        todo.extend(ast.iter_child_nodes(n))
    return out


def _reads(node) -> set[str]:
    """The global names a statement can read when it runs or when the functions it defines run:
    its own names at the top level (defaults and decorators included), and in every function,
    class, lambda and comprehension inside it the names that are global there, not their locals
    (Python's own symbol tables, ``symtable``)."""
    try:
        table = symtable.symtable(ast.unparse(node), "<statement>", "exec")
    except Exception:          # noqa: BLE001  cannot be read: every name it spells
        return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
    out, todo = set(), [table]
    while todo:
        t = todo.pop()
        top = t.get_type() == "module"
        out |= {s.get_name() for s in t.get_symbols() if s.is_referenced() and (top or s.is_global())}
        todo.extend(t.get_children())
    return out


def _registered(node, made_here: set[str]) -> bool:
    """A definition decorated by something the notebook made (``@register("name")``, ``@table.add``):
    the decorator runs with the new function or class and may keep it anywhere, so what the
    definition reads may be needed however the graded function is reached (``f = TABLE["name"]``)."""
    if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return False
    return any(_base_name(d.func if isinstance(d, ast.Call) else d) in made_here for d in node.decorator_list)


def _global_writes(node) -> set[str]:
    """Names a function definition declares ``global`` anywhere in its body."""
    return {name for n in ast.walk(node) if isinstance(n, ast.Global) for name in n.names}


# --- the notebook's statements -----------------------------------------------------------------------
def test_cell_index(cells, test_id: str) -> int | None:
    for i, cell in enumerate(cells):
        if cellcode.gid(cell) == test_id and cell.get("cell_type") == "code":
            return i
    return None


def statements(cells, end: int | None = None) -> list[tuple[str, ast.stmt]]:
    """[(label, node)] of the top-level statements of the code cells before ``end``."""
    out = []
    for i, cell in enumerate(cells[:end] if end is not None else cells):
        if cell.get("cell_type") != "code":
            continue
        tree = cellcode.parse(cellcode.source(cell))
        for node in tree.body if tree is not None else []:
            out.append((f"<cell {i + 1}, line {getattr(node, 'lineno', 0)}>", node))
    return out


def release_statements(nb) -> frozenset[str]:
    """The text of every statement of a release notebook outside its answer cells: the chapter's own."""
    out = set()
    for cell in nb.cells if hasattr(nb, "cells") else nb.get("cells", []):
        meta = cell.get("metadata", {}).get("nbgrader", {}) if isinstance(cell.get("metadata"), dict) else {}
        if cell.get("cell_type") != "code" or (isinstance(meta, dict) and meta.get("solution")):
            continue
        tree = cellcode.parse(cellcode.source(cell))
        for node in tree.body if tree is not None else []:
            try:
                out.add(ast.unparse(node))
            except Exception:      # noqa: BLE001
                pass
    return frozenset(out)


class _Groups:
    """Union-find over names that may hold the same object (``b = a``, ``t = (a, 1)``)."""

    def __init__(self):
        self.parent: dict[str, str] = {}

    def find(self, x: str) -> str:
        root = x
        while self.parent.get(root, root) != root:
            root = self.parent[root]
        while x != root:
            self.parent[x], x = root, self.parent.get(x, x)
        return root

    def union(self, a: str, b: str) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[ra] = rb


def program(cells, test_id: str, function: str, ours: frozenset[str] = frozenset()) -> list[tuple[str, str]]:
    """[(label, statement source)] that define ``function`` as the cells above the test cell do.

    ``ours``: the release's own statements (``release_statements``); every other statement is the
    student's. See the module's doc for what is kept and why."""
    end = test_cell_index(cells, test_id)
    stmts = statements(cells, end)
    texts = []
    for _, node in stmts:
        try:
            texts.append(ast.unparse(node))
        except Exception:          # noqa: BLE001  a tree unparse cannot print: the kernel could not run it
            texts.append(None)
    readings = [_Reading(node) for _, node in stmts]
    is_ours = [t is not None and t in ours for t in texts]

    # names and how they are bound, over the whole notebook above the test cell
    bound_by: dict[str, list[int]] = {}
    for k, r in enumerate(readings):
        for name in r.binds:
            bound_by.setdefault(name, []).append(k)
    global_writes = set()
    for _, node in stmts:
        for n in ast.walk(node):
            if isinstance(n, ast.Global):
                global_writes.update(n.names)
    inert_modules = set()
    for name, ks in bound_by.items():
        if name in global_writes:
            continue
        roots = []
        for k in ks:
            node = stmts[k][1]
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                roots = None
                break
            roots += [root for b, root in _module_root(node) if b == name]
        if roots and all(root in INERT_MODULES for root in roots):
            inert_modules.add(name)
    inert_builtins = {b for b in INERT_BUILTINS if b not in bound_by and b not in global_writes}

    # inert values: names bound only by plain assignments of inert expressions (a greatest fixed
    # point, by a worklist: a name found not inert makes every plain value that reads it not inert)
    candidate = {name for name, ks in bound_by.items()
                 if name not in inert_modules and name not in global_writes
                 and all(readings[k].plain is not None for k in ks)}
    readers: dict[str, list[int]] = {}
    for k, r in enumerate(readings):
        if r.plain is not None:
            for name in r.value_names:
                readers.setdefault(name, []).append(k)
    not_inert: set[str] = set()

    def callee_inert(call: ast.Call) -> bool:
        f = call.func
        base = _base_name(f)
        if base is not None and base in inert_modules:
            return True
        if isinstance(f, ast.Name) and f.id in inert_builtins:
            return True
        if isinstance(f, ast.Attribute) and f.attr in WRITES:
            return False
        names = _names_outside_arguments(f)
        return bool(names) and all(n in inert_modules or n in inert_builtins or (n in candidate and n not in not_inert)
                                   for n in names) and all(callee_inert(c) for c in ast.walk(f)
                                                           if isinstance(c, ast.Call))

    def plain_inert(k: int) -> bool:
        r = readings[k]
        if r.lambdas or r.store_bases:
            return False
        for name in r.value_names:
            if not (name in inert_modules or name in inert_builtins or (name in candidate and name not in not_inert)):
                return False
        return all(callee_inert(c) for c in r.calls)

    todo = [name for name in candidate if not all(plain_inert(k) for k in bound_by[name])]
    not_inert.update(todo)
    while todo:
        name = todo.pop()
        for k in readers.get(name, ()):
            for target in readings[k].binds:
                if target in candidate and target not in not_inert:
                    not_inert.add(target)
                    todo.append(target)
    # the calls' verdicts depended on the names found above; now they are final
    inert_value = candidate - not_inert

    groups = _Groups()
    for r in readings:
        if r.plain is not None:
            reads = {n.id for n in ast.walk(r.plain) if isinstance(n, ast.Name)} & inert_value
            for target in r.binds:
                for name in reads:
                    groups.union(target, name)

    # what each statement may change: names it binds, and groups of values it changes; None: anything
    sets_globals = {node.name: w for _, node in stmts
                    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and (w := _global_writes(node))}
    values = {name for k, r in enumerate(readings) if not isinstance(stmts[k][1], SETUP) for name in r.binds}
    keep = [False] * len(stmts)
    changes_names: list[set[str]] = []
    changes_groups: list[set[str]] = []
    for k, ((_, node), r) in enumerate(zip(stmts, readings)):
        names, grps = set(r.binds), set()
        if isinstance(node, SETUP):
            keep[k] = True
        elif is_ours[k]:
            names |= {b for b in r.store_bases if b}
            for call in r.calls:
                f = call.func
                if isinstance(f, ast.Attribute) and _base_name(f.value) in values:
                    names.add(_base_name(f.value))
                elif isinstance(f, ast.Name):
                    names |= sets_globals.get(f.id, set())
                    if f.id == "setattr" and call.args:
                        names.add(_base_name(call.args[0]) or "")
        else:          # the student's: kept unless it provably changes nothing the function needs
            unknown = r.lambdas or r.globals_ or any(b not in inert_value for b in r.store_bases)
            for call in r.calls:
                if unknown:
                    break
                if not callee_inert(call):
                    unknown = True
                elif not (_base_name(call.func) in inert_modules or
                          (isinstance(call.func, ast.Name) and call.func.id in inert_builtins)):
                    # a method of an inert value: it changes that value, and may keep what it is handed
                    receivers = {n for n in _names_outside_arguments(call.func) if n in inert_value}
                    handed = {n.id for a in call.args + [kw.value for kw in call.keywords]
                              for n in ast.walk(a) if isinstance(n, ast.Name)}
                    if any(n in bound_by and n not in inert_value and n not in inert_modules for n in handed):
                        unknown = True
                        break
                    for name in receivers:
                        for other in handed & inert_value:
                            groups.union(name, other)
                    grps |= receivers
            if unknown:
                keep[k] = True
            grps |= {b for b in r.store_bases if b in inert_value}
        changes_names.append(names)
        changes_groups.append(grps)

    by_name: dict[str, list[int]] = {}
    by_group: dict[str, list[int]] = {}
    for k in range(len(stmts)):
        for name in changes_names[k]:
            by_name.setdefault(name, []).append(k)
        for name in changes_groups[k]:          # groups are final now: index by each one's root
            by_group.setdefault(groups.find(name), []).append(k)

    seen: set[str] = set()
    seen_groups: set[str] = set()
    todo = []

    def need(names):
        for name in names:
            if name not in seen:
                seen.add(name)
                todo.append(name)

    def keep_statement(k):
        keep[k] = True
        need(_reads(stmts[k][1]))

    setup_read = [False] * len(stmts)
    made_here = {name for name, ks in bound_by.items()
                 if any(not isinstance(stmts[k][1], (ast.Import, ast.ImportFrom)) for k in ks)}
    for k in range(len(stmts)):
        node = stmts[k][1]
        if keep[k] and not isinstance(node, SETUP):
            need(_reads(node))
        elif _registered(node, made_here):      # its decorator may file it anywhere: a dict, a list
            setup_read[k] = True
            need(_reads(node))
    need([function])
    while todo:                                  # each name and each statement once: linear
        name = todo.pop()
        ks = list(by_name.get(name, ()))
        if name in inert_value:
            g = groups.find(name)
            if g not in seen_groups:
                seen_groups.add(g)
                ks += by_group.get(g, ())
        for k in ks:
            if isinstance(stmts[k][1], SETUP):
                if not setup_read[k]:            # a definition the function needs: what it reads
                    setup_read[k] = True
                    need(_reads(stmts[k][1]))
            elif not keep[k]:
                keep_statement(k)
    return [(label, text) for k, ((label, _), text) in enumerate(zip(stmts, texts)) if keep[k] and text is not None]
