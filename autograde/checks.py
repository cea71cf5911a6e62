"""The hidden tests, judged outside the student's kernel.

Each hidden test is a list of probe cases (``pusht.grading.probe`` runs them). The grader runs
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

import math
from dataclasses import dataclass, field

import numpy as np

Z6, ONE6 = {"t": [0.0] * 6}, {"t": [1.0] * 6}          # mean 0, std 1: normalised = metres
ODD_MEAN = {"rand": [6], "seed": 11, "lo": -0.5, "hi": 0.5}
ODD_STD = {"rand": [6], "seed": 12, "lo": 0.2, "hi": 1.2}


def _obs(*rows):
    return {"t": [list(r) for r in rows]}


def _yaw_rows():
    return [[0.0, 0.0, 0.0, 0.0, s * math.sin(y), s * math.cos(y)]
            for y in (0.3, 2.0, -2.5, 3.0, 1.5 * math.pi) for s in (0.5, 1.0, 1.7)]


@dataclass
class Case:
    spec: dict                 # what pusht.grading.probe runs
    hint: str                  # what the student reads when it fails
    atol: float = 1e-5


@dataclass
class Test:
    test_id: str
    notebook: str              # file stem
    function: str              # the name the student defines
    reference: str             # "module:function" of the package's implementation
    cases: list[Case] = field(default_factory=list)


def _call(*args):
    return {"kind": "call", "args": list(args)}


REWARD = Test("reward_impl_tests", "02_reward", "reward_from_obs", "pusht.reward:reward_from_obs", [
    Case(_call(_obs([0.3, -0.2, 0.0, 0.0, 0.0, 1.0]), Z6, ONE6),
         "the T on the target should score 0 (pos_err 0, ang_err 0), wherever the pusher is"),
    Case(_call(_obs([0.0, 0.0, 0.3, 0.4, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0]), Z6, ONE6),
         "known poses: (0.3, 0.4) m away scores -0.5; a quarter turn on the target scores -0.25"),
    Case(_call({"randn": [3, 5, 6], "seed": 1, "fresh": True}, {"t": [0.01, -0.02, 0.03, 0.0, 0.1, 0.2]},
               {"t": [0.2, 0.2, 0.15, 0.15, 0.7, 0.7]}),
         "random normalised observations (3, 5, 6): de-normalise with obs = norm_obs * std + mean"),
    Case(_call({"t": _yaw_rows()}, Z6, ONE6),
         "the yaw must come from atan2(sin, cos) on both components (decoded pairs need not lie on "
         "the unit circle), and angles wrap: 3*pi/2 is a quarter turn"),
    Case(_call(_obs([0.0, 0.0, 0.0, 0.0, 0.0, -1.0], [0.0, 0.0, 0.1, 0.0, 0.0, 1.3]), Z6, ONE6),
         "a half turn scores -0.5; a decoded cos above 1 must not give NaN"),
    Case(_call(_obs([0.4, 0.4, 0.1, -0.2, 0.6, 0.8], [-0.3, 0.1, 0.1, -0.2, 0.6, 0.8]), Z6, ONE6),
         "only the T's pose (dims 2-5) enters the reward, not the pusher"),
    Case(_call({"randn": [6], "seed": 3, "fresh": True}, ODD_MEAN, ODD_STD),
         "a single observation (6,) gives scalars; use the mean and std you are given"),
    Case(_call({"randn": [2, 3, 4, 6], "seed": 4, "fresh": True}, ODD_MEAN, ODD_STD),
         "any leading shape (2, 3, 4, 6) gives results of shape (2, 3, 4)"),
    Case({"kind": "grad", "of": 0, "args": [{"randn": [7, 6], "seed": 5, "fresh": True, "grad": True},
                                           ODD_MEAN, ODD_STD]},
         "the reward must be differentiable in norm_obs, with the right gradient (none on the pusher)"),
])

_HV = ({"randn": [6, 3], "seed": 21, "fresh": True}, {"randn": [7, 3], "seed": 22, "fresh": True})
LAMBDA = Test("lambda_return_impl_tests", "03_imagination_actor", "lambda_return",
              "pusht.imagination:lambda_return", [
    Case(_call({"t": [[1.0], [2.0]]}, {"t": [[10.0], [20.0], [30.0]]}, 0.5, 0.5),
         "the hand-worked case: rewards [1, 2], values [10, 20, 30], gamma = lam = 0.5 gives [[10.25], [17]]"),
    Case(_call({"randn": [15, 64], "seed": 23, "fresh": True}, {"randn": [16, 64], "seed": 24, "fresh": True},
               0.99, 0.95), "the training's shapes (H, B) = (15, 64) with the chapter's gamma and lam"),
    Case(_call(*_HV, 0.9, 0.0), "with lam = 0 the return is r_t + gamma * V_{t+1}"),
    Case(_call(*_HV, 0.9, 1.0), "with lam = 1 it is the discounted reward sum plus gamma^(H-t) * V_H"),
    Case(_call(*_HV, 0.7, 0.3), "use the gamma and lam arguments, not the config's values"),
    Case(_call(*_HV, 1.0, 0.8), "use the gamma and lam arguments (gamma = 1 too)"),
    Case(_call({"t": [[0.0]] * 6}, {"t": [[0.0]] * 6 + [[1.0]]}, 0.9, 0.5),
         "the critic's value of the LAST state V_H closes the recursion (G_H = V_H)"),
    Case(_call(_HV[0], {"t": [[100.0, -50.0, 7.0]] + [[0.5, -0.5, 0.25]] * 6}, 0.9, 0.7),
         "G_t uses V_{t+1}: V_0 (the start state's value) must not change any return"),
    Case(_call({"t": [[2.0]]}, {"t": [[5.0], [7.0]]}, 0.5, 0.3), "horizon H = 1: expected [[5.5]]"),
    Case({"kind": "grad", "of": 0, "row": 0, "args": [{"t": [[0.0]] * 6, "grad": True}, {"t": [[0.0]] * 7}, 0.9, 0.5]},
         "the gradient flows into the rewards: dG_0/dr_k = (gamma * lam)^k (stay in torch)"),
    Case({"kind": "grad", "of": 0, "args": [{"randn": [5, 3], "seed": 25, "fresh": True},
                                           {"randn": [6, 3], "seed": 26, "fresh": True, "grad": True}, 0.9, 0.6]},
         "the gradient flows into the values too (do not detach them): Dreamer's actor learns "
         "through the critic's values inside this return"),
])


def _losses_args(seed, H, B, S, hidden, gamma=0.99, lam=0.95, ent=3e-4, grad=()):
    """Arguments of actor_critic_losses: a seeded agent, dreamed states (H+1, B, S), rewards (H, B)
    in the reward's range [-1, 0], an entropy, gamma, lam, ent_coef and the chapter's return."""
    return [{"agent": {"seed": seed, "state": S, "hidden": hidden}},
            {"randn": [H + 1, B, S], "seed": seed + 1, "fresh": True, "grad": "states" in grad},
            {"rand": [H, B], "seed": seed + 2, "fresh": True, "lo": -1.0, "hi": 0.0, "grad": "rewards" in grad},
            {"t": 1.3, "grad": "entropy" in grad}, gamma, lam, ent, {"fn": "lambda_return"}]


_ALL = ("states", "rewards", "entropy")
LOSSES = Test("losses_impl_tests", "03_imagination_actor", "actor_critic_losses",
              "pusht.imagination:actor_critic_losses", [
    Case(_call(*_losses_args(40, 3, 2, 6, 8, 0.9, 0.5, 0.1)),
         "the two values on a small case: actor = -(mean lambda-return + ent_coef * entropy); critic = "
         "0.5 * mean squared error between V(states 0..H-1) and the returns"),
    Case(_call(*_losses_args(41, 15, 64, 80, 64)),
         "the training's shapes: H = 15, B = 64, state size 80, the chapter's gamma, lam and ent_coef"),
    Case(_call(*_losses_args(42, 6, 5, 7, 9, 0.8, 0.2, 0.05)),
         "use the gamma, lam and ent_coef arguments, and the return_fn you are given"),
    Case({"kind": "grad", "of": 0, "args": _losses_args(43, 5, 4, 6, 8, 0.9, 0.8, 0.01, grad=_ALL)},
         "the actor loss's gradient must flow into the rewards, the entropy AND the states through the "
         "critic's values: the return's bootstrap keeps its gradient (detaching it is the page's wiring, "
         "in which the critic never reaches the actor)"),
    Case({"kind": "grad", "of": 1, "args": _losses_args(44, 5, 4, 6, 8, 0.9, 0.8, 0.01, grad=("states",))},
         "the critic loss must send no gradient into the imagined states (read them detached): "
         "the exercise's contract, so that the critic loss stays off the actor's road however the "
         "two losses are stepped (with one summed backward() it would move the actor)"),
    Case({"kind": "grad", "of": 1, "args": _losses_args(45, 5, 4, 6, 8, 0.9, 0.8, 0.01, grad=("rewards",))},
         "the critic's target must be detached: no gradient from the critic loss into the rewards"),
    Case({"kind": "grad", "of": 1, "module_grads": ["critic"], "args": _losses_args(46, 5, 4, 6, 8, 0.9, 0.8, 0.01)},
         "the critic loss's gradient on the critic's own weights: V of states 0..H-1 (not 1..H) "
         "against the returns, 0.5 * mean squared error"),
])


def _dream(seed, latent, hidden, embed, policy, batch, horizon, obs_seed, mode="no_grad"):
    return {"kind": "dream", "model": {"seed": seed, "latent": latent, "hidden": hidden, "embed": embed},
            "policy": policy, "obs0": {"randn": [batch, 6], "seed": obs_seed, "fresh": True},
            "horizon": horizon, "mode": mode}


DREAM = Test("dream_impl_tests", "04_imagination_gap", "dream", "pusht.evaluate:dream", [
    Case(_dream(0, 4, 8, 5, 8, 3, 5, 30),
         "shapes (horizon+1, B, D) and (horizon, B, A); frame 0 is the decoded posterior of the start "
         "frame (h = 0, z = wm.filter_step(h, norm_obs0))", atol=1e-5),
    Case(_dream(1, 3, 7, 4, 6, 4, 7, 31),
         "the decoded dream and its actions, on another model, batch and horizon", atol=1e-5),
    Case(_dream(1, 3, 7, 4, "recording", 4, 3, 32),
         "the policy is called once per step on [h, z], first on [h = 0, z = posterior of the start "
         "frame]; the start frame is filtered once, then only the prior is used", atol=1e-6),
    Case(_dream(2, 3, 7, 4, "zero", 1, 1, 33, mode="inference"),
         "works without autograd (under torch.inference_mode), for B = 1 and horizon = 1"),
])

def _members(*blocks, rest=(0.0, 0.0, 0.0, 1.0)):
    """Frames (K, 1, 6) of K members that put the block centre at ``blocks`` (metres when std = 1),
    all with the same pusher (x, y) and yaw (sin, cos) ``rest``."""
    return {"t": [[[rest[0], rest[1], x, y, rest[2], rest[3]]] for x, y in blocks]}


# Members that agree on the block but not on the pusher or the yaw, next to members that disagree on
# everything; dyadic values, so any sound formula for the variance gives exactly 0 where they agree.
_BLOCK_ONLY = {"t": [[[0.5, -0.25, 0.125, 0.75, 0.0, 1.0], [0.5, 0.5, 0.25, -0.5, 1.0, 0.0]],
                     [[-1.0, 0.75, 0.125, 0.75, 1.0, 0.0], [0.5, 0.5, -0.25, 0.5, 0.0, 1.0]],
                     [[0.25, 2.0, 0.125, 0.75, -1.0, 0.5], [0.5, 0.5, 0.5, 0.0, 0.5, 0.5]]]}
_AGREE = {"t": [[[0.5, -0.25, 0.125, 0.75, 0.0, 1.0]] * 4] * 3, "grad": True}           # (3, 4, 6)
_BLOCK_STD = {"t": [0.2, 0.2, 0.15, 0.15, 0.7, 0.7]}                                     # the data's kind
_OTHER_STD = {"t": [3.0, 0.01, 0.15, 0.15, 7.0, 0.002]}                                  # same std[2:4]
DISAGREE = Test("block_disagreement_impl_tests", "06_closing_the_gap", "block_disagreement",
                "pusht.ensemble:block_disagreement", [
    Case(_call(_members((0.1, 0.2), (0.4, 0.6)), ONE6),
         "the hand-worked case: two members whose block centres are 0.5 m apart disagree by 0.25 "
         "(half the distance): sqrt(var_x + var_y) with POPULATION variances across the K members "
         "(divide by K, not K - 1: the members are the whole ensemble, not a sample)"),
    Case(_call(_BLOCK_ONLY, ONE6),
         "only the block centre (dims 2:4) counts: members that differ on the pusher or the T's angle "
         "but put the block in the same place disagree by 0"),
    Case(_call({"randn": [3, 15, 64, 6], "seed": 61, "fresh": True}, ODD_STD),
         "the training's shapes (K, H, B, D) = (3, 15, 64, 6) with a normalisation std: the answer is "
         "in metres, so scale the block's normalised (x, y) by their own std (std[2:4]) before the "
         "spread is taken (a variance scales with std squared)"),
    Case(_call({"randn": [3, 8, 6], "seed": 62, "fresh": True}, _OTHER_STD),
         "the std of the other dims (pusher, yaw) must not change the result: only std[2:4] enters"),
    Case(_call({"randn": [4, 9, 6], "seed": 63, "fresh": True}, _BLOCK_STD),
         "K = 4 members: population variance, the mean squared distance from the members' mean "
         "(divide by K, not K - 1)"),
    Case(_call(_members((0.3, -0.2)), ONE6),
         "a single member (K = 1) has nothing to disagree with: 0, not NaN (a sample variance would "
         "divide by K - 1 = 0)"),
    Case(_call({"randn": [5, 2, 3, 4, 6], "seed": 64, "fresh": True}, ODD_STD),
         "any leading shape: frames (K, 2, 3, 4, D) give (2, 3, 4); reduce over the members (dim 0) "
         "and the block's two coordinates only"),
    Case(_call({"randn": [3, 6], "seed": 65, "fresh": True}, ODD_STD),
         "frames (K, D) of one state give a scalar, shape ()"),
    Case({"kind": "grad", "of": 0, "args": [{"randn": [3, 7, 6], "seed": 66, "fresh": True, "grad": True},
                                           ODD_STD]},
         "the gradient flows into the frames (stay in torch: no .item(), numpy or detach), with the "
         "right values, and only into the block's dims (2:4)"),
    Case({"kind": "grad", "of": 0, "args": [_AGREE, _BLOCK_STD]},
         "where all members agree the disagreement is 0 and its gradient must be finite, here 0, "
         "not NaN: the square root's slope is infinite at 0, so do not take it there"),
])

TESTS = {t.test_id: t for t in (REWARD, LAMBDA, LOSSES, DREAM, DISAGREE)}


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
    from pusht.grading import probe

    fn = reference_function(test)
    helpers_ = helpers()
    return [probe(case.spec, fn, fresh, helpers_) for case in test.cases]


def probe_in_process(test: Test, fn, fresh: int = 12345) -> dict:
    """``fn``'s raw results on ``test``'s cases, run in THIS process, in the form the probe server
    gives (``probe.ProbeServer.run``): for tests of the judge and of the package's answers, never
    for a student's code."""
    from pusht.grading import decode_results, encode_results, run_probes

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
# function (``pusht.probe_server``): "`name` is not defined by the cells above the test cell"
UNDEFINED_MARK = "by the cells above the test cell"
