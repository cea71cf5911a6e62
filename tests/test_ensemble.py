"""The ensemble of world models (pusht/ensemble.py) and MOPO's disagreement penalty, smoke-sized."""

import copy

import numpy as np
import pytest
import torch

from pusht.agent import ActorCritic
from pusht.config import make_config
from pusht.agent_stage import AGENT_FIELDS
from pusht.dreamer import run, world_model_stage
from pusht.stage_cache import sources
from pusht.wm_stage import WM_FIELDS
from pusht.ensemble import EnsembleWorldModel
from pusht.evaluate import dream, policy_of, two_world_eval
from pusht.imagination import actor_critic_losses, imagine, set_gradients, train_in_imagination
from pusht.reward import reward_from_obs
from pusht.world_model import WorldModel

H, Z, E = 16, 8, 8
MEAN, STD = torch.zeros(6), torch.full((6,), 0.2)


def member(seed, predicts="state"):
    torch.manual_seed(seed)
    return WorldModel(6, 2, Z, H, E, predicts=predicts).eval()


def ensemble(k, copies=False):
    first = member(0)
    return EnsembleWorldModel([copy.deepcopy(first) if copies else member(1000 * i) for i in range(k)]
                              if k > 1 else [first])


@pytest.mark.parametrize("predicts", ["state", "delta"])
def test_an_ensemble_of_one_is_exactly_its_member(predicts):
    wm = member(0, predicts)
    ens = EnsembleWorldModel([wm])
    assert (ens.hidden_dim, ens.latent_dim) == (H, Z)
    g = torch.Generator().manual_seed(1)
    obs, act = torch.randn(4, 4, 6, generator=g), torch.rand(4, 3, 2, generator=g) * 2 - 1
    same = lambda a, b: all(torch.equal(x, y) for x, y in zip(a, b))  # noqa: E731
    with torch.no_grad():
        h, z = wm.warm(obs, act)
        assert same(ens.warm(obs, act), (h, z)) and same(ens.filter(obs, act), wm.filter(obs, act))
        assert same(ens._init(4), wm._init(4))
        assert torch.equal(ens.filter_step(h, obs[:, 0]), wm.filter_step(h, obs[:, 0]))
        assert same(ens.img_step(h, z, act[:, 0]), wm.img_step(h, z, act[:, 0]))
        assert same(ens.step(h, z, act[:, 0]), wm.step(h, z, act[:, 0]))
        assert torch.equal(ens.gru(torch.cat([z, act[:, 0]], -1), h), wm.gru(torch.cat([z, act[:, 0]], -1), h))
        assert torch.equal(ens.prior(h), wm.prior(h))
        assert torch.equal(ens.decoder(torch.cat([h, z], -1)), wm.decoder(torch.cat([h, z], -1)))
        assert torch.equal(ens.decode_dream(h[None], z[None], obs[:, 0]), wm.decode_dream(h[None], z[None], obs[:, 0]))
        assert same(ens.observe(obs, act), wm.observe(obs, act))
        policy = policy_of(ActorCritic(H + Z, 2, 16))
        assert same(dream(ens, policy, obs[:, 0], 5), dream(wm, policy, obs[:, 0], 5))
        assert torch.equal(ens.disagreement(torch.cat([h, z], -1)[None], obs0=obs[:, 0]), torch.zeros(1, 4))
    agent = ActorCritic(H + Z, 2, 16)
    torch.manual_seed(3)
    a = imagine(wm, agent, h, z, 5, obs[:, 0])
    torch.manual_seed(3)
    b = imagine(ens, agent, h, z, 5, obs[:, 0])
    assert same(a, b)


def test_the_state_is_the_members_side_by_side_and_every_rollout_runs_on_it():
    ens = ensemble(3)
    assert (ens.hidden_dim, ens.latent_dim) == (3 * H, 3 * Z)
    agent = ActorCritic(ens.hidden_dim + ens.latent_dim, 2, 16)
    assert agent.actor[0].in_features == 3 * (H + Z)
    metrics, rollouts = two_world_eval(ens, agent, copy.deepcopy(agent), [0, 1], 6, MEAN, STD,
                                       train_horizon=3)
    assert {"dream", "real", "dream_zero", "dream_untrained", "real_zero", "real_untrained"} <= set(rollouts)
    assert rollouts["dream"].obs.shape == (7, 2, 6) and rollouts["real"].obs.shape == (7, 2, 6)
    assert all(np.isfinite(v) for v in metrics.values())
    # the state really is [h_1, h_2, h_3, z_1, z_2, z_3]: member 1's own step, read off its slices
    h, z = ens._init(2)
    a = torch.full((2, 2), 0.5)
    h2, z2 = ens.img_step(h, z, a)
    h1, z1 = ens.members[1].img_step(h[:, H:2 * H], z[:, Z:2 * Z], a)
    assert torch.equal(h2[:, H:2 * H], h1) and torch.equal(z2[:, Z:2 * Z], z1)
    # and its decoded observation is the members' mean
    assert torch.allclose(ens.decode(h2, z2), torch.stack(
        [m.decode(*m.img_step(torch.zeros(2, H), torch.zeros(2, Z), a)) for m in ens.members]).mean(0))


def _dream_states(ens, seed=0):
    torch.manual_seed(seed)
    agent = ActorCritic(ens.hidden_dim + ens.latent_dim, 2, 16)
    h, z = ens.warm(torch.randn(5, 3, 6), torch.rand(5, 2, 2) * 2 - 1)
    states, _, _ = imagine(ens, agent, h, z, 6)
    return states


def test_disagreement_is_zero_for_copies_and_positive_for_other_initialisations():
    copies, others = ensemble(3, copies=True), ensemble(3)
    d_copies = copies.disagreement(_dream_states(copies)[1:], STD)
    assert d_copies.shape == (6, 5)
    assert torch.equal(d_copies, torch.zeros(6, 5))
    d_others = others.disagreement(_dream_states(others)[1:], STD)
    assert (d_others > 0).all()
    # metres when std is given: the block's dims scaled by their std (0.2 here)
    assert torch.allclose(others.disagreement(_dream_states(others)[1:]) * 0.2, d_others)
    # zero disagreement has a zero gradient, not NaN (sqrt's slope is infinite at 0)
    states = _dream_states(copies)[1:].detach().requires_grad_(True)
    copies.disagreement(states, STD).sum().backward()
    assert torch.equal(states.grad, torch.zeros_like(states))


def _actor_gradient(ens, penalty):
    torch.manual_seed(0)
    agent = ActorCritic(ens.hidden_dim + ens.latent_dim, 2, 16)
    torch.manual_seed(1)
    obs0 = torch.randn(8, 3, 6)
    h, z = ens.warm(obs0, torch.rand(8, 2, 2) * 2 - 1)
    states, obs_pred, entropy = imagine(ens, agent, h, z, 6, obs0[:, -1])
    rewards = reward_from_obs(obs_pred, MEAN, STD)[0]
    if penalty > 0:
        rewards = rewards - penalty * ens.disagreement(states[1:], STD, obs0[:, -1])
    actor_loss, critic_loss = actor_critic_losses(agent, states, rewards, entropy, 0.99, 0.95, 3e-4)
    set_gradients(agent, actor_loss, critic_loss)
    return torch.cat([p.grad.ravel() for p in agent.actor.parameters()])


def test_the_penalty_changes_the_actors_gradient():
    ens = ensemble(3)
    for p in ens.parameters():
        p.requires_grad_(False)
    base, penalised = _actor_gradient(ens, 0.0), _actor_gradient(ens, 1.0)
    assert torch.isfinite(penalised).all()
    assert not torch.equal(base, penalised)
    assert torch.equal(base, _actor_gradient(ens, 0.0))             # same seed, same gradient


def test_train_in_imagination_records_the_disagreement_and_penalises_only_when_asked():
    ens = ensemble(2)
    starts_obs, starts_act = torch.randn(8, 3, 6), torch.rand(8, 2, 2) * 2 - 1
    hists = {}
    for penalty in (0.0, 5.0):
        cfg = make_config(smoke=True, ensemble_size=2, disagreement_penalty=penalty, imag_iters=3,
                          imag_batch=4, imag_horizon=5)
        torch.manual_seed(0)
        agent = ActorCritic(ens.hidden_dim + ens.latent_dim, 2, 16)
        hists[penalty] = train_in_imagination(ens, agent, starts_obs, starts_act, MEAN, STD, cfg,
                                              torch.Generator().manual_seed(0), log=None)
        assert len(hists[penalty]["imag_disagreement"]) == 3
        assert (hists[penalty]["imag_disagreement"] > 0).all()
    # the first update's dreams are the same; the task reward is recorded, not the penalised one
    assert hists[0.0]["imag_reward"][0] == hists[5.0]["imag_reward"][0]
    assert hists[0.0]["imag_return"][0] != hists[5.0]["imag_return"][0]


def test_the_config_fields_are_validated_and_key_the_caches():
    assert make_config().ensemble_size == 1 and make_config().disagreement_penalty == 0.0
    for bad, message in ((dict(ensemble_size=0), "ensemble_size"),
                         (dict(ensemble_size=3, disagreement_penalty=-1.0), "disagreement_penalty"),
                         (dict(disagreement_penalty=1.0), "needs ensemble_size")):
        with pytest.raises(ValueError, match=message):
            make_config(**bad)
    assert "ensemble_size" in WM_FIELDS and "disagreement_penalty" in AGENT_FIELDS
    assert any(p.name == "ensemble.py" for p in sources("pusht.wm_stage"))


def test_member_0_is_the_single_model_of_the_same_config():
    single = world_model_stage(make_config(smoke=True, wm_epochs=1), log=None).wm
    ens = world_model_stage(make_config(smoke=True, wm_epochs=1, ensemble_size=2), log=None).wm
    assert isinstance(ens, EnsembleWorldModel) and len(ens) == 2
    s0, s1 = ens.members[0].state_dict(), ens.members[1].state_dict()
    assert all(torch.equal(v, s0[k]) for k, v in single.state_dict().items())
    assert not all(torch.equal(v, s1[k]) for k, v in s0.items())


def test_a_smoke_run_with_an_ensemble_and_the_penalty(tmp_path):
    res = run(make_config(smoke=True, ensemble_size=3, disagreement_penalty=1.0, out=tmp_path), log=None)
    assert isinstance(res.wm, EnsembleWorldModel) and len(res.wm) == 3
    assert res.agent.actor[0].in_features == 3 * (res.cfg.hidden_dim + res.cfg.latent_dim)
    assert all(np.isfinite(v) for v in res.metrics.values() if isinstance(v, float))
    for span in ("train_horizon", "eval_horizon"):
        assert res.metrics[f"wm_ensemble_disagreement_{span}"] > 0
    assert len(res.history["imag_disagreement"]) == res.cfg.imag_iters
    assert res.history["wm_recon_members"].shape[0] == 3
