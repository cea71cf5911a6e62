"""Notebook 07's support module: every sentence reads the numbers it is given and every reading is a
registered claim that takes both branches; Exercise 4's letter follows the two policies' outcomes; the
zero-action census counts where zero actions are; every figure draws with labelled axes. Inputs are
small synthetic rungs and rollouts; one smoke world model checks the planner's recording and refit."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import torch
from matplotlib.figure import Figure

from pusht.data import EVAL_SEED_BASE, ExpertData
from pusht.evaluate import Rollout
from pusht.nb import planning as nb07
from pusht.nb.planning_measure import Ex4Result, Rung, outcome, paired
from pusht.selfcheck import Question, render
from pusht.stats import MIN_REWARD_EFFECT, k_for

N = 30


def gate(dream=0.05, dream_se=0.01, real=0.05, real_se=0.01, moved=0.01, horizon=16):
    k = k_for(N)
    passed = dream > k * dream_se and dream >= MIN_REWARD_EFFECT
    return {"expert_signal_dream": dream, "expert_signal_dream_se": dream_se, "expert_signal_real": real,
            "expert_signal_real_se": real_se, "zero_dream_block_moved": moved, "k": k, "min_effect": MIN_REWARD_EFFECT,
            "passed": passed, "n_starts": N, "horizon": horizon}


def rung(name="chapter", dream=0.05, toward=0.0, spread=0.01, signal=None, seed=0):
    rng = np.random.default_rng(seed)
    g = gate(dream=dream)
    sig = signal if signal is not None else dream + spread * rng.standard_normal(N)
    tow = toward + 0.005 * rng.standard_normal(N)
    return Rung(name, None, g, sig, np.abs(tow) + 0.01, tow, np.linspace(0, 0.05, 101))


def ladder(signals=(-0.03, 0.0, 0.04, 0.01, 0.06)):
    return {name: rung(name, dream=s, seed=i) for i, (name, s) in enumerate(zip(nb07.LABELS, signals))}


def rollout(reward=-0.4, successes=0, n=N, steps=100, seed=0, end=(0.1, 0.0, 0.5)):
    rng = np.random.default_rng(seed)
    r = reward + 0.02 * rng.standard_normal((steps, n))
    obs = np.zeros((steps + 1, n, 6))
    obs[..., 2], obs[..., 3] = end[0], end[1]
    obs[..., 4], obs[..., 5] = np.sin(end[2]), np.cos(end[2])
    success = np.zeros(n, dtype=bool)
    success[:successes] = True
    obs[-1, :successes, 2:4] = 0.0
    obs[-1, :successes, 4], obs[-1, :successes, 5] = 0.0, 1.0
    return Rollout(obs=obs, actions=np.zeros((steps, n, 2)), rewards=r, pos_err=np.abs(r), success=success)


def result(planner=(-0.30, 5), actor=(-0.50, 0), chapter=(-0.41, 0), chapter_gate=False, recipe_gate=True,
           actor_dream=-0.25):
    zero = rollout(-0.40, 0, seed=1)
    ro = {"planner": rollout(*planner, seed=2), "planner_chapter": rollout(*chapter, seed=3),
          "actor": rollout(*actor, seed=4), "zero": zero, "expert": rollout(-0.25, 30, seed=5)}
    planned = [np.zeros((N, 17, 6)) for _ in range(100)]
    return Ex4Result(outcomes={k: outcome(r, zero) for k, r in ro.items()}, rollouts=ro,
                     actor_dream=rollout(actor_dream, 0, seed=6), dream_zero=rollout(-0.40, 0, seed=7),
                     planned=planned, actor_metrics={},
                     gates={"planner": gate(0.05 if recipe_gate else -0.02),
                            "planner_chapter": gate(0.05 if chapter_gate else -0.02)})


def test_the_gate_table_and_sentence_read_the_verdict():
    rs = ladder()
    table = nb07.gate_table(rs)
    assert table.count("\n| ") == 6 and "fails" in table and "**passes**" in table
    assert "fails the gate" in nb07.gate_sentence(rs["chapter"])
    assert "passes the gate" in nb07.gate_sentence(rs["recipe"])
    assert "+0.060" in nb07.gate_sentence(rs["recipe"])


def test_the_drift_sentence_says_toward_the_target_only_beyond_noise_and_tolerance():
    assert "toward the target" in nb07.drift_sentence(rung(toward=0.05)).split("**")[1]
    assert "not toward the target" in nb07.drift_sentence(rung(toward=0.01))
    assert "not toward the target" in nb07.drift_sentence(rung(toward=-0.05))


def test_the_census_counts_zero_actions_and_where_the_block_was():
    n, t = 4, 5
    obs = np.zeros((n, t + 1, 6))
    obs[..., 2], obs[..., 5] = 0.2, 1.0          # the block 20 cm off the target, yaw 0
    obs[0, 3:, 2] = 0.0                          # sequence 0 reaches the target at step 3 ...
    act = np.full((n, t, 2), 0.3)
    act[0, 3:] = 0.0                             # ... and is padded with zero actions after it
    data = ExpertData(obs, act, obs[:1], act[:1], np.zeros(6), np.ones(6))
    c = nb07.zero_census(data)
    assert (c["zero"], c["zero_on_target"], c["zero_off_target"], c["steps"]) == (2, 2, 0, 20)
    words = nb07.census_sentence(c, c)
    assert "every one of them comes with the block already on the target" in words
    act[1, 1:3] = 0.0                            # a pause with the block off the target
    data = ExpertData(obs, act, obs[:1], act[:1], np.zeros(6), np.ones(6), np.array([0, 2, 0, 0], dtype=np.int8))
    c2 = nb07.zero_census(data)
    assert c2["zero_off_target"] == 2 and c2["by_kind"]["pause"]["zero_off_target"] == 2
    assert "every one of them" not in nb07.census_sentence(c2, c2)
    none = nb07.zero_census(ExpertData(obs, np.full((n, t, 2), 0.3), obs[:1], act[:1], np.zeros(6), np.ones(6)))
    assert "no step has a zero action" in nb07.census_sentence(none, c2)


def test_the_shares_are_paired_differences_and_their_words_follow_the_verdicts():
    base = np.random.default_rng(0).standard_normal(N) * 0.01
    rs = {name: rung(name, signal=base + shift) for name, shift in
          zip(nb07.LABELS, (0.0, 0.0, 0.06, 0.0, 0.06))}       # changes raise it, width does nothing
    sh = nb07.shares(rs)
    assert sh["delta_alone"]["up"] and sh["delta_with_size"]["up"]
    assert not sh["size_alone"]["up"] and not sh["size_alone"]["down"]
    assert abs(sh["delta_alone"]["diff"] - 0.06) < 1e-12 and sh["delta_alone"]["se"] < 1e-12
    words = nb07.shares_sentence(sh)
    assert "predicting changes raised the dream's expert signal with and without the other change" in words
    assert "twice the width made no difference" in words
    assert nb07.shares_table(sh).count("| raised |") == 2
    # each change alone raises it, neither adds to the other (seed 0's reading at the default config)
    rs = {name: rung(name, signal=base + shift) for name, shift in
          zip(nb07.LABELS, (0.0, 0.0, 0.06, 0.06, 0.06))}
    assert "each change alone raised the dream's expert signal, and neither added" in nb07.shares_sentence(nb07.shares(rs))
    rs = {name: rung(name, signal=base + shift) for name, shift in
          zip(nb07.LABELS, (0.0, 0.0, 0.0, 0.0, 0.06))}       # only both together
    words = nb07.shares_sentence(nb07.shares(rs))
    assert "predicting changes raised the dream's expert signal only on top of the other change" in words


def test_exercise_4_letter_follows_both_policies():
    assert nb07.ex4_verdict(result()) == "b"
    assert nb07.ex4_verdict(result(actor=(-0.30, 3))) == "c"
    assert nb07.ex4_verdict(result(planner=(-0.40, 0))) == "d"
    assert nb07.ex4_verdict(result(planner=(-0.40, 0), actor=(-0.3, 4))) == "a"
    # successes without a reward beyond zero actions' are not success, and the other way round
    assert nb07.ex4_verdict(result(planner=(-0.395, 3))) == "d"
    assert nb07.ex4_verdict(result(planner=(-0.30, 0))) == "d"
    letter, words = nb07.ex4_reconciliation(result())
    assert letter == "b" and words.endswith("So the measured answer is (b).") and "**" not in words


def test_the_outcome_words_table_and_exploitation_read_the_numbers():
    res = result()
    table = nb07.outcome_table(res)
    assert "| planner, recipe's model | 5/30 |" in table and table.count("\n| ") == 6
    words = nb07.outcome_sentence(res)
    assert "The planner in the recipe's model **succeeds in reality**" in words
    assert "earns **less** per step" in words                   # the actor at -0.50 against -0.40
    words = nb07.actor_sentence(res, 15)            # the dream rates the actor -0.25, its zero actions -0.40
    assert "better than doing nothing" in words and "exploits even the model" in words
    words = nb07.actor_sentence(result(actor_dream=-0.50), 15)
    assert "even in the model, the actor is worse than doing nothing" in words
    assert "does not rate it above reality beyond the noise" in words
    # seed 7's shape: the long dream far below reality is not "agreement" (an unseen seed found the old words)
    words = nb07.actor_sentence(result(actor_dream=-0.80), 15)
    assert "agree" not in words and "does not rate it above reality" in words


def test_the_gate_predicted_sentence_takes_both_branches():
    assert "predicted the planner's outcome in both" in nb07.gate_predicted_sentence(result())
    assert "did not predict" in nb07.gate_predicted_sentence(result(chapter_gate=True))
    assert "did not predict" in nb07.gate_predicted_sentence(result(recipe_gate=False))


def test_every_claim_takes_both_branches_somewhere():
    from pusht.nb import claims

    claims.LEDGER.clear()
    for rs in (ladder(), ladder((0.05, 0.05, -0.05, 0.05, 0.05))):
        nb07.gate_table(rs)
        nb07.shares_sentence(nb07.shares(rs))
    for toward in (0.05, 0.0):
        nb07.drift_sentence(rung(toward=toward))
    c = {"zero": 2, "zero_on_target": 2, "zero_off_target": 0, "steps": 10, "zero_share": 0.2, "sequences": 2,
         "by_kind": {"expert": {"sequences": 2, "zero": 2, "zero_off_target": 0}}}
    nb07.census_sentence(c, c)
    nb07.census_sentence({**c, "zero_off_target": 1}, c)
    for res in (result(), result(chapter_gate=True), result(actor_dream=-0.5), result(planner=(-0.4, 0)),
                result(actor_dream=-0.40, actor=(-0.40, 0))):
        nb07.outcome_sentence(res)
        nb07.gate_predicted_sentence(res)
        nb07.actor_sentence(res, 15)
        nb07.ex4_reconciliation(res)
    outcomes: dict = {}
    for r in claims.LEDGER:
        outcomes.setdefault(r["claim"], set()).add(r["holds"])
        assert claims.REGISTRY[r["claim"]].predicate(**r["inputs"]) == r["holds"], r["claim"]
    mine = {name for name in claims.REGISTRY if name.startswith("07.")}
    assert set(outcomes) == mine, mine - set(outcomes)
    assert not {n for n, o in outcomes.items() if o != {True, False}}
    assert not any(claims.REGISTRY[n].fixed for n in mine)
    assert not claims.conflicts([{**r, "seed": 0} for r in claims.LEDGER])


def test_a_paired_comparison_is_beyond_only_past_k_and_the_minimum_effect():
    rng = np.random.default_rng(1)
    noise = 0.001 * rng.standard_normal(N)
    assert paired(0.05 + noise, np.zeros(N))["up"]
    assert not paired(0.01 + noise, np.zeros(N))["up"]                  # below the minimum effect
    assert paired(-0.05 + noise, np.zeros(N))["down"]


def labelled(fig):
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    assert axes and all(ax.get_xlabel() for ax in axes) and all(ax.get_ylabel() for ax in axes)
    assert all(ax.get_title() for ax in axes)


def test_every_figure_draws_with_labelled_axes():
    rs = ladder()
    for fig in (nb07.fig_drift(rs), nb07.fig_gate(rs), nb07.fig_outcomes(result()), nb07.fig_one_start(result())):
        labelled(fig)


def test_self_checks_are_well_formed():
    assert set(nb07.SELF_CHECKS) == {"why_gate_first", "zero_padding", "replan"}
    for q in nb07.SELF_CHECKS.values():
        assert isinstance(q, Question) and q.answer in q.options
        render(q, "")


@pytest.fixture(scope="module")
def smoke_model(tmp_path_factory):
    from pusht.config import make_config
    from pusht.plan import SMOKE_RECIPE
    from pusht.wm_stage import world_model_stage

    cfg = make_config(smoke=True, seed=0).replace(**SMOKE_RECIPE)
    cache = tmp_path_factory.mktemp("cache")
    return world_model_stage(cfg, cache, cache, None, None)


def test_recording_the_plans_changes_no_action_and_the_refit_is_the_one_given(smoke_model):
    from pusht.plan import PlanSettings, cem_update, plan_rollout

    T = smoke_model.data.torch()
    s = PlanSettings(horizon=6, knots=2, samples=16, iters=2, elites=4, starts=3)
    seeds = [EVAL_SEED_BASE + i for i in range(3)]
    plain = plan_rollout(smoke_model.wm, seeds, 12, T["mean"], T["std"], s)
    record = []
    recorded = plan_rollout(smoke_model.wm, seeds, 12, T["mean"], T["std"], s, record=record)
    assert np.array_equal(plain.actions, recorded.actions)
    assert len(record) == 12 and record[0].shape == (3, 7, 6)
    assert np.allclose(record[0][:, 0], plain.obs[0], atol=1e-5)       # each plan's dream starts at the real frame
    calls = []

    def mine(samples, scores, elites, min_std=0.0):
        calls.append(samples.shape)
        return cem_update(samples, scores, elites, min_std)

    same = plan_rollout(smoke_model.wm, seeds, 12, T["mean"], T["std"], s, update=mine)
    assert calls and np.array_equal(same.actions, plain.actions)

    def wrong(samples, scores, elites, min_std=0.0):
        return samples.mean(1)[:, 0], samples.std(1)[:, 0]

    with pytest.raises(ValueError, match="the refit must return a mean and a spread of shape"):
        plan_rollout(smoke_model.wm, seeds, 3, T["mean"], T["std"], s, update=wrong)


def test_the_solution_refit_equals_the_package_on_random_cases():
    from pusht.plan import cem_update

    g = torch.Generator().manual_seed(3)
    for shape in ((2, 10, 3, 2), (1, 5, 1), (4, 7, 2)):
        samples, scores = torch.randn(*shape, generator=g), torch.randn(*shape[:2], generator=g)
        idx = scores.topk(3, dim=1).indices
        best = torch.stack([samples[b, idx[b]] for b in range(shape[0])])
        m, s = cem_update(samples, scores, 3, 0.05)
        assert torch.allclose(m, best.mean(1)) and torch.allclose(s, best.std(1, correction=0).clamp_min(0.05))


def test_the_summary_table_reads_every_seed_it_finds(tmp_path):
    import json

    from pusht.nb.planning_measure import Rung  # noqa: F401

    assert "No seed" in nb07.summary_table(tmp_path)
    folder = tmp_path / "metrics" / "planning"
    folder.mkdir(parents=True)
    rs = ladder()
    for seed in (10, 2):
        res = result(planner=(-0.3, seed))
        (folder / f"plan_seed{seed}.json").write_text(json.dumps(
            nb07.as_json(rs, {}, res, type("C", (), {"seed": seed})(), nb07.settings(type("C", (), {"smoke": True})())),
            default=float))
    table = nb07.summary_table(tmp_path)
    lines = [line for line in table.splitlines() if line.startswith("| ") and line[2].isdigit()]
    assert [line.split(" | ")[0] for line in lines] == ["| 2", "| 10"]
    assert "| 2 | 32 samples, 2 knots, reward | fails | 0/30" in table and "2/30" in table and "(b) |" in table
