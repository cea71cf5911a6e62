"""The hidden tests' judge, without nbgrader: the probes' raw numbers (``pusht.grader.probes``, run here
in this process) and how the grader rules on them (``autograde/checks.py``).

The solution notebooks' implementations pass every case; a wrong one and one that returns
always-equal objects fail. (That the package's own implementations cannot be reached where
students' functions are probed is ``tests/test_probe.py``'s.)
"""

import math
from pathlib import Path

import torch

from autograde import checks

ROOT = Path(__file__).resolve().parents[1]


def verdict(test, fn):
    return checks.judge(test, checks.probe_in_process(test, fn))


def reward(norm_obs, mean, std):
    obs = norm_obs * std + mean
    pos = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang = torch.abs(torch.atan2(obs[..., 4], obs[..., 5]))
    return -0.5 * (pos / 0.5 + ang / math.pi), pos, ang


def reward_acos(norm_obs, mean, std):
    obs = norm_obs * std + mean
    pos = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang = torch.acos(obs[..., 5].clamp(-1, 1))
    return -0.5 * (pos / 0.5 + ang / math.pi), pos, ang


def lambda_return(rewards, values, gamma, lam):
    out, last = [], values[-1]
    for t in reversed(range(rewards.shape[0])):
        last = rewards[t] + gamma * ((1 - lam) * values[t + 1] + lam * last)
        out.append(last)
    return torch.stack(out[::-1])


def dream(wm, policy, norm_obs0, horizon):
    h, _ = wm._init(norm_obs0.shape[0])
    z = wm.filter_step(h, norm_obs0)
    hs, zs, acts = [h], [z], []
    for _ in range(horizon):
        a = policy(torch.cat([h, z], -1))
        h, z = wm.img_step(h, z, a)
        hs.append(h), zs.append(z), acts.append(a)
    return wm.decode(torch.stack(hs), torch.stack(zs)), torch.stack(acts)


def block_disagreement(frames, std):
    block = frames[..., 2:4] * std[2:4]
    var = ((block - block.mean(0)) ** 2).mean(0).sum(-1)
    return torch.where(var > 0, var.clamp_min(1e-30).sqrt(), torch.zeros_like(var))


def cem_update(samples, scores, elites, min_std=0.0):
    order = scores.argsort(dim=1, descending=True)[:, :elites]
    best = samples[torch.arange(samples.shape[0])[:, None], order]
    mean = best.mean(1)
    return mean, ((best - mean[:, None]) ** 2).mean(1).sqrt().clamp_min(min_std)


def test_correct_implementations_pass_every_case():
    for test, fn in ((checks.REWARD, reward), (checks.LAMBDA, lambda_return), (checks.DREAM, dream),
                     (checks.DISAGREE, block_disagreement), (checks.CEM, cem_update)):
        v = verdict(test, fn)
        assert v.passed, (test.test_id, v.message)


def test_a_wrong_reward_fails_with_a_hint():
    v = verdict(checks.REWARD, reward_acos)
    assert not v.passed and "first failure" in v.message


def test_always_equal_objects_record_nothing_that_passes():
    class Yes(float):
        def __eq__(self, other):
            return True

    v = verdict(checks.REWARD, lambda *a: (Yes(0.0), Yes(0.0), Yes(0.0)))
    assert not v.passed


def test_missing_results_and_delegation_earn_nothing():
    assert not checks.judge(checks.REWARD, None).passed
    for status in ("timeout", "toolarge", "the probe process failed (EOFError)"):
        assert not checks.judge(checks.REWARD, {"fresh": 1, "status": status, "setup": [], "results": None}).passed
    v = checks.judge(checks.REWARD, None, delegation=["cell 3, line 1: from pusht.reward import reward_from_obs"])
    assert not v.passed and "write it yourself" in v.message


def test_verdicts_judged_in_several_threads_at_once_are_the_verdicts_judged_alone():
    # grade_task judges in its own process, and several tasks finish in threads of one process; the
    # reference probes seed torch's global generator, so judgements must not interleave
    from concurrent.futures import ThreadPoolExecutor

    from autograde import task

    raw = checks.probe_in_process(checks.DREAM, dream, fresh=77)

    def judged(_):
        return task.judge_locked(checks.DREAM, raw)["message"]

    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    with ThreadPoolExecutor(4) as pool:
        messages = list(pool.map(judged, range(24)))
    assert set(messages) == {f"all {len(checks.DREAM.cases)} checks passed"}, set(messages)
    assert torch.equal(torch.rand(3), expected)        # the caller's random numbers are its own
