"""The delegation check judges the graded function, not the notebook (autograde/delegation.py).

For every graded function of the chapter, generated notebooks: honest ones (the instructor's
answer, with scratch cells that compare it with the package's in every way a learner writes
that, helper classes whose methods share the name) must never be flagged; delegating ones (the
answer handing its work to the package's implementation, directly or through helpers, aliases,
strings spelled out at run time, ``__wrapped__``) must always be; run-time lookups the grader
cannot read are only noted.
"""

import itertools
from pathlib import Path

import nbformat
import pytest

from autograde import cellcode
from autograde import checks
from autograde import delegation

ROOT = Path(__file__).resolve().parents[1]


def delegations(test, cells):
    """The check as the grader runs it, with the release version of the notebook."""
    release = nbformat.read(ROOT / "notebooks" / f"{test.notebook}.ipynb", as_version=4)
    return delegation.delegations(test, cells, release)


def solution_cells(test):
    """The solution notebook's cells up to and including the test cell, plus the cells after it."""
    nb = nbformat.read(ROOT / "solutions" / f"{test.notebook}.ipynb", as_version=4)
    return nb.cells


def index_of_answer(cells, test):
    return next(i for i, c in enumerate(cells) if cellcode.gid(c) == test.test_id[:-len("_tests")])


def index_of_tests(cells, test):
    return next(i for i, c in enumerate(cells) if cellcode.gid(c) == test.test_id)


def module_of(test):
    return test.reference.split(":")[0]


def with_cell(cells, at, src):
    cells = list(cells)
    cells.insert(at, nbformat.v4.new_code_cell(src))
    return cells


def scratch_forms(test):
    """Ways a learner compares their answer with the package's in a scratch cell."""
    mod, fn = module_of(test), test.function
    short = mod.split(".")[-1]
    return [
        f"from {mod} import {fn} as package_{fn}\nprint(package_{fn})\n",
        f"import {mod}\nprint({mod}.{fn}, {fn})\n",
        f"import {mod} as ref\nprint(getattr(ref, '{fn}'))\n",
        f"from pusht import {short}\ntheirs = {short}.{fn}\nprint(theirs is {fn})\n",
        f"def compare(*args):\n    import {mod}\n    return {mod}.{fn}(*args), {fn}(*args)\n",
        f"class Check:\n    def {fn}(self, *args):\n        return {fn}(*args)\n\n    def package(self, *args):\n"
        f"        from {mod} import {fn}\n        return {fn}(*args)\n",
        f"%%time\nimport {mod}\nx = {mod}.{fn}\n",
    ]


def delegating_bodies(test):
    """Graded functions that hand the work to the package's implementation."""
    mod, fn = module_of(test), test.function
    return [
        (f"from {mod} import {fn} as _theirs\n\n\ndef {fn}(*args, **kw):\n    return _theirs(*args, **kw)\n", ""),
        (f"import {mod}\n\n\ndef {fn}(*args, **kw):\n    return {mod}.{fn}(*args, **kw)\n", ""),
        (f"import importlib\n_m = importlib.import_module('{mod[:6]}' + '{mod[6:]}')\n_f = getattr(_m, '{fn[:3]}' + '{fn[3:]}')\n"
         f"\n\ndef {fn}(*args, **kw):\n    return _f(*args, **kw)\n", ""),
        (f"import {mod}\n\n\ndef {fn}(*args, **kw):\n    return {mod}.{fn}.__wrapped__(*args, **kw)\n", ""),
        (f"def _core(*args):\n    from {mod} import {fn} as f\n    return f(*args)\n\n\n"
         f"def {fn}(*args):\n    return _core(*args)\n", ""),
        (f"class _Impl:\n    def __call__(self, *args):\n        import {mod}\n        return {mod}.{fn}(*args)\n\n\n"
         f"{fn} = _Impl()\n", ""),
        (f"import {mod}\n{fn} = {mod}.{fn}\n", ""),
    ]


TESTS = sorted(checks.TESTS.values(), key=lambda t: t.test_id)


@pytest.mark.parametrize("test", TESTS, ids=lambda t: t.test_id)
def test_the_instructors_answer_is_not_flagged(test):
    found = delegations(test, solution_cells(test))
    assert not found.definite and not found.ambiguous, found


@pytest.mark.parametrize("test", TESTS, ids=lambda t: t.test_id)
def test_scratch_cells_comparing_with_the_package_are_not_delegation(test):
    cells = solution_cells(test)
    impl, tests = index_of_answer(cells, test), index_of_tests(cells, test)
    for form, where in itertools.product(scratch_forms(test), ("after_answer", "before_answer", "after_tests")):
        at = {"after_answer": impl + 1, "before_answer": impl, "after_tests": tests + 1}[where]
        found = delegations(test, with_cell(cells, at, form))
        # a `from pusht... import <name>` before the answer is shadowed by the answer: fine too
        assert not found.definite, (where, form, found.definite)


@pytest.mark.parametrize("test", TESTS, ids=lambda t: t.test_id)
def test_an_answer_that_hands_the_work_to_the_package_is_always_found(test):
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    for body, _ in delegating_bodies(test):
        changed = list(cells)
        changed[impl] = nbformat.v4.new_code_cell(body, metadata=cells[impl].metadata)
        found = delegations(test, changed)
        assert found.definite, (test.test_id, body)


@pytest.mark.parametrize("test", TESTS, ids=lambda t: t.test_id)
def test_an_import_that_rebinds_the_name_before_the_test_is_found(test):
    """The name the test hands over is the package's: the learner's own definition is not tested."""
    cells = solution_cells(test)
    mod, fn = module_of(test), test.function
    found = delegations(test, with_cell(cells, index_of_tests(cells, test), f"from {mod} import {fn}\n"))
    assert found.definite and "when the test runs" in found.definite[0]
    after = delegations(test, with_cell(cells, index_of_tests(cells, test) + 1, f"from {mod} import {fn}\n"))
    assert not after.definite          # after the test: it was not what the test ran


def test_a_lookup_the_grader_cannot_read_is_only_noted():
    test = checks.TESTS["reward_impl_tests"]
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    changed = list(cells)
    changed[impl] = nbformat.v4.new_code_cell(
        "import pusht.reward\nNAME = input()\n\n\ndef reward_from_obs(norm_obs, mean, std):\n"
        "    return getattr(pusht.reward, NAME)(norm_obs, mean, std)\n", metadata=cells[impl].metadata)
    found = delegations(test, changed)
    assert not found.definite and found.ambiguous and "getattr" in found.ambiguous[0]


def test_a_local_that_shares_a_name_with_a_scratch_alias_is_the_learners_own():
    test = checks.TESTS["reward_impl_tests"]
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    cells = with_cell(cells, impl, "import pusht.reward\nref = pusht.reward.reward_from_obs\n")
    answer = cellcode.source(cells[impl + 1]).replace("    obs = norm_obs", "    ref = 1.0\n    obs = ref * norm_obs")
    cells[impl + 1] = nbformat.v4.new_code_cell(answer, metadata=cells[impl + 1].metadata)
    assert not delegations(test, cells).definite


def test_the_grading_harness_patched_by_hand_is_found_and_looked_at_is_noted():
    test = checks.TESTS["reward_impl_tests"]
    cells = solution_cells(test)
    for src in ("import pusht\npusht.grading._PROBING = False\n",
                "from pusht import grading\ngrading.submit = lambda *a: None\n",
                "import importlib\n_g = importlib.import_module('pusht.' + 'grad' + 'ing')\nsetattr(_g, 'submit', print)\n"):
        found = delegations(test, with_cell(cells, len(cells), src))
        assert found.definite and "grading harness" in found.definite[0], src
    for src in ("import pusht.grading\nhelp(pusht.grading)\n", "pusht.grading??\n",
                "print('graded by pusht.grading, outside the kernel')\n"):
        found = delegations(test, with_cell(cells, len(cells), src))
        assert not found.definite and "grading harness" in found.ambiguous[0], src


# Honest code a learner writes in or around the graded function: never a finding, never a note.
HONEST_ANSWERS = {
    "a match statement whose capture shares a scratch alias's name": (
        "import pusht.reward\nref = pusht.reward.reward_from_obs\n",
        "    match 1:\n        case ref:\n            pass\n"),
    "a tolerance computed once with the package, read by the answer": (
        "import pusht.reward\nTOL = float(pusht.reward.reward_from_obs(torch.zeros(6), 0, 1)[0]) * 0 + 1e-6\n",
        "    assert TOL > 0\n"),
    "torch.compile and re.compile on the learner's own helpers": (
        "import re\n_pat = re.compile('x')\n\n\ndef _double(x):\n    return 2 * x\n\n\n_fast = torch.compile(_double)\n",
        "    _pat.match('x')\n"),
    "getattr on the learner's own object with a computed name": (
        "class _Cfg:\n    scale = 1.0\n\n    def get(self, name):\n        return getattr(self, name)\n",
        "    _Cfg().get('sca' + 'le')\n"),
    "a debug print of locals()": ("", "    print(len(locals()))\n"),
}


@pytest.mark.parametrize("case", sorted(HONEST_ANSWERS))
def test_honest_code_around_the_answer_is_neither_found_nor_noted(case):
    test = checks.TESTS["reward_impl_tests"]
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    before, inside = HONEST_ANSWERS[case]
    answer = cellcode.source(cells[impl]).replace("    obs = norm_obs", inside + "    obs = norm_obs", 1)
    changed = list(cells)
    changed[impl] = nbformat.v4.new_code_cell(answer, metadata=cells[impl].metadata)
    if before:
        changed.insert(impl, nbformat.v4.new_code_cell(before))
    found = delegations(test, changed)
    assert not found.definite and not found.ambiguous, (case, found)


# Ways to reach the reference that must be a finding (F) or at least a note (N), whatever the test.
REACHING = [
    ("F", "import {mod}\n{fn} = {mod}.{fn}\n{fn} = {fn}.__wrapped__\n"),
    ("F", "import {mod}\n_m = {{'r': {mod}}}['r']\n\n\ndef {fn}(*a):\n    return _m.{fn}(*a)\n"),
    ("F", "import {mod}\n\n\ndef {fn}(*a, m={mod}):\n    return m.{fn}(*a)\n"),
    ("F", "import {mod}\n\n\nclass K:\n    m = {mod}\n\n\ndef {fn}(*a):\n    return K.m.{fn}(*a)\n"),
    ("F", "import {mod}\n\n\ndef {fn}(*a):\n    m = {mod} if a else None\n    return m.{fn}(*a)\n"),
    ("F", "import {mod}\nif (_f := {mod}.{fn}):\n    pass\n\n\ndef {fn}(*a):\n    return _f(*a)\n"),
    ("F", "def _setup():\n    global {fn}\n    from {mod} import {fn}\n\n\n_setup()\n"),
    ("N", "import {mod}\n_ga = getattr\n\n\ndef {fn}(*a):\n    return _ga({mod}, input())(*a)\n"),
    ("N", "import pickle\n\n\ndef {fn}(*a):\n    return pickle.loads(b'')(*a)\n"),
    ("N", "import {mod}\nglobals()['{fn}'] = {mod}.{fn}\n"),
    ("N", "exec('def {fn}(*a): return 0')\n"),
    ("N", "import {mod}\n\n\ndef {fn}(*a):\n    if a[0] is None:\n        return {mod}.{fn}(*a)\n    return a[0]\n"),
]


@pytest.mark.parametrize("test", TESTS, ids=lambda t: t.test_id)
def test_every_way_of_reaching_the_reference_is_found_or_noted(test):
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    for kind, form in REACHING:
        src = form.format(mod=module_of(test), fn=test.function)
        changed = list(cells)
        changed[impl] = nbformat.v4.new_code_cell(src, metadata=cells[impl].metadata)
        found = delegations(test, changed)
        if kind == "F":
            assert found.definite, (test.test_id, src, found)
        else:
            assert not found.definite and found.ambiguous, (test.test_id, src, found)


def test_a_notebook_too_tangled_to_follow_is_noted_never_found_and_never_stops_grading():
    test = checks.TESTS["reward_impl_tests"]
    cells = solution_cells(test)
    impl = index_of_answer(cells, test)
    chain = "".join(f"def _h{k}(x):\n    return _h{k + 1}(x)\n" for k in range(1500)) + "def _h1500(x):\n    return x\n"
    changed = list(cells)
    changed[impl] = nbformat.v4.new_code_cell(chain + "\n\ndef reward_from_obs(*a):\n    return _h0(a)\n",
                                              metadata=cells[impl].metadata)
    found = delegations(test, changed)
    assert not found.definite and found.ambiguous
    for bad in ({"cell_type": "code", "source": None, "metadata": "x"}, {"cell_type": "code", "source": 5},
                {"cell_type": "code", "source": "1" + "+1" * 5000}, "not a cell"):
        delegations(test, list(cells) + [bad])            # no exception
