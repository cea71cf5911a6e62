"""The actor and the critic, both reading the world model's state [h, z].

Why [h, z]: it exists in both worlds. In a dream we get it by rolling the prior; on the real robot
we get it by filtering the posterior on real frames. Same features, so the same policy runs in each.

The actor is a Gaussian squashed by tanh: actions stay in the env's [-1, 1], and a sample is
``tanh(mean + std * noise)``, a differentiable function of the actor's parameters. That is what
lets the imagined return be differentiated *through the frozen world model* into the policy
(Dreamer's analytic, or pathwise, actor gradient).
"""

from __future__ import annotations

import math

import torch
from torch import nn


def _mlp(inp: int, hidden: int, out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(inp, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(),
                         nn.Linear(hidden, out))


class ActorCritic(nn.Module):
    def __init__(self, state_dim: int, act_dim: int, hidden_dim: int):
        super().__init__()
        self.actor = _mlp(state_dim, hidden_dim, act_dim)
        self.log_std = nn.Parameter(torch.zeros(act_dim))      # state-independent exploration
        self.critic = _mlp(state_dim, hidden_dim, 1)

    def act(self, state: torch.Tensor, sample: bool = True, noise: torch.Tensor | None = None):
        """(B, S) -> (action (B, A) in [-1, 1], entropy of the pre-tanh Gaussian, a scalar).

        A sample is ``tanh(mean + std * noise)`` with standard-normal ``noise`` (drawn here unless
        given). ``sample=False`` returns ``tanh(mean)``: the deterministic policy used for
        evaluation in both worlds.
        """
        mean = self.actor(state)
        if sample:
            noise = torch.randn_like(mean) if noise is None else noise
            mean = mean + torch.exp(self.log_std) * noise
        return torch.tanh(mean), self.entropy()

    def entropy(self) -> torch.Tensor:
        """Entropy (nats) of the diagonal Gaussian before the tanh; depends on log_std only."""
        return (0.5 + 0.5 * math.log(2 * math.pi) + self.log_std).sum()

    def value(self, state: torch.Tensor) -> torch.Tensor:
        """Critic's estimate of the lambda-return from a state: (..., S) -> (...)."""
        return self.critic(state).squeeze(-1)
