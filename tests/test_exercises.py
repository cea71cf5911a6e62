"""Each implement-it exercise, end to end without nbgrader: the solution passes its visible and
its hidden tests; plausible wrong versions pass the visible tests (shapes and a worked case) but
fail the hidden ones, with a hint; delegating to the package's own implementation earns nothing,
with a message saying why.

The visible tests are the notebook's own test cell (its hidden block stripped), executed on the
candidate; the hidden verdict is the probes run in this process (``checks.probe_in_process``)
and ``autograde/checks.judge``, what grading runs in its probe process (where the package's own
implementations are absent: ``tests/test_probe.py``).
"""

import json
from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from autograde import checks
from autograde import delegation
from pusht.agent import ActorCritic
from pusht.config import make_config
from pusht.evaluate import policy_of

ROOT = Path(__file__).resolve().parents[1]


def cell(notebook: str, grade_id: str) -> str:
    nb = json.loads((ROOT / "solutions" / f"{notebook}.ipynb").read_text())
    (src,) = ["".join(c["source"]) for c in nb["cells"]
              if c["metadata"].get("nbgrader", {}).get("grade_id") == grade_id]
    return src


def visible(src: str) -> str:
    """A test cell as the student sees it: the hidden block removed."""
    if "### END HIDDEN TESTS" in src:
        src = src.split("### END HIDDEN TESTS", 1)[1]
    return src


def namespace(**functions) -> dict:
    return {"torch": torch, "np": np, "F": F, "cfg": make_config(), "ActorCritic": ActorCritic,
            "policy_of": policy_of, **functions}


def solution(notebook: str, grade_id: str, name: str, **extra):
    ns = namespace(**extra)
    exec(cell(notebook, grade_id), ns)
    return ns[name]


def hidden(test, fn):
    return checks.judge(test, checks.probe_in_process(test, fn))


def run_visible(notebook, test_id, **functions):
    exec(visible(cell(notebook, test_id)), namespace(**functions))


# --- wrong but plausible versions -------------------------------------------------------------------
def lambda_return_detached_values(rewards, values, gamma, lam):
    """Right numbers, but the values' gradient is cut: Dreamer's actor would never hear the critic."""
    values = values.detach()
    out, last = [], values[-1]
    for t in reversed(range(rewards.shape[0])):
        last = rewards[t] + gamma * ((1 - lam) * values[t + 1] + lam * last)
        out.append(last)
    return torch.stack(out[::-1])


def lambda_return_floats(rewards, values, gamma, lam):
    """Right numbers through Python floats: nothing is differentiable any more."""
    H, B = rewards.shape
    out = [[0.0] * B for _ in range(H)]
    for b in range(B):
        last = float(values[-1, b].detach())
        for t in reversed(range(H)):
            r, v = float(rewards[t, b].detach()), float(values[t + 1, b].detach())
            last = r + gamma * ((1 - lam) * v + lam * last)
            out[t][b] = last
    return torch.tensor(out)


def losses_critic_steals(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=None):
    """The critic regresses on the live states: its loss pushes on the actor through the dream."""
    values = agent.value(states)
    returns = return_fn(rewards, values, gamma, lam)
    return -(returns.mean() + ent_coef * entropy), 0.5 * F.mse_loss(values[:-1], returns.detach())


def losses_moving_target(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=None):
    """The critic chases a target that is not detached."""
    returns = return_fn(rewards, agent.value(states), gamma, lam)
    return (-(returns.mean() + ent_coef * entropy),
            0.5 * F.mse_loss(agent.value(states.detach())[:-1], returns))


def dream_refilters(wm, policy, norm_obs0, horizon):
    """Feeds its own decoded frame back through the posterior, as if it were a real frame."""
    h, _ = wm._init(norm_obs0.shape[0])
    z = wm.filter_step(h, norm_obs0)
    hs, zs, acts = [h], [z], []
    for _ in range(horizon):
        a = policy(torch.cat([h, z], dim=-1))
        h, _ = wm.img_step(h, z, a)
        z = wm.filter_step(h, wm.decode(h, z))
        hs.append(h), zs.append(z), acts.append(a)
    return wm.decode(torch.stack(hs), torch.stack(zs)), torch.stack(acts)


def dream_stale_latent(wm, policy, norm_obs0, horizon):
    """Advances the memory h but keeps the start's latent z for every step."""
    h, _ = wm._init(norm_obs0.shape[0])
    z = wm.filter_step(h, norm_obs0)
    hs, zs, acts = [h], [z], []
    for _ in range(horizon):
        a = policy(torch.cat([h, z], dim=-1))
        h, _ = wm.img_step(h, z, a)
        hs.append(h), zs.append(z), acts.append(a)
    return wm.decode(torch.stack(hs), torch.stack(zs)), torch.stack(acts)


def _safe_root(var):
    positive = var > 0
    return torch.where(positive, torch.where(positive, var, 1.0).sqrt(), 0.0)


def disagreement_sample_variance(frames, std):
    """Divides by K - 1: the members taken for a sample of some larger population."""
    return _safe_root((frames[..., 2:4] * std[2:4]).var(dim=0).sum(-1))


def disagreement_normalised_units(frames, std):
    """Never converts to metres: the spread of the normalised frames."""
    return _safe_root(frames[..., 2:4].var(dim=0, correction=0).sum(-1))


def disagreement_std_not_squared(frames, std):
    """Converts the variance with std instead of std squared: neither normalised units nor metres."""
    return _safe_root((frames[..., 2:4].var(dim=0, correction=0) * std[2:4]).sum(-1))


def disagreement_all_dims(frames, std):
    """The spread of the whole frame, pusher and yaw included, not of the block centre."""
    return _safe_root((frames * std).var(dim=0, correction=0).sum(-1))


def disagreement_plain_root(frames, std):
    """Right values, but sqrt(0) has an infinite slope: NaN gradients wherever the members agree."""
    return (frames[..., 2:4] * std[2:4]).var(dim=0, correction=0).sum(-1).sqrt()


def disagreement_detached(frames, std):
    """Right values from detached frames: the penalty would never reach the actor."""
    return _safe_root((frames.detach()[..., 2:4] * std[2:4]).var(dim=0, correction=0).sum(-1))


def _elites(samples, scores, elites):
    idx = scores.topk(elites, dim=1).indices
    return torch.stack([samples[b, idx[b]] for b in range(samples.shape[0])])


def cem_sample_std(samples, scores, elites, min_std=0.0):
    """torch's default .std(): divides by elites - 1, the elites taken for a sample."""
    best = _elites(samples, scores, elites)
    return best.mean(1), best.std(1).clamp_min(min_std)


def cem_lowest(samples, scores, elites, min_std=0.0):
    """Sorts the scores ascending and keeps the first: the worst plans."""
    idx = scores.argsort(dim=1)[:, :elites]
    best = torch.stack([samples[b, idx[b]] for b in range(samples.shape[0])])
    return best.mean(1), best.std(1, correction=0).clamp_min(min_std)


def cem_mixes_starts(samples, scores, elites, min_std=0.0):
    """The best B * elites plans of the whole batch, whatever start they belong to."""
    B, S = scores.shape
    idx = scores.reshape(-1).topk(B * elites).indices
    best = samples.reshape(B * S, *samples.shape[2:])[idx].reshape(B, elites, *samples.shape[2:])
    return best.mean(1), best.std(1, correction=0).clamp_min(min_std)


def cem_first_start(samples, scores, elites, min_std=0.0):
    """The first start's elites, taken for every start."""
    best = samples[:, scores[0].topk(elites).indices]
    return best.mean(1), best.std(1, correction=0).clamp_min(min_std)


def cem_no_floor(samples, scores, elites, min_std=0.0):
    """Forgets the floor: a search whose elites agree collapses to a point."""
    best = _elites(samples, scores, elites)
    return best.mean(1), best.std(1, correction=0)


def cem_floor_added(samples, scores, elites, min_std=0.0):
    """Adds the floor to every spread instead of flooring it."""
    best = _elites(samples, scores, elites)
    return best.mean(1), best.std(1, correction=0) + min_std


def cem_default_floor(samples, scores, elites, min_std=0.05):
    """The planner's floor as the default: min_std is 0.0 when not given."""
    best = _elites(samples, scores, elites)
    return best.mean(1), best.std(1, correction=0).clamp_min(min_std)


def cem_spread_of_all(samples, scores, elites, min_std=0.0):
    """The elites' mean, but the spread of all the samples."""
    return _elites(samples, scores, elites).mean(1), samples.std(1, correction=0).clamp_min(min_std)


def _with_return(fn, default_return):
    """``fn`` as a learner writes it: the return function an optional 8th argument, theirs by default."""
    def losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=default_return):
        return fn(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=return_fn)
    return losses


# --- the exercises ------------------------------------------------------------------------------------
def test_lambda_return():
    test = checks.LAMBDA
    good = solution("03_imagination_actor", "lambda_return_impl", "lambda_return")
    run_visible("03_imagination_actor", "lambda_return_impl_tests", lambda_return=good)
    assert hidden(test, good).passed
    for wrong, hint in ((lambda_return_detached_values, "flows into the values"),
                        (lambda_return_floats, "gradient")):
        run_visible("03_imagination_actor", "lambda_return_impl_tests", lambda_return=wrong)
        v = hidden(test, wrong)
        assert not v.passed and hint in v.message, v.message


def test_actor_critic_losses():
    test = checks.LOSSES
    lr = solution("03_imagination_actor", "lambda_return_impl", "lambda_return")
    good = solution("03_imagination_actor", "losses_impl", "actor_critic_losses", lambda_return=lr)
    run_visible("03_imagination_actor", "losses_impl_tests", actor_critic_losses=good)
    assert hidden(test, good).passed
    from pusht.imagination import page_losses

    page = _with_return(page_losses, lr)       # the chapter page's wiring, as a learner would write it
    for wrong, hint in ((page, "page's wiring"), (_with_return(losses_critic_steals, lr), "imagined states"),
                        (_with_return(losses_moving_target, lr), "no gradient")):
        run_visible("03_imagination_actor", "losses_impl_tests", actor_critic_losses=wrong)
        v = hidden(test, wrong)
        assert not v.passed and hint in v.message, v.message


def test_dream():
    test = checks.DREAM
    good = solution("04_imagination_gap", "dream_impl", "dream")
    run_visible("04_imagination_gap", "dream_impl_tests", dream=good)
    assert hidden(test, good).passed
    for wrong in (dream_refilters, dream_stale_latent):
        run_visible("04_imagination_gap", "dream_impl_tests", dream=wrong)
        v = hidden(test, wrong)
        assert not v.passed and "first failure" in v.message, v.message


@pytest.mark.filterwarnings("ignore:var\\(\\)")      # the sample variance of one member
def test_block_disagreement():
    test = checks.DISAGREE
    nb, tests_id = "06_closing_the_gap", "block_disagreement_impl_tests"
    good = solution(nb, "block_disagreement_impl", "block_disagreement")
    run_visible(nb, tests_id, block_disagreement=good)
    assert hidden(test, good).passed
    for wrong, hint in ((disagreement_normalised_units, "in metres"),
                        (disagreement_std_not_squared, "std squared"),
                        (disagreement_all_dims, "only the block centre"),
                        (disagreement_plain_root, "not NaN")):
        run_visible(nb, tests_id, block_disagreement=wrong)
        v = hidden(test, wrong)
        assert not v.passed and hint in v.message, (wrong.__name__, v.message)
    with pytest.raises(AssertionError, match="carry gradient"):   # the visible tests catch this one
        run_visible(nb, tests_id, block_disagreement=disagreement_detached)
    assert "not differentiable" in hidden(test, disagreement_detached).message
    with pytest.raises(AssertionError, match="disagree by 0.25"):  # and this one, by the case worked by hand
        run_visible(nb, tests_id, block_disagreement=disagreement_sample_variance)
    v = hidden(test, disagreement_sample_variance)
    assert not v.passed and "POPULATION variances" in v.message, v.message


@pytest.mark.filterwarnings("ignore:std\\(\\)")      # the sample std of one elite
def test_cem_update():
    test = checks.CEM
    nb, tests_id = "07_planning", "cem_update_impl_tests"
    good = solution(nb, "cem_update_impl", "cem_update")
    run_visible(nb, tests_id, cem_update=good)
    assert hidden(test, good).passed
    for wrong, hint in ((cem_mixes_starts, "its own samples"), (cem_first_start, "its own samples"),
                        (cem_floor_added, "not std + min_std"), (cem_default_floor, "defaults to 0.0")):
        run_visible(nb, tests_id, cem_update=wrong)          # shapes and the case by hand cannot tell
        v = hidden(test, wrong)
        assert not v.passed and hint in v.message, (wrong.__name__, v.message)
    for wrong, visible_says, hint in (
            (cem_sample_std, "divide by the number of elites", "POPULATION standard deviation"),
            (cem_lowest, "the elites 1 and 3", "HIGHEST scores"),
            (cem_spread_of_all, "the elites 1 and 3 have spread 1", "the elites' alone"),
            (cem_no_floor, "the floor min_std", "floored at min_std element by element")):
        with pytest.raises(AssertionError, match=visible_says):   # the visible tests catch these ...
            run_visible(nb, tests_id, cem_update=wrong)
        v = hidden(test, wrong)                                    # ... and the hidden ones say why
        assert not v.passed and hint in v.message, (wrong.__name__, v.message)


def test_the_planner_of_exercise_4_runs_the_learners_refit_never_the_packages(tmp_path):
    """Notebook 07's experiment hands its planner ``update=cem_update``, the learner's: every refit of
    the planner is theirs (the package's own is never entered, even for a refit that is falsy, a
    callable object with ``__len__`` 0), and with the solution's refit it plans what the package's does.
    The recipe's world model of the smoke config, trained here, as the notebook's planner gets it."""
    import sys

    import pusht.plan as plan
    from pusht.nb import planning as nb07
    from pusht.wm_stage import world_model_stage

    cfg = make_config(smoke=True)
    s = nb07.settings(cfg)
    seeds = nb07.starts(cfg, s)[:2]
    stage = world_model_stage(nb07.configs(cfg)["recipe"], tmp_path, tmp_path, None, None)
    plan_in = nb07.plan_in
    learner = solution("07_planning", "cem_update_impl", "cem_update")

    class Refit:                                                       # a callable object that is falsy
        calls = 0

        def __len__(self):
            return 0

        def __call__(self, *args):
            Refit.calls += 1
            return learner(*args)

    package_calls = []

    def watch(frame, event, arg):
        if event == "call" and frame.f_code is plan.cem_update.__code__:
            package_calls.append(frame.f_code.co_name)

    sys.setprofile(watch)
    try:
        mine = plan_in(stage, seeds, 3, s, update=Refit())
    finally:
        sys.setprofile(None)
    assert Refit.calls == 3 * s.iters and package_calls == []       # 3 real steps, every refit the learner's
    theirs = plan_in(stage, seeds, 3, s)                              # the package's refit, by default
    np.testing.assert_allclose(mine.actions, theirs.actions, atol=1e-5)


@pytest.mark.parametrize("test", list(checks.TESTS.values()), ids=list(checks.TESTS))
def test_delegating_to_the_package_earns_nothing_and_says_why(test):
    module, name = test.reference.split(":")
    src = f"from {module} import {name} as _theirs\n\ndef {test.function}(*args, **kw):\n    return _theirs(*args, **kw)\n"
    found = delegation.delegations(test, [{"cell_type": "code", "source": src, "metadata": {}}]).definite
    assert found
    v = checks.judge(test, None, delegation=found)
    assert not v.passed and "no credit" in v.message and "write it yourself" in v.message


# --- the reward (notebook 02) ----------------------------------------------------------------------------
def _reward_notebook_globals():
    """What notebook 02 defines before its test cell: the data's MEAN/STD and its to_norm."""
    from pusht.env import ANG_SCALE, POS_SCALE
    from pusht.nb import reward as nb02

    MEAN = torch.tensor([0.01, -0.02, 0.03, 0.0, 0.1, 0.2])
    STD = torch.tensor([0.2, 0.2, 0.15, 0.15, 0.7, 0.7])
    return {"MEAN": MEAN, "STD": STD, "POS_SCALE": POS_SCALE, "ANG_SCALE": ANG_SCALE,
            "to_norm": lambda obs_m: nb02.to_norm(obs_m, MEAN, STD)}


def test_reward():
    test = checks.REWARD
    g = _reward_notebook_globals()
    good = solution("02_reward", "reward_impl", "reward_from_obs", **g)
    run_visible("02_reward", "reward_impl_tests", reward_from_obs=good, **g)
    assert hidden(test, good).passed
    # Plausible slips the visible tests cannot see: the notebook's own MEAN or STD used in place of
    # the arguments (the visible tests pass exactly those; the grader passes others).
    source = cell("02_reward", "reward_impl")
    for wrong_line in ("obs = norm_obs * std + MEAN", "obs = norm_obs * STD + mean"):
        ns = namespace(**g)
        exec(source.replace("obs = norm_obs * std + mean", wrong_line), ns)
        wrong = ns["reward_from_obs"]
        run_visible("02_reward", "reward_impl_tests", reward_from_obs=wrong, **g)
        v = hidden(test, wrong)
        assert not v.passed and "first failure" in v.message, v.message
