"""pusht.metric_keys: one function builds every composed metric key, and every key a run writes is
either built from a template or written whole where grep finds it."""

import ast
import dataclasses
import random
from pathlib import Path

import pytest

import pusht
from pusht import metric_keys as mk
from pusht.config import Config


def test_every_key_a_template_makes_is_explained_back_to_its_parts():
    for pattern in mk.TEMPLATES:
        made = mk.expand(pattern)
        assert made, pattern
        for name, parts in made.items():
            template, found = mk.explain(name)
            assert template.pattern == pattern and found == parts, name
            assert mk.key(pattern, **parts) == name


def test_no_two_templates_make_the_same_key():
    seen = {}
    for pattern in mk.TEMPLATES:
        for name in mk.expand(pattern):
            assert name not in seen, f"{name} from {pattern} and {seen[name]}"
            seen[name] = pattern


def test_the_keys_keep_the_grammar_metrics_files_have_always_had():
    assert mk.key(mk.GAP_TERM, term="drift", se=True, part="position", span="train_horizon") \
        == "gap_drift_se_position_train_horizon"
    assert mk.key(mk.EXPERT_SIGNAL, part="yaw", world="dream", se=True, span="eval_horizon") \
        == "expert_signal_yaw_dream_se_eval_horizon"
    assert mk.key(mk.RETURN, policy="trained", world="real", se=True, part="yaw", span="eval_horizon") \
        == "trained_real_return_per_step_se_yaw_eval_horizon"
    assert mk.key(mk.WM_RATIO, kind="one_step", dim="cos(tee_yaw)") == "wm_one_step_ratio_cos(tee_yaw)"
    assert mk.key(mk.WM_ERR, data="policy", kind="open_loop", body="block") == "wm_policy_open_loop_block_err"
    assert mk.key(mk.GAP) == "imagination_gap"


@pytest.mark.parametrize("call, message", [
    (lambda: mk.key("gap_{term}_x", term="drift"), "not a metric-key template"),
    (lambda: mk.key(mk.GAP_TERM, term="drfit", span="eval_horizon"), "term='drfit' is not one of"),
    (lambda: mk.key(mk.GAP, span="eval"), "span='eval' is not one of"),
    (lambda: mk.key(mk.ZERO_BLOCK_MOVED, part="yaw"), "has no part 'part'"),
    (lambda: mk.key(mk.GAP_TERM, span="eval_horizon"), "needs term"),
    (lambda: mk.key(mk.WM_ERR, kind="one_step", body="block", world="dream"), "has no part 'world'"),
])
def test_a_wrong_part_is_a_clear_error(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_random_parts_in_any_order_make_the_same_key():
    rng = random.Random(0)
    for _ in range(200):
        pattern = rng.choice(list(mk.TEMPLATES))
        name, parts = rng.choice(list(mk.expand(pattern).items()))
        shuffled = dict(rng.sample(list(parts.items()), len(parts)))
        assert mk.key(pattern, **shuffled) == name


def string_literals() -> set[str]:
    """Every string constant in the package's source (a key written whole is one of these)."""
    out = set()
    for path in Path(pusht.__file__).parent.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                out.add(node.value)
    return out


def unfindable(keys, literals=None) -> list[str]:
    """The keys of ``keys`` that neither a template makes nor a literal in the package spells out."""
    literals = string_literals() if literals is None else literals
    fields = {f.name for f in dataclasses.fields(Config)}
    return sorted(k for k in keys if k not in literals and k not in fields and mk.explain(k) is None)


def test_the_check_finds_a_key_born_elsewhere():
    assert unfindable(["gap_drift_se_position_train_horizon", "real_success_rate", "seed"]) == []
    assert unfindable(["gap_drfit_position_train_horizon", "made_up_" + "metric"]) \
        == ["gap_drfit_position_train_horizon", "made_up_" + "metric"]


def test_the_command_line_names_a_keys_template(capsys):
    assert mk.main(["gap_drift_se_position_train_horizon", "real_success_rate"]) == 0
    out = capsys.readouterr().out
    assert "template GAP_TERM" in out and "term=drift" in out and "reward/step" in out
    assert "written whole" in out
