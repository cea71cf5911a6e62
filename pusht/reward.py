"""The PushT reward, computed analytically from an observation instead of learned.

Dreamer learns a reward head because on pixels it has nothing else. Here the reward is a known
function of the T's pose, so we read it straight off the observation: the decoded one in a dream,
the true one in the real sim. Same function in both worlds, so any gap between them is a gap
between the states, not between two reward definitions. And in a dream this reads the block pose
the world model *imagined*: if the model is wrong about the block, the reward is wrong with it.
"""

from __future__ import annotations

import torch

from .env import ANG_SCALE, POS_SCALE
from .reference import reference


@reference("02_reward: reward_from_obs")
def reward_from_obs(norm_obs: torch.Tensor, mean: torch.Tensor, std: torch.Tensor):
    """Shaped PushT reward of normalised observations (any leading shape, last dim 6).

    De-normalise (``obs = norm_obs * std + mean``), then read the T's centre ``obs[..., 2:4]`` and
    yaw ``atan2(sin, cos)`` from ``obs[..., 4:6]``; the target is the origin with yaw 0.

    Returns ``(reward, pos_err, ang_err)``, each of the leading shape: reward per step (0 on the
    target; -1 for a block 0.5 m away and upside down), position error in metres, |yaw error| in
    radians. Differentiable in ``norm_obs``.
    """
    obs = norm_obs * std + mean
    pos_err = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang_err = torch.abs(torch.atan2(obs[..., 4], obs[..., 5]))
    reward = -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE)
    return reward, pos_err, ang_err
