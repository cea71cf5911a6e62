"""Does the graded function reach the package's own implementation of what it was asked to write?

A learner asked to write ``reward_from_obs`` earns nothing for a ``reward_from_obs`` that hands the
work to ``pusht.reward.reward_from_obs``. But checking your own work against the package in a
scratch cell is good practice, and a helper method that happens to share the name is nobody's
business. So the question is asked of the graded function, not of the notebook:

1. the notebook's code cells up to the test cell are read as the kernel runs them (``cellcode``),
   statement by statement in order, keeping what each top-level name is bound to (a later
   definition replaces an earlier one; one inside ``if``/``try``/``for`` may or may not have run,
   so both are kept). A value assigned at top level is read with the names as they were bound at
   that moment; a function's body with the names as they are when the test runs;
2. from the name the test hands to the grader, everything the function can reach is followed:
   the names its body reads (its own locals with what they were given), the functions and classes
   those are bound to (a class: all its methods and attributes), the values of module-level
   variables, imports, containers;
3. a name or attribute chain that resolves, through imports and ``getattr``/``import_module``
   with names the code spells out (``'reward_' + 'from_obs'`` included), to the package's
   implementation of this exercise, or the function it wraps, is a **finding**: the test earns
   nothing, and the feedback says where. So is an import that rebinds the graded name to the
   package's before the test runs;
4. what cannot be read without running it is **ambiguous**: the score stands and report.csv asks
   the instructor to look. That is reachable code that looks names up at run time (``getattr``
   with a computed name, ``eval``/``exec``, ``globals()``, ``sys.modules``, ``__dict__``,
   ``__wrapped__``, ``pickle``...), a reference to the package's implementation only under an
   ``if`` (a learner's own check, switched on or off), a graded name with no definition the
   grader can read (made by ``exec``, imported from a file the notebook wrote), and top-level
   code of the learner's that rebinds names by hand (``globals()[...] =``, ``setattr``);
   a value computed at top level by calling the package (a tolerance, a test input) is not a
   reference to it.

References to the grading harness itself (``pusht.grading``, its old switch, the marks) in
the learner's own cells are findings when the cell also writes something by hand (an attribute,
``setattr``, ``exec``) or the graded function reaches them, and ambiguous otherwise (a curious
``help(pusht.grading)``).

What this cannot see: code reached only through the package's own functions (a package function
that calls the reference inside it), and objects built at run time in ways rule 4 does not list.
In the probe process that decides the verdict (``probe.py``) the package's implementation does not
exist (``stripped.py``), so a call to it earns nothing either; this check is what explains why. A notebook too large or too tangled to follow within a fixed
budget is reported as ambiguous, never as a finding, and the check never stops the grading.
"""

from __future__ import annotations

import ast
import importlib
import inspect
from dataclasses import dataclass, field

from . import cellcode, checks

HARNESS_WORDS = ("pusht.grading", "pusht.grader", "pusht.reference", "PUSHT_GRADING", "_PROBING", "__pusht_reference__", "ReferenceRefused")
# Called by bare name: Python's own ways of reaching a name at run time.
DYNAMIC_BUILTINS = {"eval", "exec", "compile", "globals", "vars", "getattr", "__import__", "setattr"}
# Called by name or as an attribute: the library's ways.
DYNAMIC_FUNCTIONS = {"import_module", "attrgetter", "methodcaller", "unwrap", "resolve_name", "reload",
                     "getmembers", "module_from_spec", "exec_module", "run_module", "run_path", "loads",
                     "find_spec", "spec_from_file_location", "get_ipython", "getattr_static"}
DYNAMIC_ATTRS = {"__dict__", "__getattribute__", "__builtins__", "__closure__", "__globals__", "f_globals",
                 "f_back", "user_ns", "__wrapped__", "__code__", "__func__"}
BUDGET = 200_000          # steps of following one graded function; beyond: ambiguous, not a finding


@dataclass
class Findings:
    definite: list[str] = field(default_factory=list)    # the graded function reaches the reference
    ambiguous: list[str] = field(default_factory=list)   # it might; for the instructor to look at

    def __bool__(self) -> bool:
        return bool(self.definite or self.ambiguous)


@dataclass(frozen=True, eq=False)
class _Binding:
    kind: str          # "def" (a function or class node), "expr" (a value), "path" (a dotted import)
    value: object      # the AST node, or the dotted path
    cell: int
    line: int
    env: dict | None = None     # "expr": the top-level names as bound when the value was computed


class _TooComplex(Exception):
    pass


def _where(b_or_cell, line=None) -> str:
    if isinstance(b_or_cell, _Binding):
        return f"cell {b_or_cell.cell + 1}, line {b_or_cell.line}"
    return f"cell {b_or_cell + 1}, line {line}"


# --- the reference object, and resolving dotted paths inside the package ----------------------------
def _resolve(path: str):
    """The object a dotted path names inside the ``pusht`` package, or None. Only ``pusht``
    modules are imported (a learner's string never makes the grader import anything else)."""
    parts = path.split(".")
    if parts[0] != "pusht" or len(parts) > 40:
        return None
    obj, i = None, len(parts)
    while i:
        try:
            obj = importlib.import_module(".".join(parts[:i]))
            break
        except Exception:          # noqa: BLE001  not a module (or not importable): an attribute then
            i -= 1
    if obj is None:
        return None
    for name in parts[i:]:
        try:
            obj = inspect.getattr_static(obj, name)
        except Exception:          # noqa: BLE001
            return None
    return obj


def _is_reference(obj, reference) -> bool:
    if obj is None:
        return False
    try:
        return obj is reference or inspect.unwrap(obj) is inspect.unwrap(reference)
    except Exception:              # noqa: BLE001  an object unwrap cannot handle is not ours
        return False


# --- reading the notebook's bindings ----------------------------------------------------------------
class _Env:
    """What each top-level name is bound to, statement by statement."""

    def __init__(self):
        self.names: dict[str, list[_Binding]] = {}

    def bind(self, name: str, b: _Binding, maybe: bool) -> None:
        if maybe and name in self.names:
            self.names[name] = self.names[name] + [b]
        else:
            self.names[name] = [b]

    def expr(self, value, cell: int, line: int) -> _Binding:
        return _Binding("expr", value, cell, line, dict(self.names))

    def statement(self, node, cell: int, maybe: bool = False) -> None:
        line = getattr(node, "lineno", 0)
        for sub in ast.walk(node):               # walrus anywhere in a top-level statement
            if isinstance(sub, ast.NamedExpr) and isinstance(sub.target, ast.Name) and not isinstance(
                    node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
                self.bind(sub.target.id, self.expr(sub.value, cell, line), True)
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            self.bind(node.name, _Binding("def", node, cell, line), maybe)
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.asname:
                    self.bind(a.asname, _Binding("path", a.name, cell, line), maybe)
                else:
                    top = a.name.split(".")[0]
                    self.bind(top, _Binding("path", top, cell, line), maybe)
        elif isinstance(node, ast.ImportFrom):
            if node.level or not node.module:
                return
            for a in node.names:
                if a.name == "*":
                    for name in _public_names(node.module):
                        self.bind(name, _Binding("path", f"{node.module}.{name}", cell, line), maybe)
                else:
                    self.bind(a.asname or a.name, _Binding("path", f"{node.module}.{a.name}", cell, line), maybe)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if node.value is None:
                return
            b = self.expr(node.value, cell, line)
            for t in targets:
                for name in _target_names(t):
                    self.bind(name, b, maybe or not isinstance(t, ast.Name) or isinstance(node, ast.AugAssign))
        elif isinstance(node, ast.Delete):
            for t in node.targets:
                for name in _target_names(t):
                    if not maybe:
                        self.names.pop(name, None)
        elif isinstance(node, (ast.With, ast.AsyncWith)):
            for item in node.items:
                if item.optional_vars is not None:
                    for name in _target_names(item.optional_vars):
                        self.bind(name, self.expr(item.context_expr, cell, line), True)
            for s in node.body:
                self.statement(s, cell, maybe)
        elif isinstance(node, (ast.If, ast.For, ast.AsyncFor, ast.While, ast.Try, getattr(ast, "TryStar", ast.Try))):
            if isinstance(node, (ast.For, ast.AsyncFor)):
                for name in _target_names(node.target):
                    self.bind(name, self.expr(node.iter, cell, line), True)
            for field_name in ("body", "orelse", "finalbody"):
                for s in getattr(node, field_name, []):
                    self.statement(s, cell, True)
            for h in getattr(node, "handlers", []):
                for s in h.body:
                    self.statement(s, cell, True)
        elif isinstance(node, ast.Match):
            for case in node.cases:
                for name in _pattern_names(case.pattern):
                    self.bind(name, self.expr(node.subject, cell, line), True)
                for s in case.body:
                    self.statement(s, cell, True)

    def globals_assigned_in_functions(self, tree, cell: int) -> None:
        """``global x; x = ...`` (or ``import ... as x``) inside a function may rebind ``x`` whenever
        it is called: kept as a possibility."""
        for fn in ast.walk(tree):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            declared = {n for s in ast.walk(fn) if isinstance(s, ast.Global) for n in s.names}
            if not declared:
                continue
            for s in ast.walk(fn):
                if isinstance(s, (ast.Assign, ast.AnnAssign, ast.AugAssign)) and s.value is not None:
                    for t in (s.targets if isinstance(s, ast.Assign) else [s.target]):
                        for name in _target_names(t):
                            if name in declared:
                                self.bind(name, self.expr(s.value, cell, s.lineno), True)
                elif isinstance(s, (ast.Import, ast.ImportFrom)) and not getattr(s, "level", 0):
                    for a in s.names:
                        name = a.asname or a.name.split(".")[0]
                        path = (f"{s.module}.{a.name}" if isinstance(s, ast.ImportFrom)
                                else a.name if a.asname else a.name.split(".")[0])
                        if name in declared:
                            self.bind(name, _Binding("path", path, cell, s.lineno), True)


def _target_names(t) -> list[str]:
    if isinstance(t, ast.Name):
        return [t.id]
    if isinstance(t, (ast.Tuple, ast.List)):
        return [n for e in t.elts for n in _target_names(e)]
    if isinstance(t, ast.Starred):
        return _target_names(t.value)
    return []


def _pattern_names(p) -> list[str]:
    """The names a ``case`` pattern captures."""
    names = []
    for sub in ast.walk(p):
        if isinstance(sub, (ast.MatchAs, ast.MatchStar)) and sub.name:
            names.append(sub.name)
        elif isinstance(sub, ast.MatchMapping) and sub.rest:
            names.append(sub.rest)
    return names


def _public_names(module: str) -> list[str]:
    """What ``from module import *`` binds, for the package's modules (others bind nothing we
    need to follow)."""
    if module.split(".")[0] != "pusht":
        return []
    try:
        m = importlib.import_module(module)
    except Exception:              # noqa: BLE001
        return []
    return list(getattr(m, "__all__", [n for n in vars(m) if not n.startswith("_")]))


def _locals_of(fn) -> dict:
    """The names a function (or lambda) binds in its own scope, each with what it is given where
    that can be read: a parameter's default, an assigned value (``("expr", node)``), a local
    import's dotted path; None otherwise. Not those declared global or nonlocal, not those of
    functions nested in it."""
    args = fn.args
    params = args.posonlyargs + args.args
    defaults = dict(zip([a.arg for a in params][len(params) - len(args.defaults):], args.defaults))
    defaults |= {a.arg: d for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None}
    names: dict = {a.arg: ("expr", defaults[a.arg]) if a.arg in defaults else None
                   for a in params + args.kwonlyargs}
    names |= {a.arg: None for a in (args.vararg, args.kwarg) if a is not None}
    declared = set()

    def add(name, value):
        old = names.get(name)
        names[name] = value if name not in names else ("any", [old, value])

    todo = list(fn.body) if isinstance(fn.body, list) else [fn.body]
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            add(node.name, None)
            continue
        if isinstance(node, ast.Lambda):
            continue
        if isinstance(node, (ast.Global, ast.Nonlocal)):
            declared |= set(node.names)
        if isinstance(node, (ast.Assign, ast.AnnAssign, ast.NamedExpr)) and getattr(node, "value", None) is not None:
            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                for name in _target_names(t):
                    add(name, ("expr", node.value))
        elif isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            add(node.id, None)
        if isinstance(node, ast.Import):
            for a in node.names:
                add(a.asname or a.name.split(".")[0], a.name if a.asname else a.name.split(".")[0])
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for a in node.names:
                if a.name != "*":
                    add(a.asname or a.name, f"{node.module}.{a.name}")
        if isinstance(node, ast.ExceptHandler) and node.name:
            add(node.name, None)
        for name in _pattern_names(node) if isinstance(node, ast.match_case) else ():
            add(name, None)
        todo.extend(ast.iter_child_nodes(node))
    return {k: v for k, v in names.items() if k not in declared}


# --- following the graded function ------------------------------------------------------------------
class _Reach:
    def __init__(self, env: _Env, reference):
        self.env, self.reference = env, reference
        self.findings = Findings()
        self.seen: set = set()
        self.reported: set[tuple] = set()       # (cell, line) already named in a finding
        self.harness: list[tuple] = []          # (cell, line, word) of harness references reached
        self.steps = 0
        self.memo: dict = {}
        self.called: set[int] = set()           # ids of nodes that are the function of a call

    def tick(self) -> None:
        self.steps += 1
        if self.steps > BUDGET:
            raise _TooComplex

    # what an expression names
    def lookup(self, name: str, scope: dict, env: dict | None):
        """(local value or None, top-level bindings) of a name read in ``scope`` under ``env``."""
        if name in scope:
            return scope[name], []
        return None, (env if env is not None else self.env.names).get(name, [])

    def paths(self, node, scope: dict, env: dict | None = None, depth: int = 0) -> set[str]:
        """Dotted package paths an expression may evaluate to (empty: none we can name)."""
        if scope:
            return self._paths(node, scope, env, depth)
        key = (id(node), id(env))           # a top-level value: the same answer every time
        if key not in self.memo:
            self.memo[key] = set()           # a value that reads itself names nothing more
            self.memo[key] = self._paths(node, scope, env, depth)
        return self.memo[key]

    def _paths(self, node, scope: dict, env: dict | None, depth: int) -> set[str]:
        self.tick()
        if depth > 30:
            return set()
        d = depth + 1
        if isinstance(node, ast.Name):
            local, bound = self.lookup(node.id, scope, env)
            if node.id in scope:
                return self.local_paths(local, scope, env, d)
            out = set()
            for b in bound:
                if b.kind == "path":
                    out.add(b.value)
                elif b.kind == "expr":
                    out |= self.paths(b.value, {}, b.env, d)
            return out
        if isinstance(node, ast.Attribute):
            out = {f"{p}.{node.attr}" for p in self.paths(node.value, scope, env, d)}
            for cls in self.classes(node.value, scope, env):
                for s in cls.body:
                    if isinstance(s, (ast.Assign, ast.AnnAssign)) and s.value is not None and any(
                            node.attr in _target_names(t) for t in (s.targets if isinstance(s, ast.Assign) else [s.target])):
                        out |= self.paths(s.value, {}, env, d)
            return out
        if isinstance(node, ast.Call):
            name = _func_name(node.func)
            if name == "getattr" and len(node.args) >= 2:
                attr = self.text(node.args[1], scope, env)
                if attr is not None:
                    return {f"{p}.{attr}" for p in self.paths(node.args[0], scope, env, d)}
            if name in ("import_module", "__import__", "resolve_name") and node.args:
                mod = self.text(node.args[0], scope, env)
                if mod is not None:
                    return {mod.replace(":", ".")}
            if name == "unwrap" and node.args:
                return {f"{p}.__wrapped__" for p in self.paths(node.args[0], scope, env, d)}
            if name in ("partial", "wraps", "staticmethod", "classmethod") and node.args:
                return self.paths(node.args[0], scope, env, d)
            return set()
        if isinstance(node, ast.Subscript):
            key = self.text(node.slice, scope, env)
            if key is not None and _func_name(node.value) == "modules":
                return {key}
            return self.paths(node.value, scope, env, d)        # an element of a container
        if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
            return set().union(*(self.paths(e, scope, env, d) for e in node.elts)) if node.elts else set()
        if isinstance(node, ast.Dict):
            return set().union(*(self.paths(v, scope, env, d) for v in node.values)) if node.values else set()
        if isinstance(node, ast.IfExp):
            return self.paths(node.body, scope, env, d) | self.paths(node.orelse, scope, env, d)
        if isinstance(node, ast.BoolOp):
            return set().union(*(self.paths(v, scope, env, d) for v in node.values))
        if isinstance(node, (ast.NamedExpr, ast.Starred)):
            return self.paths(node.value, scope, env, d)
        return set()

    def local_paths(self, local, scope, env, depth) -> set[str]:
        if local is None:
            return set()
        if isinstance(local, str):
            return {local}
        kind, value = local
        if kind == "expr":
            return self.paths(value, scope, env, depth)
        return set().union(*(self.local_paths(v, scope, env, depth) for v in value))

    def classes(self, node, scope, env) -> list:
        """The learner's classes an expression names (``K``), for their class attributes."""
        if not isinstance(node, ast.Name) or node.id in scope:
            return []
        return [b.value for b in self.lookup(node.id, scope, env)[1]
                if b.kind == "def" and isinstance(b.value, ast.ClassDef)]

    def text(self, node, scope: dict, env: dict | None = None, depth: int = 0) -> str | None:
        """A string the code spells out: a literal, literals joined with + or an f-string or
        ``str.join``, or a name bound to one."""
        self.tick()
        if depth > 30:
            return None
        d = depth + 1
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return node.value
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
            a, b = self.text(node.left, scope, env, d), self.text(node.right, scope, env, d)
            return a + b if a is not None and b is not None else None
        if isinstance(node, ast.JoinedStr):
            parts = [self.text(v.value if isinstance(v, ast.FormattedValue) else v, scope, env, d)
                     for v in node.values]
            return "".join(parts) if all(p is not None for p in parts) else None
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "join"
                and len(node.args) == 1 and isinstance(node.args[0], (ast.List, ast.Tuple))):
            sep = self.text(node.func.value, scope, env, d)
            parts = [self.text(e, scope, env, d) for e in node.args[0].elts]
            return sep.join(parts) if sep is not None and all(p is not None for p in parts) else None
        if isinstance(node, ast.Name):
            local, bound = self.lookup(node.id, scope, env)
            if node.id in scope:
                return self.text(local[1], scope, env, d) if isinstance(local, tuple) and local[0] == "expr" else None
            values = {self.text(b.value, {}, b.env, d) for b in bound if b.kind == "expr"}
            if len(bound) == 1 and len(values) == 1:
                return values.pop()
        return None

    # walking what the graded function reaches
    def visit_binding(self, b: _Binding) -> None:
        key = (id(b.value), b.cell, b.line) if b.kind != "path" else (b.value, b.cell, b.line)
        if key in self.seen:
            return
        self.seen.add(key)
        if b.kind == "path":
            if _is_reference(_resolve(b.value), self.reference):
                self.definite(b.cell, b.line, f"`{b.value}` is the package's implementation")
            return
        if b.kind == "expr":           # computed once, at top level: what it calls is not reached
            self.visit(b.value, b.cell, {}, b.env, toplevel=True)
        else:
            self.visit(b.value, b.cell, {}, None)

    def definite(self, cell, line, what, cond=False) -> None:
        if (cell, line) in self.reported:
            return
        self.reported.add((cell, line))
        if cond:
            self.findings.ambiguous.append(f"{_where(cell, line)}: {what}, but only under a condition "
                                           f"(a check of the learner's own, switched on or off?)")
        else:
            self.findings.definite.append(f"{_where(cell, line)}: {what}")

    def visit(self, node, cell: int, scope: dict, env: dict | None, toplevel=False, cond=False) -> None:
        """Everything ``node`` reaches, with ``scope`` the local names around it, ``env`` the
        top-level names it sees (None: as when the test runs)."""
        self.tick()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            for d in getattr(node, "decorator_list", []) + node.args.defaults + \
                    [d for d in node.args.kw_defaults if d is not None]:
                self.visit(d, cell, scope, env, toplevel, cond)
            inner = scope | _locals_of(node)
            for s in (node.body if isinstance(node.body, list) else [node.body]):
                self.visit(s, cell, inner, None, False, cond)      # run when called: the test's names
            return
        if isinstance(node, ast.ClassDef):
            for d in node.decorator_list + node.bases + [k.value for k in node.keywords]:
                self.visit(d, cell, scope, env, toplevel, cond)
            body_scope = scope | {s.name: None for s in node.body
                                  if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))}
            for s in node.body:
                # a method's free names are the module's, not the class body's
                self.visit(s, cell, scope if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef)) else body_scope,
                           env, toplevel, cond)
            return
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            for path in _words(node):
                if _is_reference(_resolve(path), self.reference):
                    self.definite(cell, node.lineno, f"imports `{path}`, the package's implementation", cond)
            return
        line = getattr(node, "lineno", "?")
        for word in _words(node):
            hit = next((w for w in HARNESS_WORDS if w in word), None)
            if hit:
                self.harness.append((cell, line, hit))
        self.check(node, cell, scope, env, toplevel, cond)
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
            local, bound = self.lookup(node.id, scope, env)
            if node.id not in scope:
                for b in bound:
                    self.visit_binding(b)
        if isinstance(node, (ast.If, ast.IfExp, ast.While)) and not (
                isinstance(node.test, ast.Constant) and node.test.value):
            self.visit(node.test, cell, scope, env, toplevel, cond)
            for part in (node.body, node.orelse):
                for s in (part if isinstance(part, list) else [part]):
                    self.visit(s, cell, scope, env, toplevel, True)
            return
        if isinstance(node, ast.Call):
            self.called.add(id(node.func))
        for child in ast.iter_child_nodes(node):
            if toplevel and isinstance(node, ast.Call) and child is node.func and not self.learners(child, scope, env):
                continue       # the package called once at top level: its result is the value, not it
            self.visit(child, cell, scope, env, toplevel, cond)

    def learners(self, node, scope, env) -> bool:
        """Is ``node`` a name bound to one of the learner's own functions or classes?"""
        return isinstance(node, ast.Name) and node.id not in scope and any(
            b.kind == "def" for b in self.lookup(node.id, scope, env)[1])

    def check(self, node, cell: int, scope: dict, env, toplevel, cond) -> None:
        line = getattr(node, "lineno", "?")
        if isinstance(node, (ast.Attribute, ast.Call, ast.Subscript)):
            for p in self.paths(node, scope, env):
                if _is_reference(_resolve(p), self.reference):
                    self.definite(cell, line, f"`{p}` is the package's implementation", cond)
                    return
        dyn = _dynamic(node, lambda n: self.paths(n, scope, env), lambda n: self.text(n, scope, env), scope)
        if (isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and node.id in DYNAMIC_BUILTINS
                and node.id not in scope and id(node) not in self.called):
            dyn = f"`{node.id}` handed on as a value (it looks names up at run time)"
        if dyn:
            self.findings.ambiguous.append(f"{_where(cell, line)}: {dyn}")


def _dynamic(node, paths, text, scope) -> str | None:
    """Why ``node`` reads names in a way that cannot be followed without running it, or None."""
    if isinstance(node, ast.Call):
        name = _func_name(node.func)
        bare = isinstance(node.func, ast.Name)
        if name in ("getattr", "import_module", "__import__", "resolve_name"):
            spelled = node.args[1 if name == "getattr" else 0] if len(node.args) > (name == "getattr") else None
            if spelled is not None and text(spelled) is not None:
                return None
            if name == "getattr" and node.args and isinstance(node.args[0], ast.Name) and \
                    node.args[0].id in scope and not paths(node.args[0]):
                return None            # getattr(self, name): the learner's own object
            return f"`{name}(...)` looks a name up at run time"
        if name == "vars" and not any(paths(a) for a in node.args):
            return None
        if (bare and name in DYNAMIC_BUILTINS) or name in DYNAMIC_FUNCTIONS:
            return f"`{name}(...)` looks a name up at run time"
    elif isinstance(node, ast.Attribute):
        if node.attr in DYNAMIC_ATTRS:
            return f"`.{node.attr}` reaches names at run time"
        if node.attr == "modules" and isinstance(node.value, ast.Name) and node.value.id == "sys":
            return "`sys.modules` looks modules up at run time"
    return None


def _words(node) -> list[str]:
    """The names and strings a node spells: what a reference to the harness would show."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.Attribute):
        try:
            return [ast.unparse(node)]
        except Exception:          # noqa: BLE001
            return [node.attr]
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom):
        return [f"{node.module}.{a.name}" for a in node.names]
    return []


def _func_name(f) -> str | None:
    if isinstance(f, ast.Name):
        return f.id
    if isinstance(f, ast.Attribute):
        return f.attr
    return None


def _hand_writes(tree) -> list[tuple[str, bool]]:
    """What a cell writes by hand: (what, whether it can rebind names unseen) for each attribute or
    item it assigns or deletes and each ``setattr``/``delattr``/``exec`` it calls. Rebinding names
    unseen: writing into ``globals()``, setting an attribute of ``__main__``, ``builtins`` or
    ``sys``, and those calls."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign, ast.Delete)):
            for t in (node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target]):
                if isinstance(t, ast.Subscript):
                    into_globals = _func_name(getattr(t.value, "func", None)) in ("globals", "vars")
                    out.append(("writes into `globals()`" if into_globals else "sets an item", into_globals))
                elif isinstance(t, ast.Attribute):
                    root = t
                    while isinstance(root, ast.Attribute):
                        root = root.value
                    unseen = isinstance(root, ast.Name) and root.id in ("__main__", "builtins", "__builtins__", "sys")
                    out.append((f"sets `{ast.unparse(t)}`", unseen))
        elif isinstance(node, ast.Call) and _func_name(node.func) in ("setattr", "exec", "delattr", "__setattr__"):
            out.append((f"calls `{_func_name(node.func)}`", isinstance(node.func, ast.Name)))
    return out


# --- the check ----------------------------------------------------------------------------------------
def delegations(test, cells, release=None, reference=None) -> Findings:
    """What the graded function ``test.function`` reaches of the package's implementation
    (``test.reference``), read from the notebook's ``cells`` up to the test cell; plus references
    to the grading harness in the learner's own cells (not identical to a cell of ``release``, the
    release version of the notebook, and not one of its locked cells, which nbgrader puts back).
    Never raises on a hand-in: what cannot be read is reported as ambiguous."""
    if reference is None:
        reference = checks.reference_function(test)
    try:
        return _delegations(test, list(cells), release, reference)
    except (_TooComplex, RecursionError, MemoryError):
        return Findings(ambiguous=[f"the notebook is too large or tangled to follow `{test.function}` "
                                   f"through it within the grader's budget"])


def _delegations(test, cells, release, reference) -> Findings:
    release_cells = release.cells if release is not None else []
    release_sources = {cellcode.source(c) for c in release_cells}
    locked_ids = {cellcode.gid(c) for c in release_cells
                  if isinstance(c.get("metadata"), dict) and isinstance(c.metadata.get("nbgrader"), dict)
                  and c.metadata["nbgrader"].get("locked")}
    cells = [c if isinstance(c, dict) else {} for c in cells]
    own = [i for i, c in enumerate(cells) if c.get("cell_type") == "code"
           and cellcode.source(c) not in release_sources and cellcode.gid(c) not in locked_ids]
    stop = next((i for i, c in enumerate(cells) if cellcode.gid(c) == test.test_id), len(cells))
    env = _Env()
    trees = {i: cellcode.parse(cellcode.source(c)) for i, c in enumerate(cells) if c.get("cell_type") == "code"}
    for i in range(stop):
        tree = trees.get(i)
        if tree is None:
            continue
        for node in tree.body:
            env.statement(node, i)
        env.globals_assigned_in_functions(tree, i)
    reach = _Reach(env, reference)
    graded = env.names.get(test.function, [])
    if not graded:
        reach.findings.ambiguous.append(f"`{test.function}` has no definition the grader can read before the "
                                        f"test cell (made by exec, or imported from a file the notebook wrote?)")
    for b in graded:
        if b.kind == "path" and _is_reference(_resolve(b.value), reference):
            reach.findings.definite.append(
                f"{_where(b)}: `{test.function}` is bound to the package's `{b.value}` when the test runs"
                + ("" if len(graded) == 1 else " (your own definition may not be the one tested)"))
        elif b.kind == "path" and b.value.split(".")[0] != "pusht":
            reach.findings.ambiguous.append(f"{_where(b)}: `{test.function}` is imported from `{b.value}`, "
                                            f"which the grader cannot read")
        else:
            reach.visit_binding(b)
    for i in own:
        tree = trees.get(i)
        if tree is None or i >= stop:
            continue
        why = next((what for what, unseen in _hand_writes(tree) if unseen), None)
        if why:
            reach.findings.ambiguous.append(f"cell {i + 1}: {why}, which can rebind names without the grader "
                                            f"seeing it")
    harness_cells = {}
    for i in own:
        tree = trees.get(i)
        for node in ast.walk(tree) if tree is not None else ():
            words = _words(node) + ([t] if isinstance(node, (ast.BinOp, ast.JoinedStr)) and (
                t := reach.text(node, {})) else [])
            hit = next((w for w in HARNESS_WORDS for text in words if w in text), None)
            if hit:
                harness_cells.setdefault(i, (getattr(node, "lineno", "?"), hit))
    for i, (line, hit) in harness_cells.items():
        where = f"{_where(i, line)}: a reference to the grading harness (`{hit}`)"
        if _hand_writes(trees[i]) or any(c == i for c, _, _ in reach.harness):
            reach.findings.definite.append(where)
        else:
            reach.findings.ambiguous.append(where + " that changes nothing the grader can see")
    reach.findings.definite = list(dict.fromkeys(reach.findings.definite))
    reach.findings.ambiguous = list(dict.fromkeys(reach.findings.ambiguous))
    return reach.findings
