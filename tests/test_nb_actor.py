"""Notebook 03's support module: the gradient measurements tell Dreamer's wiring from the page's,
the figures draw, and the sentences follow the numbers."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import torch  # noqa: E402

from pusht.agent import ActorCritic  # noqa: E402
from pusht.imagination import actor_critic_losses, freeze, imagine, page_losses  # noqa: E402
from pusht.nb import actor  # noqa: E402
from pusht.reward import reward_from_obs  # noqa: E402
from pusht.world_model import WorldModel  # noqa: E402


def batch_maker():
    torch.manual_seed(0)
    wm = freeze(WorldModel(6, 2, latent_dim=8, hidden_dim=16, embed_dim=8))
    agent = ActorCritic(24, 2, 16)
    h, z = wm.warm(torch.randn(5, 3, 6), torch.rand(5, 2, 2) * 2 - 1)

    def make():
        torch.manual_seed(1)
        states, obs, ent = imagine(wm, agent, h, z, 4)
        return states, reward_from_obs(obs, torch.zeros(6), torch.ones(6))[0], ent
    return agent, make


def test_the_measurements_tell_the_two_wirings_apart():
    agent, make = batch_maker()
    dreamer = actor.gradient_reach(agent, *make(), actor_critic_losses, 0.99, 0.95, 3e-4)
    page = actor.gradient_reach(agent, *make(), page_losses, 0.99, 0.95, 3e-4)
    assert dreamer["actor loss", "states, via the values"] > 0 == page["actor loss", "states, via the values"]
    assert dreamer["critic loss", "states, via the values"] == 0 == page["critic loss", "states, via the values"]
    before = [p.clone() for p in agent.critic.parameters()]
    assert actor.critic_reaches_actor(agent, make, actor_critic_losses, 0.99, 0.95, 3e-4)
    assert not actor.critic_reaches_actor(agent, make, page_losses, 0.99, 0.95, 3e-4)
    assert all(torch.equal(a, b) for a, b in zip(before, agent.critic.parameters()))   # restored
    table = actor.reach_table({"Dreamer": dreamer, "page": page})
    assert table.count("\n") == 5 and "| actor loss | states, via the values |" in table


def _metrics(first, last, se, gap=0.2):
    return {"imagined_reward_first20_train": first, "imagined_reward_last20_train": last,
            "imagined_reward_rise_se": se, "real_reward_monitor_first": -0.4, "real_reward_monitor_last": -0.39,
            "imag_horizon": 15, "imagination_gap": gap, "real_success_rate": 0.0}


def test_a_rise_counts_only_beyond_twice_its_noise():
    assert actor.rose_beyond_noise(_metrics(-0.32, -0.28, 0.01))
    assert not actor.rose_beyond_noise(_metrics(-0.32, -0.31, 0.01))
    assert "a real rise" in actor.training_sentence(_metrics(-0.32, -0.28, 0.01))
    assert "cannot tell it from no change" in actor.training_sentence(_metrics(-0.32, -0.31, 0.01))
    same = actor.wiring_sentence(_metrics(-0.32, -0.30, 0.01), _metrics(-0.32, -0.29, 0.01))
    assert "within twice their combined noise" in same
    apart = actor.wiring_sentence(_metrics(-0.32, -0.31, 0.005), _metrics(-0.32, -0.25, 0.005, gap=0.3))
    assert "The page wiring raised" in apart and "+0.300" in apart


def test_figures_draw_with_labelled_axes():
    hist = {"imag_reward": np.linspace(-0.3, -0.2, 40), "imag_return": np.linspace(-3, -2, 40),
            "critic_loss": np.linspace(1, 0.1, 40), "log_std": np.zeros(40),
            "monitor_iters": [0, 20, 40], "monitor_real_reward": [-0.4, -0.4, -0.39]}
    for fig in (actor.fig_training({"a": hist, "b": hist}, 10), actor.fig_critic_and_std(hist),
                actor.fig_lambda_returns({0.0: np.zeros(5), 0.95: np.ones(5)}, 0.95, 64)):
        assert all(ax.get_xlabel() and ax.get_ylabel() for ax in fig.axes)


def test_self_checks_are_well_formed():
    for q in actor.SELF_CHECKS.values():
        assert q.answer in q.options and q.why and q.text.endswith("?")
