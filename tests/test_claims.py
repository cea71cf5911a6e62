"""Claims about the learner's run (pusht/nb/claims.py) against the table `make claims` recorded.

benchmarks/claims.json holds every claim notebooks 03-06 evaluated on seeds 0-9, with the numbers
each predicate read. Here every predicate is evaluated again on those numbers: a fixed sentence
(``fixed=True``) that is false on a recorded seed fails, a predicate that no longer gives the
recorded outcome fails (its code changed: run make claims again), and so does a registered claim
that no recorded run ever evaluated."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pusht.nb import claims

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "benchmarks" / "claims.json"


@pytest.fixture(scope="module")
def table():
    assert TABLE.exists(), "benchmarks/claims.json is missing: run make claims"
    return json.loads(TABLE.read_text())


@pytest.fixture(scope="module")
def registry():
    return claims.load_all()


# Notebooks 03-06 are recorded on seeds 0-9; notebook 07 (about 7 minutes a seed on two cores, most of
# it five world models and two planners) on seeds 0-5, the seeds of benchmarks/plan_*.csv.
SEEDS = {"03_imagination_actor": range(10), "04_imagination_gap": range(10), "05_horizon": range(10),
         "06_closing_the_gap": range(10), "07_planning": range(6)}


def test_the_table_covers_seeds_0_to_9_of_notebooks_03_to_06_and_0_to_5_of_07_at_the_default_config(table):
    assert table["config"] == "default"
    assert set(table["notebooks"]) == set(SEEDS)
    assert table["host"] and table["commit"]
    seen = {(r["notebook"], r["seed"]) for r in table["records"]}
    missing = {(nb, s) for nb, seeds in SEEDS.items() for s in seeds} - seen
    assert not missing, f"no claim recorded for {sorted(missing)}"


def test_every_registered_claim_was_recorded(table, registry):
    recorded = {r["claim"] for r in table["records"]}
    never = sorted(set(registry) - recorded)
    assert not never, f"claims no recorded run evaluated: {never} (run make claims)"


def test_every_recorded_claim_is_still_registered_and_gives_the_recorded_outcome(table, registry):
    changed = []
    for r in table["records"]:
        assert r["claim"] in registry, f"{r['claim']} is in the table but no longer registered (run make claims)"
        if bool(registry[r["claim"]].predicate(**r["inputs"])) != r["holds"]:
            changed.append(f"{r['claim']} seed {r['seed']}")
    assert not changed, f"predicates that no longer give the recorded outcome: {changed[:10]} (run make claims)"


def test_no_fixed_claim_is_false_on_a_recorded_seed(table, registry):
    false = sorted({f"{r['claim']} (seed {r['seed']}): {registry[r['claim']].says}" for r in table["records"]
                    if registry[r["claim"]].fixed and not registry[r["claim"]].predicate(**r["inputs"])})
    assert not false, "fixed sentences false on a recorded seed:\n" + "\n".join(false)


def test_a_claim_records_what_it_read_and_logs_it(tmp_path, monkeypatch):
    log = tmp_path / "log.jsonl"
    monkeypatch.setenv(claims.LOG_ENV, str(log))

    @claims.claim("99.test_positive", "x is positive")
    def positive(*, x):
        return x > 0

    try:
        before = len(claims.LEDGER)
        assert positive(x=0.5) is True and positive(x=-1) is False
        assert claims.LEDGER[before:] == [
            {"claim": "99.test_positive", "holds": True, "fixed": False, "inputs": {"x": 0.5}},
            {"claim": "99.test_positive", "holds": False, "fixed": False, "inputs": {"x": -1}}]
        assert [json.loads(line)["holds"] for line in log.read_text().splitlines()] == [True, False]
        assert claims.note_if_false(True, positive) == ""
        assert "99.test_positive" in claims.note_if_false(False, positive)
        with pytest.raises(ValueError, match="registered twice"):
            @claims.claim("99.test_positive", "another")
            def other(*, x):
                return True
    finally:
        claims.REGISTRY.pop("99.test_positive", None)


def test_numpy_inputs_are_recorded_as_plain_numbers():
    import numpy as np

    assert claims._plain(np.float32(0.25)) == 0.25 and isinstance(claims._plain(np.float64(1)), float)
    assert claims._plain([np.int64(2), 3.0]) == [2, 3.0]
    assert claims._plain({"a": np.array([1.0, 2.0])}) == {"a": [1.0, 2.0]}


def test_no_two_claims_in_a_notebook_run_judge_one_number_with_different_tests(table):
    bad = claims.conflicts(table["records"])
    assert not bad, f"{len(bad)} numbers judged twice with different tests, e.g.:\n" + "\n".join(bad[:5])


def test_the_one_test_rule_catches_a_drop_judged_twice():
    # issue 38's seed 8: one gap drop, 0.236 -> 0.137, judged with the gap's standard errors ("shrank")
    # and with a bound on them ("did not fall"): the rule must see it, and must pass one test used twice
    gap = {"claim": "06.gap_shrank", "notebook": "06", "seed": 8, "holds": True,
           "inputs": {"first": 0.236, "first_se": 0.02, "last": 0.137, "last_se": 0.02, "k": 2.05, "min_effect": 0.02}}
    bound = {"claim": "06.error_size_shrank", "notebook": "06", "seed": 8, "holds": False,
             "inputs": {"first": 0.236, "first_bound": 0.03, "last": 0.137, "last_bound": 0.03, "k": 2.05,
                        "min_effect": 0.02}}
    same = {**bound, "inputs": {"first": 0.236, "first_se": 0.02, "last": 0.137, "last_se": 0.02, "k": 2.05,
                                "min_effect": 0.02}}
    assert len(claims.conflicts([gap, bound])) == 2 and claims.conflicts([gap, same]) == []
    assert claims.conflicts([gap, {**bound, "seed": 9}]) == []            # another run: another number
    assert claims.conflicts([gap, {**same, "inputs": {**same["inputs"], "k": 2.5}}])     # another k


# A claim whose sentence reads a cause names the control that isolates it.
CAUSAL_WORDS = ("exploit", "taught", "brought", "bringing", "because", "caused", "training made", "drifts",
                "recognis", "standing still", "than the state model", "round 0", "with the horizon",
                "wiring")


def test_every_causal_claim_names_a_known_control(registry):
    missing = sorted(n for n, c in registry.items() if c.notebook in ("04", "05", "06") and c.control is None
                     and any(w in c.says.lower() for w in CAUSAL_WORDS))
    assert not missing, f"causal claims without a control: {missing}"
    assert all(c.control in claims.CONTROLS for c in registry.values() if c.control is not None)
    with pytest.raises(ValueError, match="unknown control"):
        claims.claim("99.x", "x", control="the weather")


def test_the_recorded_table_lists_each_causal_claims_control():
    md = (ROOT / "benchmarks" / "claims.md").read_text()
    assert "| claim | kind | control |" in md
    for name, c in claims.load_all().items():
        if c.control:
            assert f"| `{name}` | {'fixed' if c.fixed else 'guarded'} | {c.control} |" in md, name


def test_numbers_named_as_different_quantities_are_not_one_quantity():
    # reality's change and the gap's change are equal in size when the dream's side did not move at all:
    # two quantities, each judged against its own noise, not one number judged twice
    real = {"claim": "06.change_down", "notebook": "06", "seed": 0, "holds": True,
            "inputs": {"diff": -0.06, "se": 0.001, "k": 2.05, "min_effect": 0.02, "quantity": "real rating"}}
    gap = {**real, "claim": "06.change_up", "inputs": {"diff": 0.06, "se": 0.1, "k": 2.05, "min_effect": 0.02}}
    assert claims.conflicts([real, gap]) == []
    assert claims.conflicts([real, {**gap, "inputs": {**gap["inputs"], "quantity": "real rating"}}])


def test_the_table_says_on_how_many_seeds_each_exercise_letter_was_decided(table):
    decided: dict = {}
    for r in table["records"]:
        if r["claim"].endswith("_letter_decided"):
            seeds = decided.setdefault(r["claim"], {})
            seeds[r["seed"]] = seeds.get(r["seed"], True) and r["holds"]
    assert set(decided) == {"04.ex1_letter_decided", "05.ex2_letter_decided", "06.ex3_letter_decided"}
    md = (ROOT / "benchmarks" / "claims.md").read_text()
    for name, ex in (("04.ex1_letter_decided", "Exercise 1 (04)"), ("05.ex2_letter_decided", "Exercise 2 (05)"),
                     ("06.ex3_letter_decided", "Exercise 3 (06)")):
        assert f"* {ex}: {sum(decided[name].values())} of {len(decided[name])} seeds" in md
    # issue 38's target, nine seeds in ten, holds for Exercise 3; Exercises 1 and 2 reach eight (the closing
    # note of issue 38 gives the starts and actor seeds their undecided seeds would need)
    assert sum(decided["06.ex3_letter_decided"].values()) >= 9
