"""The learning pieces: reward, lambda-return, and the analytic gradient through a frozen model."""

import math

import numpy as np
import pytest
import torch

from pusht.agent import ActorCritic
from pusht.env import PushTEnv, shaped_reward
from pusht.imagination import freeze, imagine, lambda_return
from pusht.reward import reward_from_obs
from pusht.world_model import WorldModel


def test_reward_from_obs_matches_the_env_on_true_states():
    env = PushTEnv()
    obs = [env.reset(s) for s in range(8)]
    obs = np.array(obs)
    mean, std = obs.mean(0), obs.std(0) + 0.1
    norm = torch.tensor((obs - mean) / std, dtype=torch.float64)
    r, pos, ang = reward_from_obs(norm, torch.tensor(mean), torch.tensor(std))
    yaw = np.arctan2(obs[:, 4], obs[:, 5])
    r_env, pos_env, ang_env = shaped_reward(obs[:, 2:4], yaw)
    np.testing.assert_allclose(r.numpy(), r_env, atol=1e-12)
    np.testing.assert_allclose(pos.numpy(), pos_env, atol=1e-12)
    np.testing.assert_allclose(ang.numpy(), ang_env, atol=1e-12)


def test_reward_from_obs_any_leading_shape_and_differentiable():
    norm = torch.randn(5, 3, 6, requires_grad=True)
    r, pos, ang = reward_from_obs(norm, torch.zeros(6), torch.ones(6))
    assert r.shape == pos.shape == ang.shape == (5, 3)
    r.sum().backward()
    assert torch.isfinite(norm.grad).all() and norm.grad[..., 2:6].abs().sum() > 0
    assert norm.grad[..., :2].abs().sum() == 0          # the pusher's position earns nothing


def test_reward_is_zero_at_the_target_and_minus_one_at_worst():
    obs = torch.tensor([[0.3, 0.3, 0.0, 0.0, 0.0, 1.0],            # T on target
                        [0.3, 0.3, 0.5, 0.0, 0.0, -1.0]])          # 0.5 m away, upside down
    r, _, _ = reward_from_obs(obs, torch.zeros(6), torch.ones(6))
    np.testing.assert_allclose(r.numpy(), [0.0, -1.0], atol=1e-6)


def test_lambda_return_by_hand():
    rewards = torch.tensor([[1.0], [2.0]])          # H = 2, B = 1
    values = torch.tensor([[10.0], [20.0], [30.0]])
    g, lam = 0.5, 0.5
    # G_1 = r_1 + g * V_2 (the bootstrap at the horizon) = 2 + 15 = 17
    # G_0 = r_0 + g * ((1 - lam) * V_1 + lam * G_1) = 1 + 0.5 * (10 + 8.5) = 10.25
    out = lambda_return(rewards, values, g, lam)
    np.testing.assert_allclose(out[:, 0].numpy(), [10.25, 17.0])


def test_lambda_return_limits():
    torch.manual_seed(0)
    r, v = torch.randn(6, 4), torch.randn(7, 4)
    td = lambda_return(r, v, 0.9, 0.0)
    torch.testing.assert_close(td, r + 0.9 * v[1:])                 # lam = 0: one-step TD targets
    mc = lambda_return(r, v, 0.9, 1.0)
    disc = 0.9 ** torch.arange(6.0)
    expect0 = (disc[:, None] * r).sum(0) + 0.9 ** 6 * v[-1]         # lam = 1: whole dream + V_H
    torch.testing.assert_close(mc[0], expect0)


def test_lambda_return_rejects_mismatched_lengths():
    with pytest.raises(ValueError, match="one more step"):
        lambda_return(torch.zeros(5, 2), torch.zeros(5, 2), 0.99, 0.95)


def test_actor_gradient_flows_through_the_frozen_model_but_never_into_it():
    torch.manual_seed(0)
    wm = freeze(WorldModel(6, 2, latent_dim=8, hidden_dim=16, embed_dim=8))
    agent = ActorCritic(16 + 8, 2, 16)
    h, z = wm.warm(torch.randn(4, 3, 6), torch.randn(4, 2, 2).clamp(-1, 1))
    states, obs_pred, _ = imagine(wm, agent, h, z, horizon=5)
    rewards = reward_from_obs(obs_pred, torch.zeros(6), torch.ones(6))[0]
    rewards.mean().backward()
    actor_grads = [p.grad for p in agent.actor.parameters()]
    assert all(g is not None and g.abs().sum() > 0 for g in actor_grads)
    assert agent.log_std.grad is not None and agent.log_std.grad.abs().sum() > 0
    assert all(p.grad is None and not p.requires_grad for p in wm.parameters())
    assert all(p.grad is None for p in agent.critic.parameters())  # the reward path skips the critic


def test_deterministic_actions_are_tanh_of_the_mean_and_in_range():
    torch.manual_seed(0)
    agent = ActorCritic(10, 2, 32)
    s = torch.randn(7, 10) * 100
    a, ent = agent.act(s, sample=False)
    torch.testing.assert_close(a, torch.tanh(agent.actor(s)))
    assert a.abs().max() <= 1
    assert ent.item() == pytest.approx(2 * (0.5 + 0.5 * math.log(2 * math.pi)))
    sampled, _ = agent.act(s, sample=True)
    assert not torch.equal(sampled, a) and sampled.abs().max() <= 1


def test_world_model_learns_to_reconstruct():
    torch.manual_seed(0)
    obs, act = torch.randn(16, 6, 6), torch.rand(16, 5, 2) * 2 - 1
    wm = WorldModel(6, 2, 8, 32, 16)
    opt = torch.optim.Adam(wm.parameters(), lr=3e-3)
    first = None
    for _ in range(150):
        recon, dyn = wm.observe(obs, act)
        first = first if first is not None else recon.item()
        opt.zero_grad()
        (recon + dyn).backward()
        opt.step()
    assert recon.item() < 0.3 * first
    h, z, o = wm.step(*wm.warm(obs[:, :2], act[:, :1]), act[:, 1])
    assert h.shape == (16, 32) and z.shape == (16, 8) and o.shape == (16, 6)


# --- how the critic reaches the actor (DreamerV1's wiring; the page's kept as a contrast) ----------
def _dreams(seed=0):
    """A small frozen model, an agent, and one batch of dreams with their rewards."""
    torch.manual_seed(seed)
    wm = freeze(WorldModel(6, 2, latent_dim=8, hidden_dim=16, embed_dim=8))
    agent = ActorCritic(16 + 8, 2, 16)
    h, z = wm.warm(torch.randn(4, 3, 6), torch.randn(4, 2, 2).clamp(-1, 1))
    return wm, agent, h, z


def _actor_grads(wm, agent, h, z, wiring):
    from pusht.imagination import losses_for, set_gradients

    torch.manual_seed(1)                                          # the same action noise each time
    states, obs_pred, entropy = imagine(wm, agent, h, z, horizon=5)
    rewards = reward_from_obs(obs_pred, torch.zeros(6), torch.ones(6))[0]
    actor_loss, critic_loss = losses_for(wiring)(agent, states, rewards, entropy, 0.99, 0.95, 3e-4)
    agent.zero_grad()
    set_gradients(agent, actor_loss, critic_loss, clip=1e9)
    return [p.grad.clone() for p in [*agent.actor.parameters(), agent.log_std]], \
           [p.grad.clone() for p in agent.critic.parameters()], critic_loss


def _perturb_critic(agent):
    with torch.no_grad():
        for p in agent.critic.parameters():
            p.add_(0.5 * torch.randn_like(p))


@pytest.mark.parametrize("wiring, reaches", [("dreamer", True), ("page", False)])
def test_the_critic_reaches_the_actor_only_under_dreamers_wiring(wiring, reaches):
    wm, agent, h, z = _dreams()
    before, _, _ = _actor_grads(wm, agent, h, z, wiring)
    _perturb_critic(agent)
    after, _, _ = _actor_grads(wm, agent, h, z, wiring)
    same = all(torch.equal(a, b) for a, b in zip(before, after))
    assert same is not reaches          # page: other critic weights, bit-identical actor gradient
    assert all(p.grad is None and not p.requires_grad for p in wm.parameters())


@pytest.mark.parametrize("wiring", ["dreamer", "page"])
def test_each_loss_steps_only_its_own_parameters(wiring):
    from pusht.imagination import losses_for

    wm, agent, h, z = _dreams()
    _, critic_grads, _ = _actor_grads(wm, agent, h, z, wiring)
    # the critic's gradient is the critic loss's alone: recompute it with no actor loss at all
    torch.manual_seed(1)
    states, obs_pred, entropy = imagine(wm, agent, h, z, horizon=5)
    rewards = reward_from_obs(obs_pred, torch.zeros(6), torch.ones(6))[0]
    _, critic_loss = losses_for(wiring)(agent, states, rewards, entropy, 0.99, 0.95, 3e-4)
    alone = torch.autograd.grad(critic_loss, list(agent.critic.parameters()))
    for got, want in zip(critic_grads, alone):
        torch.testing.assert_close(got, want, rtol=0, atol=0)
    # ... and the critic loss pushes nothing into the actor (states and target are detached)
    actor_side = torch.autograd.grad(critic_loss, [*agent.actor.parameters(), agent.log_std],
                                     allow_unused=True)
    assert all(g is None or g.abs().sum() == 0 for g in actor_side)


def test_a_training_run_under_either_wiring_changes_only_the_agent():
    from pusht.config import make_config
    from pusht.imagination import train_in_imagination

    wm, agent, _, _ = _dreams()
    wm_before = [p.clone() for p in wm.parameters()]
    for wiring in ("dreamer", "page"):
        cfg = make_config(smoke=True, imag_iters=3, imag_batch=4, imag_horizon=4, critic_wiring=wiring)
        hist = train_in_imagination(wm, agent, torch.randn(8, 3, 6), torch.rand(8, 2, 2) * 2 - 1,
                                    torch.zeros(6), torch.ones(6), cfg, torch.Generator().manual_seed(0),
                                    log=None)
        assert np.isfinite(hist["imag_reward"]).all() and len(hist["imag_return"]) == 3
    assert all(torch.equal(a, b) for a, b in zip(wm_before, wm.parameters()))


def test_critic_wiring_is_validated_and_a_cli_flag():
    from pusht.config import make_config
    from pusht.dreamer import parse_config

    with pytest.raises(ValueError, match="critic_wiring"):
        make_config(critic_wiring="detached")
    cfg, _ = parse_config(["--critic_wiring", "page", "--smoke"])
    assert cfg.critic_wiring == "page" and make_config().critic_wiring == "dreamer"
