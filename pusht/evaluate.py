"""The headline: deploy the SAME deterministic policy in two worlds and compare.

* DREAM: filter the start frame into (h, z), then roll the prior forward under the policy for
  ``horizon`` steps, decode every state, score the decoded T pose.
* REAL: at every step filter (h, z) on the TRUE frame, act, step the real pymunk sim, score the
  true T pose with the same reward function. Success is the env's own flag.

All starts run as one batch: one torch call per step for all of them, which is what makes the
evaluation cheap (at these sizes the cost is per operation, not per number).

Two control dreams tell the actor's exploitation apart from the model's own drift: the same dream
driven by zero actions, and by the untrained (initial) actor. The target sits where the expert data
usually leaves the block, so a model that loses track of the block may decode it near the target
all by itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .env import ANG_SCALE, POS_SCALE, PUSHER_RADIUS, PushTEnv, distance_to_tee, obs_to_pose
from .metric_keys import FINAL_YAW, key
from .reference import reference
from .reward import reward_from_obs


@dataclass
class Rollout:
    """One batch of trajectories in one world, in physical units."""

    obs: np.ndarray       # (T+1, B, 6) metres; in a dream, obs[0] is the decoded start frame
                          # (a "delta" world model's dream starts at the true start frame itself)
    actions: np.ndarray   # (T, B, 2)
    rewards: np.ndarray   # (T, B) reward per step on arrival; NaN after an episode ended
    pos_err: np.ndarray   # (T, B) metres, same masking
    success: np.ndarray   # (B,) bool (always False in a dream: the env's flag exists only in reality)

    @property
    def return_per_step(self) -> np.ndarray:
        """(B,) mean reward per step over the steps each episode lasted."""
        return np.nanmean(self.rewards, axis=0)

    @property
    def final_tee_dist(self) -> np.ndarray:
        """(B,) block-to-target distance (m) at each episode's last step."""
        _, tee = obs_to_pose(self.obs[-1])
        return np.linalg.norm(tee[:, :2], axis=-1)

    @property
    def final_yaw_err(self) -> np.ndarray:
        """(B,) |yaw error| of the block (degrees) at each episode's last step."""
        _, tee = obs_to_pose(self.obs[-1])
        return np.degrees(np.abs(tee[:, 2]))

    def reward_part(self, part: str) -> np.ndarray:
        """(T, B) one of the reward's two terms per step, masked like ``rewards``: "position"
        (-0.5 * block distance / POS_SCALE) or "yaw" (-0.5 * |yaw error| / ANG_SCALE), read off
        ``obs[1:]`` as ``reward_from_obs`` reads it. The two add up to ``rewards`` (to float32
        rounding: the rewards were computed in float32)."""
        _, tee = obs_to_pose(self.obs[1:])
        if part == "position":
            term = -0.5 * np.linalg.norm(tee[..., :2], axis=-1) / POS_SCALE
        elif part == "yaw":
            term = -0.5 * np.abs(tee[..., 2]) / ANG_SCALE
        else:
            raise ValueError(f"part must be 'position' or 'yaw', got {part!r}")
        return np.where(np.isnan(self.rewards), np.nan, term)


def policy_of(agent):
    """The deterministic policy of an ActorCritic: state -> tanh(mean)."""
    return lambda state: agent.act(state, sample=False)[0]


def zero_policy(state):
    """A control: never move the pusher."""
    return state.new_zeros(state.shape[0], 2)


def _to_np(x):
    return x.detach().cpu().numpy().astype(np.float64)


@reference("04_imagination_gap: dream")
def dream(wm, policy, norm_obs0: torch.Tensor, horizon: int):
    """The imagined half of the evaluation, in the model's own (normalised) units.

    Warm the state on the start frames only: ``h = 0``, ``z = posterior(h, encoder(o_0))``. Then,
    ``horizon`` times: act on ``[h, z]``, step the prior with ``wm.img_step``. Decode every state,
    the start included. Returns (decoded observations (T+1, B, D), actions (T, B, A)).

    The decoding goes through ``wm.decode_dream(hs, zs, norm_obs0)``: for the chapter's world
    model (``predicts="state"``) that is exactly ``wm.decode(hs, zs)``. A ``"delta"`` model decodes
    changes, which ``decode_dream`` adds up from the start frame (its frame 0 is ``norm_obs0``).
    """
    if horizon < 1:
        raise ValueError(f"horizon must be at least 1 step, got {horizon}")
    h, _ = wm._init(norm_obs0.shape[0])
    z = wm.filter_step(h, norm_obs0)
    hs, zs, acts = [h], [z], []
    for _ in range(horizon):
        a = policy(torch.cat([h, z], dim=-1))
        h, z = wm.img_step(h, z, a)
        hs.append(h)
        zs.append(z)
        acts.append(a)
    return wm.decode_dream(torch.stack(hs), torch.stack(zs), norm_obs0), torch.stack(acts)


@torch.inference_mode()
def dream_rollout(wm, policy, obs0: np.ndarray, horizon: int, mean, std, dream_fn=dream) -> Rollout:
    """Warm (h, z) on the start frames ``obs0`` (B, 6, metres) and dream ``horizon`` steps.

    ``dream_fn`` (default: :func:`dream`) does the dreaming; a learner can pass their own.
    """
    norm0 = torch.as_tensor((obs0 - _to_np(mean)) / _to_np(std), dtype=torch.float32, device=mean.device)
    norm, acts = dream_fn(wm, policy, norm0, horizon)                        # (T+1, B, D), (T, B, A)
    if tuple(norm.shape) != (horizon + 1, len(obs0), mean.shape[-1]):
        raise ValueError(f"dream_fn must return decoded observations of shape (horizon+1, B, D) = "
                         f"{(horizon + 1, len(obs0), mean.shape[-1])}; got {tuple(norm.shape)}")
    r, pos, _ = reward_from_obs(norm[1:], mean, std)
    return Rollout(obs=_to_np(norm * std + mean), actions=_to_np(acts), rewards=_to_np(r),
                   pos_err=_to_np(pos), success=np.zeros(len(obs0), dtype=bool))


@torch.inference_mode()
def real_rollout(wm, policy, seeds, horizon: int, mean, std) -> Rollout:
    """Run the policy in the real sim from ``env.reset(seed)`` for each seed, all in lockstep."""
    envs = [PushTEnv() for _ in seeds]
    B = len(envs)
    obs = np.zeros((horizon + 1, B, 6))
    obs[0] = [env.reset(s) for env, s in zip(envs, seeds)]
    actions = np.zeros((horizon, B, 2))
    alive = np.ones((horizon, B), dtype=bool)     # alive[t]: the episode was still running at step t
    success = np.zeros(B, dtype=bool)
    mean_np, std_np = _to_np(mean), _to_np(std)
    h, _ = wm._init(B)
    live = np.ones(B, dtype=bool)
    for t in range(horizon):
        norm = torch.as_tensor((obs[t] - mean_np) / std_np, dtype=torch.float32, device=mean.device)
        z = wm.filter_step(h, norm)
        a = policy(torch.cat([h, z], dim=-1))
        actions[t] = _to_np(a)
        obs[t + 1] = obs[t]
        alive[t] = live
        for i in np.flatnonzero(live):
            obs[t + 1, i], _, done, info = envs[i].step(actions[t, i])
            success[i] = info["success"]
            live[i] = not done
        h = wm.gru(torch.cat([z, a], dim=-1), h)
    norm_next = torch.as_tensor((obs[1:] - mean_np) / std_np, dtype=torch.float32, device=mean.device)
    r, pos, _ = reward_from_obs(norm_next, mean, std)      # the SAME reward function, true states
    r, pos = _to_np(r), _to_np(pos)
    r[~alive], pos[~alive] = np.nan, np.nan
    return Rollout(obs=obs, actions=actions, rewards=r, pos_err=pos, success=success)


def expert_rollout(seeds, horizon: int, mean, std) -> Rollout:
    """The scripted expert (``pusht.expert``), which solves the task, in the real sim from
    ``env.reset(seed)`` for each seed, in lockstep, acting on the TRUE observations. Scored with
    the same ``reward_from_obs`` as every other rollout."""
    from .expert import ScriptedExpert

    envs = [PushTEnv() for _ in seeds]
    B = len(envs)
    expert = ScriptedExpert(batch_size=B)
    obs = np.zeros((horizon + 1, B, 6))
    obs[0] = [env.reset(s) for env, s in zip(envs, seeds)]
    actions = np.zeros((horizon, B, 2))
    alive = np.ones((horizon, B), dtype=bool)
    success = np.zeros(B, dtype=bool)
    live = np.ones(B, dtype=bool)
    for t in range(horizon):
        actions[t] = expert.act(obs[t])
        obs[t + 1] = obs[t]
        alive[t] = live
        for i in np.flatnonzero(live):
            obs[t + 1, i], _, done, info = envs[i].step(actions[t, i])
            success[i] = info["success"]
            live[i] = not done
    mean_np, std_np = _to_np(mean), _to_np(std)
    norm_next = torch.as_tensor((obs[1:] - mean_np) / std_np, dtype=torch.float32, device=mean.device)
    with torch.inference_mode():
        r, pos, _ = reward_from_obs(norm_next, mean, std)
    r, pos = _to_np(r), _to_np(pos)
    r[~alive], pos[~alive] = np.nan, np.nan
    return Rollout(obs=obs, actions=actions, rewards=r, pos_err=pos, success=success)


def replay_rollout(wm, real: Rollout, mean, std) -> Rollout:
    """The dream of ``real``'s own actions, replayed open-loop from its start frames with the
    package's :func:`dream` (steps after a real episode ended are masked as in ``real``). Used for
    the expert: would the dream rate the pushes that solve the task as reality does?"""
    actions = torch.as_tensor(real.actions, dtype=torch.float32, device=mean.device)
    step = iter(range(len(actions)))

    def replay(state):                     # dream() calls the policy once per step, in order
        return actions[next(step)]

    roll = dream_rollout(wm, replay, real.obs[0], len(actions), mean, std)
    roll.rewards[np.isnan(real.rewards)] = np.nan
    roll.pos_err[np.isnan(real.rewards)] = np.nan
    return roll


def pusher_gap(rollout: Rollout) -> np.ndarray:
    """(T+1, B) free space (m) between the pusher's rim and the T; about 0 means touching."""
    pusher, tee = obs_to_pose(rollout.obs)
    return distance_to_tee(pusher, tee) - PUSHER_RADIUS


TOUCH_TOL = 0.003   # m: a rim within 3 mm of the T counts as a touch


def two_world_eval(wm, agent, init_agent, seeds, horizon: int, mean, std,
                   dream_fn=dream, train_horizon: int | None = None) -> tuple[dict, dict]:
    """Evaluate ``agent`` in the dream and in reality on the same starts, plus two control dreams.

    ``dream_fn`` does the dreaming (see :func:`dream`); a learner can pass their own.

    Returns ``(metrics, rollouts)``: metrics is a flat dict of floats, rollouts maps
    ``"dream"``, ``"real"`` (the trained policy; also under ``"dream_trained"``/``"real_trained"``),
    ``"dream_zero"``, ``"dream_untrained"``, ``"real_zero"``, ``"real_untrained"``, ``"real_expert"``
    (the scripted expert in reality) and ``"dream_expert"`` (its actions replayed in the dream) to
    ``Rollout``. With ``train_horizon``, the gap and its split (``split.gap_split``) are measured
    over the first ``train_horizon`` steps (what the actor's gradient saw) and over all of them, in
    total and for each of the reward's two terms (keys ``..._position_<span>``, ``..._yaw_<span>``),
    and so is the expert control (``split.expert_signal``).
    """
    was_training = agent.training
    agent.eval()
    real = real_rollout(wm, policy_of(agent), seeds, horizon, mean, std)
    obs0 = real.obs[0]
    rollouts = {
        "dream": dream_rollout(wm, policy_of(agent), obs0, horizon, mean, std, dream_fn),
        "real": real,
        "dream_zero": dream_rollout(wm, zero_policy, obs0, horizon, mean, std, dream_fn),
        "dream_untrained": dream_rollout(wm, policy_of(init_agent), obs0, horizon, mean, std, dream_fn),
        # the same two controls in reality: what zero actions and the untrained actor really earn
        "real_zero": real_rollout(wm, zero_policy, seeds, horizon, mean, std),
        "real_untrained": real_rollout(wm, policy_of(init_agent), seeds, horizon, mean, std),
        # a control for whether the dream can recognise success at all: the scripted expert, which
        # solves the real task, in reality, and its very actions replayed in the dream
        "real_expert": expert_rollout(seeds, horizon, mean, std),
    }
    rollouts["dream_expert"] = replay_rollout(wm, rollouts["real_expert"], mean, std)
    rollouts["dream_trained"], rollouts["real_trained"] = rollouts["dream"], rollouts["real"]
    agent.train(was_training)

    dream = rollouts["dream"]
    imag_return = float(dream.return_per_step.mean())
    real_return = float(real.return_per_step.mean())
    _, tee = obs_to_pose(real.obs)
    spawn = np.linalg.norm(tee[0, :, :2], axis=-1)
    moved = np.linalg.norm(tee[-1, :, :2] - tee[0, :, :2], axis=-1)
    min_gap = np.nanmin(pusher_gap(real), axis=0)
    metrics = {
        "imagined_return_per_step": imag_return,
        "real_return_per_step": real_return,
        "imagination_gap": imag_return - real_return,
        "imagined_final_tee_dist": float(dream.final_tee_dist.mean()),
        "real_final_tee_dist": float(real.final_tee_dist.mean()),
        "real_success_rate": float(real.success.mean()),
        "spawn_tee_dist": float(spawn.mean()),
        "real_block_displacement": float(moved.mean()),
        "real_block_displacement_max": float(moved.max()),
        "real_pusher_min_gap": float(min_gap.mean()),
        "real_episodes_touching_block": int((min_gap < TOUCH_TOL).sum()),
    }
    # the dream's rating of the two controls (written whole: grep finds these keys here)
    zero, untrained = rollouts["dream_zero"], rollouts["dream_untrained"]
    metrics["zero_action_dream_return_per_step"] = float(zero.return_per_step.mean())
    metrics["zero_action_dream_final_tee_dist"] = float(zero.final_tee_dist.mean())
    metrics["untrained_actor_dream_return_per_step"] = float(untrained.return_per_step.mean())
    metrics["untrained_actor_dream_final_tee_dist"] = float(untrained.final_tee_dist.mean())
    for world in ("dream", "real"):
        for pol in ("zero", "trained", "expert"):
            roll = rollouts[f"{world}_{pol}"]
            metrics[key(FINAL_YAW, policy=pol, world=world)] = float(roll.final_yaw_err.mean())
    metrics["expert_real_success_rate"] = float(rollouts["real_expert"].success.mean())
    metrics["expert_dream_final_tee_dist"] = float(rollouts["dream_expert"].final_tee_dist.mean())
    metrics["expert_real_final_tee_dist"] = float(rollouts["real_expert"].final_tee_dist.mean())
    metrics["zero_action_real_final_tee_dist"] = float(rollouts["real_zero"].final_tee_dist.mean())
    # the control for "real successes appear": how often a pusher that never moves succeeds from these starts
    metrics["zero_action_real_success_rate"] = float(rollouts["real_zero"].success.mean())
    if train_horizon is not None:
        from .split import PARTS, expert_signal, gap_split, size_split

        for span, steps in (("train_horizon", min(train_horizon, horizon)), ("eval_horizon", None)):
            for part in PARTS:
                metrics.update(gap_split(rollouts, steps, part, span))
            metrics.update(size_split(rollouts, steps, span))
            metrics.update(expert_signal(rollouts, steps, span))
    return metrics, rollouts
