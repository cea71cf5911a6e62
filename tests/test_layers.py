"""The package's floors: no import circle but the claims' registry, and the grader's runtime
(``pusht/grader/``) out of the learner's way: nothing else in the package imports it."""

import pkgutil

import pusht
from pusht.stage_cache import PACKAGE, imports

MODULES = sorted(m.name for m in pkgutil.walk_packages(pusht.__path__, "pusht."))
# The one deliberate circle: ``claims.load_all`` imports the notebooks' claim modules so that their
# @claim predicates register, and each of those imports ``claim`` from ``claims``.
REGISTRY = {("pusht.nb.claims", f"pusht.nb.{m}_claims") for m in ("actor", "closing", "gap", "horizon", "planning")}


def graph() -> dict[str, set[str]]:
    return {m: {n for n in imports(m) if n != m and (m, n) not in REGISTRY} for m in MODULES}


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in edges:
        if v not in index:
            visit(v)
    return out


def test_the_package_has_no_import_circle_but_the_claims_registry():
    assert circles(graph()) == []


def test_the_check_finds_a_circle_where_there_is_one():
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({**graph(), **{a: imports(a) - {a} for a, _ in REGISTRY}}) != []   # the registry is one


def test_nothing_outside_the_graders_runtime_imports_it():
    assert "pusht.grader.probes" in MODULES and (PACKAGE / "grader" / "zygote.py").is_file()
    leaks = {m: sorted(n for n in imports(m) if n.startswith("pusht.grader"))
             for m in MODULES if not m.startswith("pusht.grader")}
    assert {m: n for m, n in leaks.items() if n} == {}
