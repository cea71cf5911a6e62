"""The hidden tests' judge, without nbgrader: what a test cell records in the kernel
(``pusht.grading.submit``) and how the grader's own process rules on it (``autograde/checks.py``).

The solution notebooks' implementations pass every case; a wrong one, one that returns
always-equal objects, and one that delegates to the package's reference all fail.
"""

import json
import math
import sys
from pathlib import Path

import pytest
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "autograde"))

import checks  # noqa: E402
import pusht.evaluate as ev  # noqa: E402
import pusht.grading as grading  # noqa: E402
from pusht.ensemble import block_disagreement as package_disagreement  # noqa: E402
from pusht.reward import reward_from_obs as package_reward  # noqa: E402


def verdict(grading_dir, test, fn):
    grading.submit(test.test_id, fn)
    return checks.judge(test, grading_dir / "results" / f"{test.test_id}.npz")


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


def test_correct_implementations_pass_every_case(grading_dir):
    for test, fn in ((checks.REWARD, reward), (checks.LAMBDA, lambda_return), (checks.DREAM, dream),
                     (checks.DISAGREE, block_disagreement)):
        v = verdict(grading_dir, test, fn)
        assert v.passed, (test.test_id, v.message)


def test_a_wrong_reward_fails_with_a_hint(grading_dir):
    v = verdict(grading_dir, checks.REWARD, reward_acos)
    assert not v.passed and "first failure" in v.message


def test_always_equal_objects_record_nothing_that_passes(grading_dir):
    class Yes(float):
        def __eq__(self, other):
            return True

    v = verdict(grading_dir, checks.REWARD, lambda *a: (Yes(0.0), Yes(0.0), Yes(0.0)))
    assert not v.passed


def test_the_package_reference_refuses_to_run_inside_a_probe(grading_dir):
    for test, fn in ((checks.REWARD, package_reward), (checks.REWARD, lambda *a: package_reward(*a)),
                     (checks.DREAM, lambda *a: ev.dream(*a)), (checks.DISAGREE, package_disagreement)):
        v = verdict(grading_dir, test, fn)
        assert not v.passed and "package's own solution" in v.message
    assert package_reward(torch.zeros(6), torch.zeros(6), torch.ones(6))[0] == 0   # outside: as usual


def test_missing_results_and_delegation_earn_nothing(grading_dir):
    assert not checks.judge(checks.REWARD, grading_dir / "nothing.npz").passed
    v = checks.judge(checks.REWARD, "", delegation=["cell 3, line 1: from pusht.reward import reward_from_obs"])
    assert not v.passed and "write it yourself" in v.message


def test_verdicts_judged_in_several_threads_at_once_are_the_verdicts_judged_alone(grading_dir):
    # grade_task judges in its own process, and several tasks finish in threads of one process; the
    # reference probes seed torch's global generator, so judgements must not interleave
    import base64
    from concurrent.futures import ThreadPoolExecutor

    import grade

    grading.submit(checks.DREAM.test_id, dream)
    raw = base64.b64encode((grading_dir / "results" / f"{checks.DREAM.test_id}.npz").read_bytes()).decode()

    def judged(_):
        results = {"04.ipynb": {"results": {checks.DREAM.test_id: raw}}}
        grade.judge_results(results)
        return results["04.ipynb"]["verdicts"][checks.DREAM.test_id]["message"]

    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    with ThreadPoolExecutor(4) as pool:
        messages = list(pool.map(judged, range(24)))
    assert set(messages) == {f"all {len(checks.DREAM.cases)} checks passed"}, set(messages)
    assert torch.equal(torch.rand(3), expected)        # the caller's random numbers are its own
