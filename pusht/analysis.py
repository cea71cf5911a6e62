"""How far the deployed policy takes the model from the data it knows: where the pusher goes, how
well the model tracks the policy's own real actions against the expert's, and how the long dream's
end points collapse.

Everything here reads rollouts the evaluation already made (``evaluate.two_world_eval``) plus the
expert data; nothing trains. The numbers go into ``metrics.json`` and notebook 04 reads them. The
split of the gap itself into drift, motion and training is ``split.py``'s.
"""

from __future__ import annotations

import numpy as np
import torch

from .env import ARENA_HALF, PUSHER_RADIUS, WALL_RADIUS, obs_to_pose
from .evaluate import Rollout, dream

# A pusher whose centre is this close to where a wall stops it counts as "against the wall". 5 mm
# is 1/6 of its radius; a pusher travelling at full speed moves 50 mm per step, so it is not a
# pusher merely passing by.
AT_WALL_TOL = 0.005
WALL_STOP = ARENA_HALF - WALL_RADIUS - PUSHER_RADIUS      # 0.466 m: the pusher centre's limit


def at_wall(obs: np.ndarray) -> np.ndarray:
    """(..., 6) observations in metres -> (...) bool: the pusher is pinned against a wall."""
    pusher = np.asarray(obs)[..., :2]
    return (np.abs(pusher) >= WALL_STOP - AT_WALL_TOL).any(axis=-1)


def replay_error(wm, real, mean, std) -> dict:
    """Dream from each real start under the actions the policy really took, and compare.

    Returns ``pusher`` and ``block`` (T, B): the distance (m) between the dreamed and the true
    pusher (block centre) after each step. The dream is warmed on the start frame only, as the
    evaluation dream is, so any error is the model's own prediction of where the actions lead.
    """
    mean_np, std_np = mean.detach().cpu().numpy(), std.detach().cpu().numpy()
    norm0 = torch.as_tensor((real.obs[0] - mean_np) / std_np, dtype=torch.float32)
    actions = torch.as_tensor(real.actions, dtype=torch.float32)
    step = iter(range(len(actions)))

    def replay(state):                     # dream() calls the policy once per step, in order
        return actions[next(step)]

    with torch.inference_mode():
        norm, _ = dream(wm, replay, norm0, len(actions))
    dreamed = norm.double().numpy() * std_np + mean_np                     # (T+1, B, 6) metres
    return {"pusher": np.linalg.norm(dreamed[1:, :, :2] - real.obs[1:, :, :2], axis=-1),
            "block": np.linalg.norm(dreamed[1:, :, 2:4] - real.obs[1:, :, 2:4], axis=-1)}


def expert_replay_error(wm, val_obs: np.ndarray, val_act: np.ndarray, mean, std) -> dict:
    """The same replay on held-out EXPERT clips (metres in, (T, M) errors out): the model on
    the kind of data it was trained on, the reference for :func:`replay_error`."""
    T = val_act.shape[1]
    roll = Rollout(obs=np.swapaxes(val_obs, 0, 1), actions=np.swapaxes(val_act, 0, 1),
                   rewards=np.zeros((T, len(val_obs))), pos_err=np.zeros((T, len(val_obs))),
                   success=np.zeros(len(val_obs), dtype=bool))
    return replay_error(wm, roll, mean, std)


def spread(xy: np.ndarray) -> float:
    """(B, 2) points -> mean distance (m) from their centroid: how far apart the starts end up."""
    return float(np.linalg.norm(xy - xy.mean(0), axis=-1).mean())


def shift_metrics(wm, rollouts: dict, data, mean, std, train_horizon: int, seq_len: int) -> dict:
    """Distribution shift, measured: where the deployed policy takes the pusher compared with the
    expert data, how the model tracks the policy's own real actions compared with the expert's,
    and how the long evaluation dream collapses its end points. Flat floats for metrics.json."""
    real, dream = rollouts["real_trained"], rollouts["dream_trained"]
    alive = ~np.isnan(real.rewards)                                         # (T, B)
    rep = replay_error(wm, real, mean, std)
    exp = expert_replay_error(wm, data.val_obs, data.val_act, mean, std)
    k = min(train_horizon, len(rep["pusher"]), len(exp["pusher"])) - 1      # the step 1.5 s in
    _, tee_dream = obs_to_pose(dream.obs[-1])
    _, tee_real = obs_to_pose(real.obs[-1])
    _, tee_spawn = obs_to_pose(real.obs[0])
    return {
        "real_pusher_at_wall_share": float(at_wall(real.obs[1:])[alive].mean()),
        "expert_pusher_at_wall_share": float(at_wall(data.train_obs).mean()),
        "replay_pusher_err_train_horizon": float(rep["pusher"][k].mean()),
        "replay_block_err_train_horizon": float(rep["block"][k].mean()),
        "replay_pusher_err_eval_horizon": float(rep["pusher"][-1].mean()),
        "replay_block_err_eval_horizon": float(rep["block"][-1].mean()),
        "expert_replay_pusher_err_train_horizon": float(exp["pusher"][k].mean()),
        "expert_replay_block_err_train_horizon": float(exp["block"][k].mean()),
        "train_clip_steps": int(seq_len),
        "dream_steps_per_train_clip": float(len(dream.rewards) / seq_len),
        "dream_final_block_spread": spread(tee_dream[:, :2]),
        "real_final_block_spread": spread(tee_real[:, :2]),
        "spawn_block_spread": spread(tee_spawn[:, :2]),
    }
