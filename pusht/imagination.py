"""Learning a policy inside the frozen world model: the Dreamer move.

Every gradient the actor sees comes from a dream. Each update:

1. take real expert sequences, filter ``context + 1`` true frames into start states (h, z);
2. roll the FROZEN prior forward ``imag_horizon`` steps under the actor's own sampled actions;
3. decode every dreamed state and score it with the analytic reward (``reward.py``);
4. mix those rewards with the critic's bootstrap into Dreamer's lambda-return;
5. the actor maximises the return by backpropagating through the frozen model (pathwise
   gradient), *through the critic's values too*; the critic regresses on the detached return.

Step 5 is DreamerV1's wiring (``danijar/dreamer``, ``Dreamer._train``): the values inside the
actor's return are computed on the imagined features WITH their gradient, so the critic's slope
tells the actor which way is better beyond the last dreamed step, while only the actor's own
parameters are stepped by the actor loss. The critic is trained on detached features and a
detached target. ``critic_wiring="page"`` keeps the chapter page's version as a contrast: there
the values are detached, so the actor's gradient comes from the dreamed rewards alone and the
critic never reaches it.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from .optim import Adam
from .reference import reference
from .reward import reward_from_obs


@reference("03_imagination_actor: lambda_return")
def lambda_return(rewards: torch.Tensor, values: torch.Tensor, gamma: float, lam: float) -> torch.Tensor:
    """Dreamer's lambda-return, computed backwards from the horizon.

    ``G_t = r_t + gamma * ((1 - lam) * V_{t+1} + lam * G_{t+1})``, with ``G_H = V_H``.

    ``rewards`` (H, B): the reward on arriving in state t+1. ``values`` (H+1, B): critic values of
    states 0..H. Returns (H, B). ``lam = 0`` gives one-step TD targets, ``lam = 1`` the discounted
    dream return bootstrapped only at the horizon.
    """
    if values.shape[0] != rewards.shape[0] + 1:
        raise ValueError(f"values needs one more step than rewards (H+1 vs H); got "
                         f"{tuple(values.shape)} and {tuple(rewards.shape)}")
    out, last = [], values[-1]
    for t in reversed(range(rewards.shape[0])):
        last = rewards[t] + gamma * ((1 - lam) * values[t + 1] + lam * last)
        out.append(last)
    return torch.stack(out[::-1])


def freeze(module: nn.Module) -> nn.Module:
    """Stop a module's parameters from learning; gradients still flow *through* it."""
    for p in module.parameters():
        p.requires_grad_(False)
    return module


def imagine(wm, agent, h, z, horizon: int, obs0=None):
    """Roll the prior under the actor's sampled actions. Returns states [h, z] (H+1, B, S),
    decoded normalised observations (H, B, D) and the actor's entropy (scalar).

    ``obs0`` (B, D): the normalised real frame (h, z) was filtered on, which a ``"delta"`` world
    model adds its decoded changes to (``wm.decode_dream``); a ``"state"`` model ignores it.

    Written for speed without changing the maths of ``agent.act``: the noise for every step is
    drawn in one call, the std and the entropy (which depend on ``log_std`` only) are computed
    once, and all dreamed states are decoded in one batched call at the end. At these sizes the
    cost is per operation, not per number, so fewer operations is what makes it fast.
    """
    noise = torch.randn(horizon, h.shape[0], agent.log_std.shape[0], device=h.device)  # (H, B, A)
    std = torch.exp(agent.log_std)
    states = [torch.cat([h, z], dim=-1)]
    for t in range(horizon):
        action = torch.tanh(agent.actor(states[-1]) + std * noise[t])      # (B, A), reparameterised
        h, z = wm.img_step(h, z, action)
        states.append(torch.cat([h, z], dim=-1))
    states = torch.stack(states)                                        # (H+1, B, S)
    hs, zs = states[1:].split([wm.hidden_dim, wm.latent_dim], dim=-1)  # views of the dreamed states
    obs_pred = wm.decode_dream(hs, zs, obs0, includes_start=False)      # (H, B, D)
    return states, obs_pred, agent.entropy()


WIRINGS = ("dreamer", "page")


@reference("03_imagination_actor: actor_critic_losses")
def actor_critic_losses(agent, states, rewards, entropy, gamma: float, lam: float, ent_coef: float,
                        return_fn=lambda_return):
    """Dreamer's two losses on one batch of dreams. Returns ``(actor_loss, critic_loss)``, scalars.

    ``states`` (H+1, B, S): the imagined [h, z], carrying the gradient back to the actor's actions.
    ``rewards`` (H, B): the decoded dream's rewards, carrying gradient too. ``entropy``: the
    actor's entropy (a scalar tensor).

    * actor: maximise the mean lambda-return plus ``ent_coef`` x entropy. The return bootstraps
      on the critic's values of the imagined states *with their gradient*: the actor learns from
      the critic's slope as well as from the rewards.
    * critic: regress V(state) for states 0..H-1 on the return, with the states and the target
      both detached. The target's detach is essential: the critic must not chase a target that
      moves with it. The states' detach keeps the critic loss off the actor's road: with
      :func:`set_gradients`, which hands each loss's gradient to its own network, it changes no
      gradient (notebook 03 measures it); with one summed ``backward()`` it would move the actor.
    """
    values = agent.value(states)                                        # (H+1, B), gradient kept
    returns = return_fn(rewards, values, gamma, lam)                    # (H, B)
    actor_loss = -(returns.mean() + ent_coef * entropy)
    critic_loss = 0.5 * F.mse_loss(agent.value(states.detach())[:-1], returns.detach())
    return actor_loss, critic_loss


def page_losses(agent, states, rewards, entropy, gamma: float, lam: float, ent_coef: float,
                return_fn=lambda_return):
    """The chapter page's wiring, kept as a measured contrast: the values are computed on
    detached states and detached again inside the return, so no gradient from the critic ever
    reaches the actor (its gradient comes from the H dreamed rewards alone)."""
    values = agent.value(states.detach())
    returns = return_fn(rewards, values.detach(), gamma, lam)
    actor_loss = -(returns.mean() + ent_coef * entropy)
    critic_loss = 0.5 * F.mse_loss(values[:-1], returns.detach())
    return actor_loss, critic_loss


def losses_for(wiring: str):
    """The loss function of a ``critic_wiring`` value."""
    if wiring == "dreamer":
        return actor_critic_losses
    if wiring == "page":
        return page_losses
    raise ValueError(f"critic_wiring must be one of {WIRINGS}, got {wiring!r}")


def actor_params(agent) -> list:
    return [*agent.actor.parameters(), agent.log_std]


def set_gradients(agent, actor_loss, critic_loss, clip: float = 100.0) -> tuple[float, float]:
    """Put each loss's gradient on its own parameters only, as Dreamer's two optimisers do.

    The actor's parameters get the gradient of ``actor_loss`` (none of the critic loss); the
    critic's get the gradient of ``critic_loss`` (none of the actor loss, though the actor's
    return runs through the critic). Each group is clipped to norm ``clip`` on its own.
    Returns the two norms before clipping.
    """
    a_params, c_params = actor_params(agent), list(agent.critic.parameters())
    a_grads = torch.autograd.grad(actor_loss, a_params, retain_graph=True, allow_unused=True)
    c_grads = torch.autograd.grad(critic_loss, c_params, allow_unused=True)
    for params, grads in ((a_params, a_grads), (c_params, c_grads)):
        for p, g in zip(params, grads):
            p.grad = torch.zeros_like(p) if g is None else g
    a_norm = nn.utils.clip_grad_norm_(a_params, clip)
    c_norm = nn.utils.clip_grad_norm_(c_params, clip)
    return float(a_norm), float(c_norm)


def train_in_imagination(wm, agent, starts_obs, starts_act, mean, std, cfg, gen: torch.Generator,
                         monitor=None, progress=None, log=print, reward_fn=reward_from_obs,
                         return_fn=lambda_return, loss_fn=None):
    """Train ``agent`` purely in dreams of the frozen ``wm``. Returns the training history.

    ``starts_obs`` (N, C+1, D) and ``starts_act`` (N, C, A): normalised real frames to warm the
    start states from. ``monitor(agent) -> float``, if given, is called every
    ``cfg.monitor_every`` iterations and at the last one, and should return the policy's mean
    reward per step in the REAL sim: it only watches, no gradient ever comes from it.
    ``reward_fn(norm_obs, mean, std)``, ``return_fn(rewards, values, gamma, lam)`` and ``loss_fn``
    (the signature of :func:`actor_critic_losses`; default: the one ``cfg.critic_wiring`` names)
    default to this package's; a learner can pass their own and watch it drive the training.
    History: ``imag_reward`` (per-step imagined reward, every iteration), ``imag_return`` (the
    mean lambda-return the actor maximised, critic bootstrap included), ``critic_loss``,
    ``log_std``, and ``monitor_iters``/``monitor_real_reward``.

    An ensemble (``ensemble.EnsembleWorldModel``, which has ``disagreement``) adds
    ``imag_disagreement``: the members' mean disagreement on the dreamed block position (m) per
    iteration. With ``cfg.disagreement_penalty`` > 0 the actor is trained on the reward minus that
    weight times the disagreement (MOPO's penalty); ``imag_reward`` stays the task reward.
    """
    freeze(wm)
    if loss_fn is None:              # a learner's own loss_fn uses their own lambda-return
        package_losses = losses_for(cfg.critic_wiring)
        loss_fn = lambda *args: package_losses(*args, return_fn=return_fn)  # noqa: E731
    opt = Adam(agent.parameters(), lr=cfg.actor_lr)
    hist = {"imag_reward": [], "imag_return": [], "critic_loss": [], "log_std": [], "monitor_iters": [],
            "monitor_real_reward": []}
    if hasattr(wm, "disagreement"):
        hist["imag_disagreement"] = []
    with torch.no_grad():   # real start states are data: filter them once, not every update
        starts_h, starts_z = wm.warm(starts_obs, starts_act)
    iters = range(cfg.imag_iters)
    for it in (progress(iters) if progress else iters):
        if monitor is not None and it % cfg.monitor_every == 0:
            hist["monitor_iters"].append(it)
            hist["monitor_real_reward"].append(monitor(agent))
        idx = torch.randint(len(starts_obs), (cfg.imag_batch,), generator=gen)
        states, obs_pred, entropy = imagine(wm, agent, starts_h[idx], starts_z[idx], cfg.imag_horizon,
                                            starts_obs[idx][:, -1])
        rewards = task_rewards = reward_fn(obs_pred, mean, std)[0]      # (H, B)
        if "imag_disagreement" in hist:        # an ensemble: how far apart its members dream the block
            disagreement = wm.disagreement(states[1:], std, starts_obs[idx][:, -1])  # (H, B), metres
            hist["imag_disagreement"].append(disagreement.mean().item())
            if cfg.disagreement_penalty > 0:
                rewards = task_rewards - cfg.disagreement_penalty * disagreement

        actor_loss, critic_loss = loss_fn(agent, states, rewards, entropy, cfg.gamma, cfg.lam,
                                          cfg.ent_coef)
        opt.zero_grad()
        set_gradients(agent, actor_loss, critic_loss)
        opt.step()

        hist["imag_reward"].append(task_rewards.mean().item())
        hist["imag_return"].append(-(actor_loss.item() + cfg.ent_coef * entropy.item()))
        hist["critic_loss"].append(critic_loss.item())
        hist["log_std"].append(agent.log_std.mean().item())
        if log and (it % max(cfg.imag_iters // 5, 1) == 0 or it == cfg.imag_iters - 1):
            log(f"[imag] iter {it:4d}  imagined reward/step {hist['imag_reward'][-1]:+.4f}  "
                f"critic {hist['critic_loss'][-1]:.4f}")
    if monitor is not None:
        hist["monitor_iters"].append(cfg.imag_iters)
        hist["monitor_real_reward"].append(monitor(agent))
    return {k: np.array(v) for k, v in hist.items()}
