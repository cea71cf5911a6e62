"""A world model that decodes changes instead of states (``WorldModel(..., predicts="delta")``).

The chapter's model (``"state"``) must stay bit for bit what it was at every decode site; a delta
model's dreams must start at the real start frame and add up scaled changes from there, and the
frame each change belongs to must be the same in training, dreaming, replay and measurement.
"""

import math

import numpy as np
import pytest
import torch

from pusht.analysis import expert_replay_error
from pusht.config import make_config
from pusht.data import load_expert_data
from pusht.dreamer import parse_config, run
from pusht.stage_cache import stage_path
from pusht.wm_stage import WM_FIELDS
from pusht.evaluate import dream, zero_policy
from pusht.imagination import freeze, imagine
from pusht.agent import ActorCritic
from pusht.world_model import WorldModel, prediction_error_vs_copy_last, train_world_model

H, Z = 16, 8


def _model(predicts, seed=0):
    torch.manual_seed(seed)
    return WorldModel(6, 2, latent_dim=Z, hidden_dim=H, embed_dim=8, predicts=predicts).eval()


def _sequences(seed=0, n=12, T=7):
    g = torch.Generator().manual_seed(seed)
    obs = torch.randn(n, T + 1, 6, generator=g).cumsum(1) * 0.3        # a random walk: real deltas
    act = torch.rand(n, T, 2, generator=g) * 2 - 1
    return obs, act


# --- the state model: nothing changes ---------------------------------------------------------
def test_state_decode_dream_is_decode_bit_for_bit():
    wm = _model("state")
    hs, zs, obs0 = torch.randn(6, 5, H), torch.rand(6, 5, Z) * 2 - 1, torch.randn(5, 6)
    for kwargs in ({}, {"includes_start": False}):
        assert torch.equal(wm.decode_dream(hs, zs, obs0, **kwargs), wm.decode(hs, zs))
        assert torch.equal(wm.decode_dream(hs, zs, None, **kwargs), wm.decode(hs, zs))
    assert "delta_std" not in wm.state_dict()        # the state model's weights hash as before


def _old_imagine(wm, agent, h, z, horizon):
    """imagine() as it was before decode_dream: the state model's reference."""
    noise = torch.randn(horizon, h.shape[0], agent.log_std.shape[0])
    std = torch.exp(agent.log_std)
    states = [torch.cat([h, z], dim=-1)]
    for t in range(horizon):
        action = torch.tanh(agent.actor(states[-1]) + std * noise[t])
        h, z = wm.img_step(h, z, action)
        states.append(torch.cat([h, z], dim=-1))
    states = torch.stack(states)
    return states, wm.decoder(states[1:]), agent.entropy()


def test_state_imagine_gives_the_same_floats_and_gradients_as_before():
    wm = freeze(_model("state"))
    obs, act = _sequences()
    results = []
    for fn in (_old_imagine, lambda *a: imagine(*a, obs0=obs[:, 2])):
        torch.manual_seed(3)
        agent = ActorCritic(H + Z, 2, 16)
        h, z = wm.warm(obs[:, :3], act[:, :2])
        states, obs_pred, _ = fn(wm, agent, h, z, 5)
        (obs_pred.square().sum() + agent.value(states).sum()).backward()
        results.append([states, obs_pred, *[p.grad for p in agent.actor.parameters()]])
    for old, new in zip(*results):
        assert torch.equal(old, new)


def test_state_dream_decodes_the_start_state():
    wm = _model("state")
    obs0 = torch.randn(4, 6)
    frames, _ = dream(wm, zero_policy, obs0, 3)
    h, _ = wm._init(4)
    assert torch.equal(frames[0], wm.decode(h, wm.filter_step(h, obs0)))


# --- the delta model ----------------------------------------------------------------------------
def test_delta_scale_is_the_std_of_the_one_step_changes_with_a_floor():
    wm = _model("delta")
    obs, _ = _sequences()
    obs[..., 5] = 1.0                                   # a dimension that never changes
    wm.set_delta_scale(obs)
    d = (obs[:, 1:] - obs[:, :-1]).reshape(-1, 6)
    assert torch.allclose(wm.delta_std[:5], d[:, :5].std(0))
    assert wm.delta_std[5] == pytest.approx(1e-6)
    assert "delta_std" in wm.state_dict()
    with pytest.raises(ValueError, match="'delta' model"):
        _model("state").set_delta_scale(obs)
    with pytest.raises(ValueError, match="predicts must be one of"):
        WorldModel(6, 2, Z, H, 8, predicts="states")


def test_delta_observe_regresses_the_scaled_changes_after_the_first_frame():
    wm = _model("delta")
    obs, act = _sequences()
    wm.set_delta_scale(obs)
    recon, _ = wm.observe(obs, act)
    h, z = wm.filter(obs, act)
    target = (obs[:, 1:] - obs[:, :-1]) / wm.delta_std
    assert torch.equal(recon, torch.nn.functional.mse_loss(wm.decode(h[:, 1:], z[:, 1:]), target))


def test_delta_dream_starts_at_the_start_frame_and_adds_scaled_changes():
    wm = _model("delta")
    obs, _ = _sequences()
    wm.set_delta_scale(obs)
    obs0 = obs[:, 0]
    frames, _ = dream(wm, zero_policy, obs0, 4)                           # (5, B, D)
    assert torch.equal(frames[0], obs0)                                   # exactly the start frame
    # re-run the same dream by hand: each frame is the previous one plus its state's change
    h, _ = wm._init(len(obs0))
    z = wm.filter_step(h, obs0)
    prev = obs0
    for t in range(1, 5):
        h, z = wm.img_step(h, z, zero_policy(h))
        step = wm.decode(h, z) * wm.delta_std
        assert torch.allclose(frames[t], prev + step, atol=1e-5)
        prev = frames[t]


def test_delta_imagine_needs_and_starts_from_the_start_frame():
    wm = freeze(_model("delta"))
    obs, act = _sequences()
    wm.set_delta_scale(obs)
    torch.manual_seed(1)
    agent = ActorCritic(H + Z, 2, 16)
    h, z = wm.warm(obs[:, :3], act[:, :2])
    with pytest.raises(ValueError, match="start frame"):
        imagine(wm, agent, h, z, 3)
    states, obs_pred, _ = imagine(wm, agent, h, z, 3, obs0=obs[:, 2])
    first = wm.decode(states[1, :, :H], states[1, :, H:]) * wm.delta_std
    assert torch.equal(obs_pred[0], obs[:, 2] + first)                    # one step: o_c + change
    later = wm.decode(states[2:, :, :H], states[2:, :, H:]) * wm.delta_std
    assert torch.allclose(obs_pred[1:] - obs_pred[:-1], later, atol=1e-5)


def test_training_in_imagination_starts_each_dream_at_its_own_last_context_frame(monkeypatch):
    import pusht.imagination as imagination

    wm = _model("delta")
    obs, act = _sequences(n=10)
    wm.set_delta_scale(obs)
    seen = []

    def spy(wm_, agent, h, z, horizon, obs0=None):
        seen.append((h.clone(), obs0.clone()))
        return imagine(wm_, agent, h, z, horizon, obs0)

    monkeypatch.setattr(imagination, "imagine", spy)
    torch.manual_seed(2)
    agent = ActorCritic(H + Z, 2, 16)
    cfg = make_config(smoke=True, imag_iters=2, imag_batch=6, imag_horizon=3)
    imagination.train_in_imagination(wm, agent, obs[:, :3], act[:, :2], torch.zeros(6), torch.ones(6),
                                     cfg, torch.Generator().manual_seed(0), log=None)
    starts_h, _ = wm.warm(obs[:, :3], act[:, :2])
    assert len(seen) == 2
    for h, obs0 in seen:
        for row_h, row_o in zip(h, obs0):
            j = [k for k in range(len(obs)) if torch.equal(starts_h[k], row_h)]
            assert len(j) == 1 and torch.equal(row_o, obs[j[0], 2])


def _oracle(wm, frames_tf):
    """Make ``wm.decode`` return the TRUE scaled changes of ``frames_tf`` (T+1, B, D), so a correct
    delta bookkeeping reproduces the true frames exactly: decode(states of frames 0..T) gets row t =
    (o_t - o_{t-1}) / delta_std and a nonsense row 0 (the start state's output must be unused)."""
    true = (frames_tf[1:] - frames_tf[:-1]) / wm.delta_std
    rows = torch.cat([torch.full_like(true[:1], 1e3), true])             # (T+1, B, D)
    calls = {"step": 0}

    def decode(h, z):
        if h.dim() == 3 and h.shape[0] == rows.shape[0]:                  # a whole dream, time first
            return rows
        if h.dim() == 3:                                                  # one-step: (B, T, .) from t=1
            return rows[1:].transpose(0, 1)
        calls["step"] += 1                                                # open loop, one step at a time
        return rows[wm._oracle_start + calls["step"]]
    return decode


def test_every_decode_site_gives_a_delta_oracle_the_true_frames():
    data = load_expert_data(0, 6, 5, 8, None)
    T = data.torch()
    wm = _model("delta")
    wm.set_delta_scale(T["train_obs"])
    val = T["val_obs"]                                                    # (M, 9, 6) normalised
    # replay (through evaluate.dream): the dream from frame 0 under the true actions
    wm.decode = _oracle(wm, val.transpose(0, 1))
    rep = expert_replay_error(wm, data.val_obs, data.val_act, T["mean"], T["std"])
    assert rep["pusher"].max() < 1e-5 and rep["block"].max() < 1e-5
    # one step and open loop (from the last of context + 1 filtered frames)
    context = 2
    wm._oracle_start = context
    wm.decode = _oracle(wm, val.transpose(0, 1))
    err = prediction_error_vs_copy_last(wm, val, T["val_act"], T["std"], context)
    assert err["one_step_model"].max() < 1e-5 and err["open_loop_model"].max() < 1e-5
    assert err["one_step_copy"].max() > 1e-3                               # the oracle beat something


# --- the pipeline -------------------------------------------------------------------------------
def test_wm_predicts_is_validated_a_cli_choice_and_part_of_the_cache_key(tmp_path):
    with pytest.raises(ValueError, match="wm_predicts must be 'state' or 'delta'"):
        make_config(wm_predicts="deltas")
    cfg, _ = parse_config(["--smoke", "--wm_predicts", "delta"])
    assert cfg.wm_predicts == "delta" and make_config().wm_predicts == "state"
    with pytest.raises(SystemExit):
        parse_config(["--wm_predicts", "deltas"])
    keys = {p: stage_path(tmp_path, "wm", make_config(smoke=True, wm_predicts=p), WM_FIELDS, "pusht.wm_stage")
            for p in ("state", "delta")}
    assert keys["state"] != keys["delta"]


def test_a_delta_smoke_run_completes_with_finite_metrics(tmp_path):
    res = run(make_config(smoke=True, wm_predicts="delta", out=tmp_path), log=None)
    assert res.wm.predicts == "delta" and bool((res.wm.delta_std > 0).all())
    bad = [k for k, v in res.metrics.items() if isinstance(v, float) and not math.isfinite(v)]
    assert not bad, bad
    dreamed = res.rollouts["dream"].obs
    assert np.allclose(dreamed[0], res.rollouts["real"].obs[0], atol=1e-5)   # the dream starts at reality


def _block_ratio(err):
    """One-step RMSE of the block's centre, model over copy-last (both x and y together)."""
    return float(np.sqrt((err["one_step_model"][2:4] ** 2).sum() / (err["one_step_copy"][2:4] ** 2).sum()))


def test_a_briefly_trained_delta_model_beats_copy_last_on_the_block_one_step():
    """Measured (seeds 0-9 at this size, 1-2 s of training each): trained 0.68-0.77, untrained
    0.998-1.03. The untrained check shows the bound is not met by construction (a delta model
    that predicts nothing is copy-last)."""
    data = load_expert_data(0, 100, 30, 16, None)
    T = data.torch()
    cfg = make_config(smoke=True, wm_epochs=20)
    torch.manual_seed(0)
    wm = WorldModel(6, 2, cfg.latent_dim, cfg.hidden_dim, cfg.embed_dim, predicts="delta")
    wm.set_delta_scale(T["train_obs"])
    untrained = _block_ratio(prediction_error_vs_copy_last(wm, T["val_obs"], T["val_act"], T["std"]))
    train_world_model(wm, T["train_obs"], T["train_act"], cfg, torch.Generator().manual_seed(0), log=None)
    trained = _block_ratio(prediction_error_vs_copy_last(wm, T["val_obs"], T["val_act"], T["std"]))
    assert untrained > 0.95
    assert trained < 0.85
