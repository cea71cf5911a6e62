"""Grading judges the function the kernel defined, however the notebook binds it: a class of
generated honest variants (autograde/classes/variants.py) of the six graded functions, each the
instructor's answer rewritten through one or two of the ways Python binds and mutates module
state (stores, binders, wraps, implementations, ``__future__`` annotations, try/except imports,
split cells), really executed in kernels and graded as one class. Every variant earns the full
automatic points of its notebook (what the instructor's solutions earn, tests/test_honest_class.py)
and the tripwire fires on none.

The class is drawn with a fixed seed (``SEED``): ``N`` hand-ins, one notebook each (02, 03, 04, 06
or 07, in turn; a notebook 03 hand-in carries a variant of each of its two functions), chosen so that
every kind appears at least once. A failure prints each variant's recipe, points and verdict; the
same class, or a larger one, is built and graded on demand with

    python -m autograde.classes.variants OUT.zip --n 20 --seed 0 --grade COURSE_DIR

The in-process tests check the generator itself, without kernels: every variant, drawn at random
or in the class, computes the instructor's numbers on every hidden case.
"""

import random

import pytest

from autograde.classes import variants

SEED = 0
N = 20                 # hand-ins: 24 variants (the four notebook 03 hand-ins carry two)
TIMEOUT = 120          # seconds per cell, as tests/test_lms_intake.py: a loaded machine must not time out a cell


def all_kinds() -> set[str]:
    out = {f"store:{s}" for s in variants.STORES}
    out |= {f"binder:{b}" for bs in variants.BINDERS.values() for b in bs}
    out |= {f"impl:{i}" for i in variants.IMPLS} | {f"mod:{m}" for m in variants.MODS}
    out |= {f"wrap:{w}" for w in variants.WRAPS if w != "none"}
    out |= {f"fmt:{f}" for f in variants.FILE_FORMATS} | {f"path:{p}" for p in variants.FILE_PATHS}
    out |= {f"call:{c}" for c in variants.CALLS} | {"future_at:cell", "future_at:own"}
    return out


@pytest.fixture(scope="module")
def ci_class():
    return variants.draw_class(N, SEED)


# --- the generator, without kernels ----------------------------------------------------------------------
def test_the_class_covers_every_kind_with_distinct_variants(ci_class):
    s = variants.summary(ci_class)
    print(f"{s['hand-ins']} hand-ins, {s['variants']} variants, {s['distinct']} distinct, {len(s['kinds'])} kinds")
    turns = sorted(variants.NOTEBOOK_FUNCTIONS)                        # the notebooks take turns
    assert s["distinct"] == s["variants"] == sum(len(variants.NOTEBOOK_FUNCTIONS[turns[i % len(turns)]])
                                                 for i in range(N))
    assert set(s["kinds"]) == all_kinds(), sorted(all_kinds() - set(s["kinds"]))
    bare = {r.binder for rs in ci_class for r in rs if r.wrap == "none"}        # no block keeps them whole
    assert bare == {b for bs in variants.BINDERS.values() for b in bs}
    assert variants.draw_class(N, SEED) == ci_class                  # the seed decides the class
    for rs in ci_class:                                                 # a recipe reproduces its variant
        for r in rs:
            assert variants.Recipe.from_json(r.to_json()) == r


def test_every_variant_of_the_class_computes_the_answer(ci_class, tmp_path):
    """Run as IPython runs cells (``__future__`` flags carried), judged by the hidden tests."""
    for k, rs in enumerate(ci_class):
        for j, r in enumerate(rs):
            (tmp_path / f"{k}_{j}").mkdir()
            ok, message = variants.check_in_process(r, tmp_path / f"{k}_{j}")
            assert ok, (r.label(), message, variants.render(r))


@pytest.mark.parametrize("seed", range(3))
def test_random_variants_compute_the_answer(seed, tmp_path):
    """Variants drawn at random, up to every axis at once, are honest too: the generator's own
    property test (what a failure of the class in kernels means depends on it)."""
    rng = random.Random(1000 + seed)
    for k in range(40):
        r = variants.draw(rng, depth=(1, len(variants.AXES)))
        (tmp_path / str(k)).mkdir()
        ok, message = variants.check_in_process(r, tmp_path / str(k))
        assert ok, (r.label(), message, variants.render(r))


# --- the class, executed in kernels and graded -----------------------------------------------------------
@pytest.fixture(scope="module")
def graded(executed_solutions, ci_class, tmp_path_factory):
    from autograde import grade

    tmp = tmp_path_factory.mktemp("variants")
    subs = variants.write_zip(tmp / "class.zip", ci_class, executed_solutions, tmp / "learners")
    course = tmp / "course"
    course.mkdir()
    report = grade.grade_class(subs, course, timeout=TIMEOUT, log=print, progress=False)
    rows = variants.verdicts(course, report, ci_class)
    variants.print_rows(rows)
    bad = variants.failing_kinds(rows)
    print(f"{sum(r['ok'] for r in rows)} of {len(rows)} variants earned full marks with no tripwire; "
          f"{variants.summary(ci_class)['distinct']} distinct variants ran")
    for kind, (b, n) in bad.items():
        print(f"  {kind}: {b} of {n} failed")
    return report, rows


@pytest.mark.parametrize("student", range(N), ids=variants.student_id)
def test_every_variant_earns_full_marks_and_no_tripwire(graded, student):
    report, rows = graded
    sid = variants.student_id(student)
    mine = [r for r in rows if r["student"] == sid]
    assert mine, sid
    why = "\n".join(f"{r['recipe']}\n  points {r['points']}/{r['max']}, order {r['order']}, "
                    f"tripwires {r['tripwires']}\n  verdict: {r['verdict']}" for r in mine)
    assert sid in report, why
    assert not report[sid].get("failed"), (report[sid]["failed"], why)
    for r in mine:
        assert r["points"] is not None and r["points"] == r["max"], why
        assert all(s == m for s, m in r["order"].values()), why
    assert not (report[sid].get("tripwires") or []), why
    assert not any("no credit" in n for n in report[sid]["notes"]), (report[sid]["notes"], why)


def test_the_instructor_is_asked_to_read_only_code_that_binds_names_at_run_time(graded, ci_class):
    """Full marks stand either way; but a flag for the instructor (the delegation check cannot
    tell what the function reaches) costs a human's time, so it is for hand-ins whose code binds
    names it does not spell (``setattr``, ``globals()``; in notebook 03 the losses reach the
    lambda-return through their default argument, so either variant's code counts), never for plain
    assignments, classes, decorators or files."""
    _, rows = graded
    flagged = {row["student"]: row for row in rows if row["flags"]}
    print(f"{len(flagged)} of {len(ci_class)} hand-ins flagged for the instructor")
    for i, recipes in enumerate(ci_class):
        sid = variants.student_id(i)
        if sid in flagged:
            assert any(variants.binds_at_run_time(r) for r in recipes), (
                sid, [r.label() for r in recipes], flagged[sid]["flags"])
