"""The PushT sim: what a learner can rely on when they step it."""

import math

import numpy as np
import pytest

from pusht.env import (MAX_SPEED, PUSHER_RADIUS, PushTEnv, distance_to_tee, sample_start,
                       shaped_reward)


def rollout(seed, n=80):
    env = PushTEnv()
    obs = [env.reset(seed)]
    rng = np.random.default_rng(123)
    for _ in range(n):
        o, r, done, info = env.step(rng.uniform(-1, 1, 2))
        obs.append(o)
        if done:
            break
    return np.array(obs)


def test_same_seed_same_trajectory_bit_for_bit():
    a, b = rollout(7), rollout(7)
    assert a.shape == b.shape and np.array_equal(a, b)
    assert not np.array_equal(a, rollout(8))


def test_observation_layout_and_reward():
    env = PushTEnv()
    obs = env.reset(state=[0.3, 0.3, 0.1, -0.05, 0.5])
    np.testing.assert_allclose(obs, [0.3, 0.3, 0.1, -0.05, math.sin(0.5), math.cos(0.5)])
    obs, reward, done, info = env.step([0.0, 0.0])        # nothing moves under a zero command
    np.testing.assert_allclose(obs, [0.3, 0.3, 0.1, -0.05, math.sin(0.5), math.cos(0.5)], atol=1e-9)
    pos_err = math.hypot(0.1, -0.05)
    assert reward == pytest.approx(-0.5 * (pos_err / 0.5 + 0.5 / math.pi))
    assert info["pos_err"] == pytest.approx(pos_err) and not info["success"] and not done


def test_pusher_moves_at_commanded_speed_in_free_space():
    env = PushTEnv()
    env.reset(state=[-0.3, -0.3, 0.2, 0.2, 0.0])
    xs = [env.step([1.0, 0.0])[0][0] for _ in range(4)]
    # From rest the first 10 ms substep only gets the disc moving; then it travels v * 0.1 s a step.
    assert xs[0] - (-0.3) == pytest.approx(0.9 * MAX_SPEED * 0.1, rel=0.02)
    np.testing.assert_allclose(np.diff(xs), MAX_SPEED * 0.1, rtol=0.02)
    assert env.pusher_xy[1] == pytest.approx(-0.3, abs=1e-6)


def test_block_moves_only_while_pushed():
    env = PushTEnv()
    env.reset(state=[0.0, -0.35, 0.0, -0.1, 0.0])        # pusher under the stem
    for _ in range(6):
        obs, *_ = env.step([0.0, 1.0])
    moved = obs[3] - (-0.1)
    assert moved > 0.1                                     # pushed up along the stem
    obs1, *_ = env.step([0.0, -1.0])                       # back off
    for _ in range(4):
        obs2, *_ = env.step([0.0, -1.0])
    # Quasi-static: the block coasts for at most one 10 ms substep, then stays exactly put.
    assert 0 <= obs1[3] - obs[3] <= MAX_SPEED * 0.01 + 2e-4     # + contact slop
    assert obs2[3] == obs1[3]


def test_wall_stops_the_block_and_pusher_stays_in_arena():
    env = PushTEnv()
    env.reset(state=[0.0, 0.1, 0.0, 0.3, 0.3])
    for _ in range(60):
        obs, *_ = env.step([0.0, 1.0])
    assert obs[3] + 0.09 <= 0.5                             # bar's top edge never passes the wall
    assert np.all(np.abs(obs[:2]) <= 0.5 - PUSHER_RADIUS + 1e-6)


def test_random_starts_never_overlap_and_spawn_about_017m_away():
    rng = np.random.default_rng(0)
    starts = [sample_start(rng) for _ in range(2000)]
    gaps = [distance_to_tee(p, t) - PUSHER_RADIUS for p, t in starts]
    assert min(gaps) > 0
    mean_dist = np.mean([np.linalg.norm(t[:2]) for _, t in starts])
    assert 0.15 < mean_dist < 0.19


def test_success_ends_the_episode():
    env = PushTEnv()
    env.reset(state=[0.0, -0.206, 0.0, -0.025, 0.0])       # T 2.5 cm below the target, pusher under it
    done, info = False, {}
    for _ in range(20):
        obs, reward, done, info = env.step([0.0, 0.05])    # creep up at 2.5 mm a step
        if done:
            break
    assert done and info["success"]
    with pytest.raises(RuntimeError, match="reset"):
        env.step([0.0, 0.0])


@pytest.mark.parametrize("bad, message", [
    ([float("nan"), 0.0], "finite"),
    ([0.0, float("inf")], "finite"),
    ([0.0, 0.0, 0.0], "shape"),
    ([[0.0, 0.0]], "shape"),
])
def test_bad_actions_raise_clear_errors(bad, message):
    env = PushTEnv()
    env.reset(0)
    with pytest.raises(ValueError, match=message):
        env.step(bad)
    env.step([0.0, 0.0])                                   # the episode is still usable


def test_out_of_range_actions_are_clipped():
    a, b = PushTEnv(), PushTEnv()
    a.reset(3)
    b.reset(3)
    np.testing.assert_array_equal(a.step([5.0, -7.0])[0], b.step([1.0, -1.0])[0])


def test_shaped_reward_wraps_angles():
    r1, _, ang1 = shaped_reward([0.0, 0.0], 2 * math.pi - 0.1)
    assert ang1 == pytest.approx(0.1)
    assert r1 == pytest.approx(-0.5 * 0.1 / math.pi)
