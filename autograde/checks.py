"""The hidden tests, judged outside the student's kernel.

Each hidden test is a list of probe cases (``pusht.grader.probes.probe`` runs them). The grader runs
them on the student's function in its probe process (``probe.py``: the function defined from the
hand-in's cells, in a sandbox where the package's own implementations are absent) and on the
package's implementation here, and compares the numbers. A test earns its points only if every
case matches; the feedback names the first case that did not, with a hint, but never shows this
file.

The static check (``delegation.py``) follows the graded function through the notebook: one that
reaches the package's implementation of the function it was asked to write earns no credit for it,
with a message that says where.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

@dataclass
class Case:
    spec: dict                 # what pusht.grader.probes.probe runs
    hint: str                  # what the student reads when it fails
    atol: float = 1e-5


@dataclass
class Test:
    test_id: str
    notebook: str              # file stem
    function: str              # the name the student defines
    reference: str             # "module:function" of the package's implementation
    cases: list[Case] = field(default_factory=list)


def _gen(name: str, seed: int, kind: str = "call", **fixed) -> dict:
    """A generated case (``pusht.grader.cases.expand``): generator ``name`` draws every input from the run's
    nonce and ``seed``; ``fixed`` holds only what the case's property fixes, and how it is run
    (``of``, ``row``, ``module_grads``, ``helpers``)."""
    return {"kind": kind, "gen": name, "seed": seed, **fixed}


# Every case below is drawn from the run's nonce (``pusht.grader.cases``' generators), edge cases included:
# this file is public, so a fixed input could be recognised and answered from memory. The hand-worked
# numbers (the lambda-return's [[10.25], [17]], the reward's -0.5 and -0.25, the disagreement's 0.25)
# are the notebooks' visible tests; here each is a case of the same kind on numbers nobody has seen.
REWARD = Test("reward_impl_tests", "02_reward", "reward_from_obs", "pusht.reward:reward_from_obs", [
    Case(_gen("reward_on_target", 1),
         "the T on the target should score 0 (pos_err 0, ang_err 0), wherever the pusher is, whatever the "
         "length of the decoded (sin, cos) pair, after de-normalising with the mean and std given"),
    Case(_gen("reward_known_poses", 2),
         "known poses, in metres once de-normalised: a square T d m from the target scores -d (0.3, 0.4 m "
         "away: -0.5); a T turned by theta on the target scores -|theta| / (2 pi) (a quarter turn: -0.25)"),
    Case(_gen("reward_random", 3, lead="batch", norm="data"),
         "random normalised observations (A, B, 6): de-normalise with obs = norm_obs * std + mean"),
    Case(_gen("reward_yaw", 4),
         "the yaw must come from atan2(sin, cos) on both components (decoded pairs need not lie on "
         "the unit circle), and angles wrap: a turn past pi counts from the other side (3*pi/2 is a "
         "quarter turn)"),
    Case(_gen("reward_half_turn", 5),
         "a half turn on the target scores -0.5, whatever the length of (sin, cos); a decoded cos above 1 "
         "must not give NaN"),
    Case(_gen("reward_pusher_only", 6),
         "only the T's pose (dims 2-5) enters the reward, not the pusher"),
    Case(_gen("reward_random", 7, lead="single"),
         "a single observation (6,) gives scalars; use the mean and std you are given"),
    Case(_gen("reward_random", 8, lead="any"),
         "any leading shape: (d1, ..., dk, 6) gives results of shape (d1, ..., dk)"),
    Case(_gen("reward_random", 9, kind="grad", of=0, lead="rows", grad=True),
         "the reward must be differentiable in norm_obs, with the right gradient (none on the pusher)"),
])

LAMBDA = Test("lambda_return_impl_tests", "03_imagination_actor", "lambda_return",
              "pusht.imagination:lambda_return", [
    Case(_gen("lambda_small", 21),
         "a small case (H up to 4, B up to 3): G_t = r_t + gamma * ((1 - lam) * V_{t+1} + lam * G_{t+1}), "
         "from G_H = V_H, worked backwards as in the visible test's hand-worked case"),
    Case(_gen("lambda_return", 22, H=15, B=64, gamma=0.99, lam=0.95),
         "the training's shapes (H, B) = (15, 64) with the chapter's gamma and lam"),
    Case(_gen("lambda_return", 23, lam=0.0), "with lam = 0 the return is r_t + gamma * V_{t+1}"),
    Case(_gen("lambda_return", 24, lam=1.0),
         "with lam = 1 it is the discounted reward sum plus gamma^(H-t) * V_H"),
    Case(_gen("lambda_return", 25), "use the gamma and lam arguments, not the config's values"),
    Case(_gen("lambda_return", 26, gamma=1.0), "use the gamma and lam arguments (gamma = 1 too)"),
    Case(_gen("lambda_return", 27, values="vh_only"),
         "the critic's value of the LAST state V_H closes the recursion (G_H = V_H): with all rewards and "
         "the other values 0, the returns are not 0"),
    Case(_gen("lambda_return", 28, values="v0_big"),
         "G_t uses V_{t+1}: V_0 (the start state's value) must not change any return"),
    Case(_gen("lambda_return", 29, H=1), "horizon H = 1: G_0 = r_0 + gamma * V_1, for every column"),
    Case(_gen("lambda_return", 30, kind="grad", of=0, row=0, grad="rewards"),
         "the gradient flows into the rewards: dG_0/dr_k = (gamma * lam)^k (stay in torch)"),
    Case(_gen("lambda_return", 31, kind="grad", of=0, grad="values"),
         "the gradient flows into the values too (do not detach them): Dreamer's actor learns "
         "through the critic's values inside this return"),
])

_ALL = ("states", "rewards", "entropy")
_HELPER = {"helpers": ["lambda_return"]}            # the losses are given the chapter's lambda-return
LOSSES = Test("losses_impl_tests", "03_imagination_actor", "actor_critic_losses",
              "pusht.imagination:actor_critic_losses", [
    Case(_gen("losses", 40, **_HELPER),
         "the two values on a small case: actor = -(mean lambda-return + ent_coef * entropy); critic = "
         "0.5 * mean squared error between V(states 0..H-1) and the returns"),
    Case(_gen("losses", 41, H=15, B=64, S=80, hidden=64, gamma=0.99, lam=0.95, ent=3e-4, **_HELPER),
         "the training's shapes: H = 15, B = 64, state size 80, the chapter's gamma, lam and ent_coef"),
    Case(_gen("losses", 42, **_HELPER),
         "use the gamma, lam and ent_coef arguments, and the return_fn you are given"),
    Case(_gen("losses", 43, kind="grad", of=0, grad=list(_ALL), **_HELPER),
         "the actor loss's gradient must flow into the rewards, the entropy AND the states through the "
         "critic's values: the return's bootstrap keeps its gradient (detaching it is the page's wiring, "
         "in which the critic never reaches the actor)"),
    Case(_gen("losses", 44, kind="grad", of=1, grad=["states"], **_HELPER),
         "the critic loss must send no gradient into the imagined states (read them detached): "
         "the exercise's contract, so that the critic loss stays off the actor's road however the "
         "two losses are stepped (with one summed backward() it would move the actor)"),
    Case(_gen("losses", 45, kind="grad", of=1, grad=["rewards"], **_HELPER),
         "the critic's target must be detached: no gradient from the critic loss into the rewards"),
    Case(_gen("losses", 46, kind="grad", of=1, module_grads=["critic"], **_HELPER),
         "the critic loss's gradient on the critic's own weights: V of states 0..H-1 (not 1..H) "
         "against the returns, 0.5 * mean squared error"),
])

DREAM = Test("dream_impl_tests", "04_imagination_gap", "dream", "pusht.evaluate:dream", [
    Case(_gen("dream", 50, kind="dream"),
         "shapes (horizon+1, B, D) and (horizon, B, A); frame 0 is the decoded posterior of the start "
         "frame (h = 0, z = wm.filter_step(h, norm_obs0))", atol=1e-5),
    Case(_gen("dream", 51, kind="dream"),
         "the decoded dream and its actions, on another model, batch and horizon", atol=1e-5),
    Case(_gen("dream", 52, kind="dream", policy="recording"),
         "the policy is called once per step on [h, z], first on [h = 0, z = posterior of the start "
         "frame]; the start frame is filtered once, then only the prior is used", atol=1e-6),
    Case(_gen("dream", 53, kind="dream", policy="zero", batch=1, horizon=1, mode="inference"),
         "works without autograd (under torch.inference_mode), for B = 1 and horizon = 1"),
])

DISAGREE = Test("block_disagreement_impl_tests", "06_closing_the_gap", "block_disagreement",
                "pusht.ensemble:block_disagreement", [
    Case(_gen("disagree_pair", 60),
         "two members whose block centres are d m apart (std 1 on the block) disagree by d / 2 (0.5 m "
         "apart: 0.25): "
         "sqrt(var_x + var_y) with POPULATION variances across the K members (divide by K, not K - 1: "
         "the members are the whole ensemble, not a sample)"),
    Case(_gen("disagree_agree", 61),
         "only the block centre (dims 2:4) counts: members that differ on the pusher or the T's angle "
         "but put the block in the same place disagree by 0"),
    Case(_gen("disagree", 62, K=3, lead=[15, 64], std="data"),
         "the training's shapes (K, H, B, D) = (3, 15, 64, 6) with a normalisation std: the answer is "
         "in metres, so scale the block's normalised (x, y) by their own std (std[2:4]) before the "
         "spread is taken (a variance scales with std squared)"),
    Case(_gen("disagree", 63, std="wild"),
         "the std of the other dims (pusher, yaw) must not change the result: only std[2:4] enters"),
    Case(_gen("disagree", 64, K_min=4, K_max=8, std="data"),
         "K >= 4 members: population variance, the mean squared distance from the members' mean "
         "(divide by K, not K - 1)"),
    Case(_gen("disagree", 65, K=1),
         "a single member (K = 1) has nothing to disagree with: 0, not NaN (a sample variance would "
         "divide by K - 1 = 0)"),
    Case(_gen("disagree", 66, lead="any"),
         "any leading shape: frames (K, d1, ..., dk, D) give (d1, ..., dk); reduce over the members "
         "(dim 0) and the block's two coordinates only"),
    Case(_gen("disagree", 67, lead="none"),
         "frames (K, D) of one state give a scalar, shape ()"),
    Case(_gen("disagree", 68, kind="grad", of=0, grad=True),
         "the gradient flows into the frames (stay in torch: no .item(), numpy or detach), with the "
         "right values, and only into the block's dims (2:4)"),
    Case(_gen("disagree_agree", 69, kind="grad", of=0, grad=True),
         "where all members agree on the block the disagreement is 0 and its gradient must be finite, "
         "here 0, not NaN: the square root's slope is infinite at 0, so do not take it there"),
])

CEM = Test("cem_update_impl_tests", "07_planning", "cem_update", "pusht.plan:cem_update", [
    Case(_gen("cem", 70, B=1, elites="all", min_std=0.0),
         "with elites = S every sample is an elite: their mean and their POPULATION standard deviation "
         "across the samples (dim 1), element by element (divide by elites, not elites - 1: the elites are "
         "the whole set being fitted, not a sample of it; torch's .std() divides by n - 1 unless told "
         "correction=0)"),
    Case(_gen("cem", 71, B=1, min_std=0.0),
         "the elites are the `elites` samples with the HIGHEST scores (higher is better), not the lowest "
         "(sort the scores in descending order, or use topk), and both the mean and the spread are the "
         "elites' alone, not all the samples'"),
    Case(_gen("cem", 72, apart=True, min_std=0.0),
         "each start refits to its own samples only: start b's elites are the best of samples[b] by "
         "scores[b], whatever the other starts scored (here every score of one start lies above every "
         "score of another: pick the elites along dim 1, start by start, never across the flattened batch)"),
    Case(_gen("cem", 73, trail="plan", agree=True),
         "the spread is floored at min_std element by element: max(std, min_std), not std + min_std; "
         "where the elites agree exactly, or nearly, the spread is min_std, and a spread above the floor "
         "stays as it is"),
    Case(_gen("cem", 74, S=64, elites=8, min_std=0.05, trail=[4, 2]),
         "the planner's shapes: samples (B, 64, 4, 2), scores (B, 64), 8 elites, min_std 0.05 give a mean "
         "and a std of shape (B, 4, 2)"),
    Case(_gen("cem", 75, trail="none"),
         "samples (B, S) of single numbers give a mean and a std of shape (B,)"),
    Case(_gen("cem", 76, trail="any"),
         "any shape after the first two dimensions: samples (B, S, d1, ..., dk) give a mean and a std of "
         "shape (B, d1, ..., dk), taken element by element across each start's elites"),
    Case(_gen("cem", 77, elites="all"),
         "elites = S, several starts: every sample of a start is an elite (population standard deviation)"),
    Case(_gen("cem", 78, elites=1),
         "a single elite: its own values as the mean, and a spread of 0 floored at min_std (not NaN: "
         "a sample standard deviation would divide by elites - 1 = 0)"),
    Case(_gen("cem", 79, trail="plan", agree=True, min_std="default"),
         "min_std defaults to 0.0: called with three arguments the spread is not floored, so elites "
         "that agree exactly give a spread of exactly 0"),
])

TESTS = {t.test_id: t for t in (REWARD, LAMBDA, LOSSES, DREAM, DISAGREE, CEM)}


def reference_function(test: Test):
    import importlib

    module, name = test.reference.split(":")
    return getattr(importlib.import_module(module), name)


# The functions a test's cases hand to the function under test (``{"fn": name}`` in a spec), by the
# test whose reference they are: the losses exercise is given the chapter's lambda-return.
HELPERS = {"lambda_return": LAMBDA}


def helpers() -> dict:
    """{name: the package's implementation} of every function in ``HELPERS``, in THIS process."""
    return {name: reference_function(t) for name, t in HELPERS.items()}


def reference_results(test: Test, fresh: int) -> list[dict]:
    """The reference implementation's raw results on every case, computed in THIS process."""
    from pusht.grader.probes import probe

    fn = reference_function(test)
    helpers_ = helpers()
    return [probe(case.spec, fn, fresh, helpers_) for case in test.cases]


def probe_in_process(test: Test, fn, fresh: int = 12345) -> dict:
    """``fn``'s raw results on ``test``'s cases, run in THIS process, in the form the probe server
    gives (``probe.ProbeServer.run``): for tests of the judge and of the package's answers, never
    for a student's code."""
    from pusht.grader.probes import decode_results, encode_results, run_probes

    helpers_ = helpers()
    setup, results = decode_results(encode_results(run_probes([c.spec for c in test.cases], fn, fresh, helpers_)),
                                    len(test.cases))
    return {"fresh": fresh, "status": "ok", "setup": setup, "results": results}


@dataclass
class Verdict:
    test_id: str
    passed: bool               # every case matched: the cell earns all its points, else none
    message: str
    # why, in one word: passed, delegation, not_probed, timeout, toolarge, unchecked (the probe
    # failed), undefined (the cells above the test define no such function), raised (a case raised),
    # wrong (numbers that differ); ``tripwire.py`` reads it
    kind: str = ""
    errors: list = field(default_factory=list)     # the exceptions the cases raised, one line each


def judge(test: Test, probed: dict | None, delegation: list[str] | None = None) -> Verdict:
    """The verdict on one test cell from the raw results the probe process returned
    (``probe.ProbeServer.run``; None: the test was never probed). ``delegation``: where the graded
    function reaches the package's implementation (the ``definite`` findings of
    ``delegation.delegations``): no credit, whatever the results."""
    if delegation:
        return Verdict(test.test_id, False,
                       f"no credit: your `{test.function}` reaches the package's own implementation "
                       f"({'; '.join(delegation[:3])}). This exercise asks you to write it yourself.", "delegation")
    if probed is None:
        return Verdict(test.test_id, False, "this test was not checked: the notebook holding it was not graded",
                       "not_probed")
    setup = probed.get("setup") or []
    defining = f" (defining it: {setup[0][:200]})" if setup else ""
    status = probed.get("status")
    if status == "timeout":
        return Verdict(test.test_id, False, f"your `{test.function}` did not finish the checks in time{defining}",
                       "timeout")
    if status == "toolarge":
        return Verdict(test.test_id, False, f"your `{test.function}` returned far more numbers than the checks need",
                       "toolarge")
    if status != "ok" or probed.get("results") is None:
        return Verdict(test.test_id, False, f"your `{test.function}` could not be checked: "
                                            f"{(setup[0] if setup else status)[:300]}", "unchecked")
    saved = probed["results"]
    errors = [r for r in saved if isinstance(r, str)]
    if errors and len(errors) == len(saved) and all(UNDEFINED_MARK in r for r in errors):
        return Verdict(test.test_id, False, f"0 of {len(saved)} checks passed: {errors[0][:300]}{defining}",
                       "undefined", errors[:1])
    refs = reference_results(test, int(probed["fresh"]))
    passed = 0
    first = None
    for i, (case, ref) in enumerate(zip(test.cases, refs)):
        ok, why = True, ""
        got_case = saved[i]
        if isinstance(got_case, str):
            ok, why = False, f"your function raised {got_case[:200]}"
        else:
            for key, want in ref.items():
                got = got_case.get(key)
                if got is None:
                    ok, why = False, f"no numeric result for {key}"
                    break
                if got.shape != want.shape:
                    ok, why = False, f"{key} has shape {tuple(got.shape)}, expected {tuple(want.shape)}"
                    break
                if not np.allclose(got, want, atol=case.atol, rtol=1e-5):
                    ok, why = False, f"{key} differs from the expected values"
                    break
        passed += ok
        if not ok and first is None:
            first = f"check {i + 1}: {case.hint} ({why})"
    n = len(test.cases)
    if passed == n:
        return Verdict(test.test_id, True, f"all {n} checks passed", "passed")
    return Verdict(test.test_id, False, f"{passed} of {n} checks passed; first failure: {first}{defining}",
                   "raised" if errors else "wrong", sorted(set(e[:200] for e in errors))[:5])


# what the probe process answers, for every case, when the cells above the test define no such
# function (``pusht.grader.probe_server``): "`name` is not defined by the cells above the test cell"
UNDEFINED_MARK = "by the cells above the test cell"
