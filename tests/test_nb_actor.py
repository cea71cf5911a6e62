"""Notebook 03's support module: the gradient measurements tell Dreamer's wiring from the page's,
the figures draw, and the sentences follow the numbers."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import torch

from pusht.agent import ActorCritic
from pusht.imagination import actor_critic_losses, freeze, imagine, page_losses
from pusht.nb import actor
from pusht.reward import reward_from_obs
from pusht.world_model import WorldModel


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


def test_detach_effects_show_where_each_stop_gradient_matters():
    agent, make = batch_maker()
    e = actor.detach_effects(agent, make, actor_critic_losses, 0.99, 0.95, 3e-4)
    states, target = "critic loss reads the states undetached", "critic loss's target keeps its gradient"
    a, c = actor.GROUPS
    sg, sb = actor.ROUTES
    # set_gradients: the states' detach changes nothing, anywhere; one summed backward: the actor moves
    assert e[states, sg, a] == 0 == e[states, sg, c]
    assert e[states, sb, a] > 0 and e[states, sb, c] == 0
    # the target's detach matters even with set_gradients (for the critic), never for the actor there
    assert e[target, sg, c] > 0 and e[target, sg, a] == 0
    assert all(p.grad is None for p in agent.parameters())
    assert e["norm", sg, a] > 0 and e["norm", sb, c] > 0
    table = actor.detach_table(e)
    assert table.count("\n") == 5 and "bit-identical" in table and "**differs**" in table
    text = actor.detach_sentence(e)
    assert "changes nothing" in text and "stands between the critic and the policy" in text
    assert "matters in **both** set-ups" in text
    # the other branches, on made-up measurements
    other = {**e, (states, sg, a): 1e-3, (states, sb, a): 0.0, (target, sg, c): 0.0}
    text = actor.detach_sentence(other)
    assert "did not make the states' detach redundant" in text and "did not change the actor's gradient" in text
    assert "left the critic's gradient bit-identical" in text


def test_the_undetached_variants_keep_the_losses_values():
    agent, make = batch_maker()
    args = (*make(), 0.99, 0.95, 3e-4)
    a0, c0 = actor_critic_losses(agent, *args)
    for variant in (actor.states_undetached, actor.target_undetached):
        a1, c1 = variant(actor_critic_losses)(agent, *args)
        assert torch.equal(a0, a1) and torch.allclose(c0, c1)


def test_critic_reach_sentence_both_branches():
    assert "**changes**" in actor.critic_reach_sentence(0.1, 0.0)
    assert "stays bit-identical**: the page's actor" in actor.critic_reach_sentence(0.1, 0.0)
    s = actor.critic_reach_sentence(0.0, 0.2)
    assert "your actor never hears from the critic" in s and "not the package's `page_losses`" in s


def test_reach_reading_both_branches():
    keys = [("actor loss", "critic's weights"), ("actor loss", "states, via the values"),
            ("critic loss", "critic's weights"), ("critic loss", "states, via the values")]
    good = {"your losses": dict(zip(keys, (1.0, 1.0, 1.0, 0.0))),
            "the page's losses": dict(zip(keys, (0.0, 0.0, 1.0, 0.0)))}
    s = actor.reach_reading(good)
    assert "Dreamer's wiring" in s and "as Exercise B asks" in s and "rewards alone" in s
    bad = {"your losses": dict(zip(keys, (0.0, 0.0, 1.0, 0.5))),
           "the page's losses": dict(zip(keys, (0.0, 0.3, 1.0, 0.0)))}
    s = actor.reach_reading(bad)
    assert "no gradient on the critic's weights" in s and "not Dreamer's" in s
    assert "sends 0.5 into the states" in s and "should rule out" in s


def _hist(first, last, n=40, noise=0.01, seed=0):
    rng = np.random.default_rng(seed)
    return {"imag_reward": np.r_[first + noise * rng.standard_normal(n // 2),
                                 last + noise * rng.standard_normal(n - n // 2)]}


def _metrics(hist, gap=0.2):
    r = hist["imag_reward"]
    return {"imagined_reward_first20_train": float(r[:20].mean()),
            "imagined_reward_last20_train": float(r[-20:].mean()),
            "imagined_reward_rise_se": float(np.sqrt(r[:20].var(ddof=1) / 20 + r[-20:].var(ddof=1) / 20)),
            "imag_horizon": 15, "imagination_gap": gap, "imagination_gap_se_eval_horizon": 0.01,
            "real_success_rate": 0.0}


def _floor(change, spread=0.003, n=10):
    first = -0.4 + 0.05 * np.sin(np.arange(n))
    return {"first": first, "last": first + change + spread * np.cos(3 * np.arange(n))}


def test_rise_test_matches_the_runs_standard_error():
    h = _hist(-0.32, -0.28)
    t = actor.rise_test(h)
    up, se = actor.rise(_metrics(h))
    assert abs(t.diff - up) < 1e-12 and abs(t.se - se) < 1e-12 and t.min_effect == actor.MIN_REWARD_EFFECT
    assert actor.rose_beyond_noise(h) and not actor.rose_beyond_noise(_hist(-0.32, -0.31))


def test_verdicts_take_every_branch():
    for last, want in ((-0.28, "up"), (-0.36, "down"), (-0.31, "small"), (-0.3195, "same")):
        assert actor.verdict(actor.rise_test(_hist(-0.32, last, noise=0.002)), actor.IMAGINED) == want, last
    for change, want in ((0.05, "up"), (-0.05, "down"), (0.01, "small"), (0.0005, "same")):
        assert actor.verdict(actor.floor_test(_floor(change)), actor.REAL_FLOOR) == want, change


def test_training_sentence_reads_both_worlds_with_noise_and_minimum_effect():
    h_up, h_flat = _hist(-0.32, -0.28), _hist(-0.32, -0.3195, noise=0.01)
    s = actor.training_sentence(h_up, _floor(0.0005))
    assert "**rise**" in s and "cannot tell it from no change" in s and "before this test can tell it from none" in s
    assert "do not confirm" in s and "cannot be told from none" in s and "0.020" in s and "±" in s
    assert "Welch's t-test" in s and "one-sample t-test" in s
    s = actor.training_sentence(h_up, _floor(0.05))
    assert "both rose" in s
    s = actor.training_sentence(h_up, _floor(0.01, spread=0.0))
    assert "are equal, +0.01 each" in s and "before this test can tell" not in s
    s = actor.training_sentence(h_up, _floor(0.0, spread=0.0))
    assert "**0 of the 10 starts changed at all**" in s and "has nothing to weigh" in s and "are equal" not in s
    f = _floor(0.05)
    mon = {**h_up, "monitor_real_reward": [float(f["first"].mean()), -0.39, float(f["last"].mean())]}
    assert "do not reproduce" not in actor.training_sentence(mon, f)
    mon["monitor_real_reward"][-1] += 0.01
    assert "do not reproduce the monitor's own means" in actor.training_sentence(mon, f)
    s = actor.training_sentence(h_up, _floor(-0.05))
    assert "got **worse**" in s
    s = actor.training_sentence(h_up, _floor(0.01))
    assert "too small to matter" in s
    s = actor.training_sentence(h_flat, _floor(0.05))
    assert "does not show the policy improving" in s and "yet reality improved" in s
    for change, words in ((-0.05, "and reality got worse"), (0.01, "too small to matter"),
                          (0.0005, "neither did reality")):
        assert words in actor.training_sentence(h_flat, _floor(change))


def test_the_real_floor_counts_the_starts_that_changed():
    f = _floor(0.0005)
    f["last"] = f["first"].copy()
    f["last"][3] += 0.0015                           # one start changed, the others exactly not
    s = actor.training_sentence(_hist(-0.32, -0.28), f)
    assert "**1 of the 10 starts changed at all**" in s and "almost nothing to weigh" in s
    assert "neither policy's real pushes ever moved it" not in s      # no displacement given: not claimed
    f["moved_first"], f["moved_last"] = np.zeros(10), np.zeros(10)
    f["moved_last"][3] = 0.02
    s = actor.training_sentence(_hist(-0.32, -0.28), f)
    assert "neither policy's real pushes ever moved it" in s
    f["moved_first"][0] = 0.01                        # an unchanged start whose block moved: not claimed
    assert "neither policy's real pushes ever moved it" not in actor.training_sentence(_hist(-0.32, -0.28), f)
    s = actor.training_sentence(_hist(-0.32, -0.28), _floor(0.05))
    assert "**10 of the 10 starts changed at all**" in s and "almost nothing" not in s


def test_the_objective_sentence_explains_a_falling_lambda_return():
    h = _hist(-0.32, -0.28)
    h["imag_return"] = np.r_[np.full(20, -1.5), np.full(20, -6.0)] + 0.05 * np.sin(np.arange(40))
    s = actor.objective_sentence(h, 15)
    assert "**fell**" in s and "rose" in s and "critic's values" in s and "not the actor getting worse" in s
    assert "left panel" not in s                          # no critic loss given: not claimed
    h["critic_loss"] = np.linspace(2.0, 0.5, 40)
    assert "its loss fell from" in actor.objective_sentence(h, 15)
    h["critic_loss"] = np.linspace(0.5, 2.0, 40)
    assert "left panel" not in actor.objective_sentence(h, 15)
    h2 = _hist(-0.32, -0.36, noise=0.002)
    h2["imag_return"] = h["imag_return"]
    assert "and so did the imagined reward" in actor.objective_sentence(h2, 15)
    h["imag_return"] = h["imag_return"][::-1].copy()
    assert "It rose" in actor.objective_sentence(h, 15)
    h["imag_return"] = -2.0 + 0.05 * np.sin(np.arange(40))
    assert "within the noise" in actor.objective_sentence(h, 15)


def test_carry_forward_both_branches():
    h_up, h_flat = _hist(-0.32, -0.28), _hist(-0.32, -0.3195)
    assert "by its own measure, the dream's, it improved" in actor.carry_forward(h_up, _floor(0.0005))
    assert "does not show it improving" in actor.carry_forward(h_flat, _floor(0.0005))
    for change, words in ((0.05, "rose too"), (-0.05, "fell"), (0.01, "less than matters"),
                          (0.0005, "cannot be told from none")):
        assert words in actor.carry_forward(h_up, _floor(change))


def test_wiring_sentence_every_branch():
    same = actor.wiring_sentence(_metrics(_hist(-0.32, -0.30)), _metrics(_hist(-0.32, -0.30, seed=1)),
                                 _hist(-0.32, -0.30), _hist(-0.32, -0.30, seed=1))
    assert "cannot tell the two wirings apart" in same
    hd, hp = _hist(-0.32, -0.31, noise=0.005), _hist(-0.32, -0.25, noise=0.005)
    apart = actor.wiring_sentence(_metrics(hd), _metrics(hp, gap=0.3), hd, hp)
    assert "the page's wiring raised the imagined reward more" in apart
    # notebook 04's Exercise 1 asks for the deployed gap and real success: 03 must not state them
    assert "+0.300" not in apart and "real success" not in apart and "gap" not in apart
    apart = actor.wiring_sentence(_metrics(hp), _metrics(hd), hp, hd)
    assert "Dreamer's wiring raised the imagined reward more" in apart
    hs = _hist(-0.32, -0.30, noise=0.001)
    small = actor.wiring_sentence(_metrics(hs), _metrics(hd), hs, hd)
    assert "smaller than the minimum effect" in small
    # the real floor of each wiring, and their difference start by start
    fd, fp = _floor(0.05), _floor(0.0005, spread=0.002)
    s = actor.wiring_sentence(_metrics(hd), _metrics(hp), hd, hp, fd, fp)
    assert "On the monitor's real starts" in s and "Dreamer's wiring raised the real floor more" in s
    assert "10 of 10 starts changed at all" in s and "real success" not in s and "gap" not in s
    s = actor.wiring_sentence(_metrics(hd), _metrics(hp), hd, hp, fp, fd)
    assert "the page's wiring raised the real floor more" in s
    s = actor.wiring_sentence(_metrics(hd), _metrics(hp), hd, hp, _floor(0.0005), _floor(0.0005, spread=0.002))
    assert "cannot be told apart in reality" in s
    same_floor = _floor(0.01, spread=0.0)
    s = actor.wiring_sentence(_metrics(hd), _metrics(hp), hd, hp, same_floor, same_floor)
    assert "no spread to test their difference" in s


def test_match_and_lambda_sentences_both_branches():
    assert "**identical**" in actor.match_sentence(0.0, 400, " took 3.0 s")
    assert "differs from the package's run by up to 0.001" in actor.match_sentence(1e-3, 400, "")
    r = -0.3 * np.ones((15, 4))
    v = np.zeros((16, 4))
    G = {0.0: np.full(15, -0.3), 1.0: np.full(15, -3.0)}
    s = actor.lambda_sentence(G, r, v, 0.99)
    assert "more optimistic than that bound" in s and "come out higher" in s
    s = actor.lambda_sentence({0.0: np.full(15, -5.0), 1.0: np.full(15, -3.0)}, r, v - 10, 0.99)
    assert "not optimistic here" in s and "do not come out higher" in s


def test_every_claim_of_notebook_03_is_evaluated_by_a_sentence():
    from pusht.nb import claims

    start = len(claims.LEDGER)
    agent, make = batch_maker()
    actor.detach_sentence(actor.detach_effects(agent, make, actor_critic_losses, 0.99, 0.95, 3e-4))
    reach = {n: actor.gradient_reach(agent, *make(), fn, 0.99, 0.95, 3e-4)
             for n, fn in (("your losses", actor_critic_losses), ("the page's losses", page_losses))}
    actor.reach_reading(reach)
    actor.critic_reach_sentence(0.1, 0.0)
    for last in (-0.28, -0.36, -0.31):
        h = _hist(-0.32, last, noise=0.002)
        actor.training_sentence({**h, "monitor_real_reward": [-0.4, -0.39]}, _floor(0.01))
        actor.wiring_sentence(_metrics(h), _metrics(_hist(-0.32, -0.32, noise=0.002)), h,
                              _hist(-0.32, -0.32, noise=0.002), _floor(0.05), _floor(0.0005, spread=0.002))
        g = {**h, "imag_return": np.linspace(-1.5, -6.0, 40), "critic_loss": np.linspace(2.0, 0.5, 40)}
        actor.objective_sentence(g, 15)
    f = _floor(0.0)
    f["last"] = f["first"].copy()
    f["moved_first"], f["moved_last"] = np.zeros(10), np.zeros(10)
    actor.training_sentence(_hist(-0.32, -0.28), f)
    actor.match_sentence(0.0, 1, "")
    actor.lambda_sentence({0.0: np.zeros(3), 1.0: np.zeros(3)}, -np.ones((3, 2)), np.zeros((4, 2)), 0.9)
    seen = {r["claim"] for r in claims.LEDGER[start:]}
    assert {n for n in claims.REGISTRY if n.startswith("03.")} <= seen
    assert all(r["inputs"] and isinstance(r["holds"], bool) for r in claims.LEDGER[start:])


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


def test_an_older_releases_calls_still_read_a_run(tmp_path):
    """Notebook 03 of an older release (tests/data/release_1ba340f) calls training_sentence(metrics)
    and wiring_sentence(metrics, metrics): a learner who installs today's package next to it keeps a
    notebook that runs, and what it reads is tested as far as the metrics allow."""
    m = {"imagined_reward_first20_train": -0.32, "imagined_reward_last20_train": -0.29,
         "imagined_reward_rise_se": 0.004, "real_reward_monitor_first": -0.33, "real_reward_monitor_last": -0.30,
         "imagination_gap": 0.2, "imagination_gap_se_eval_horizon": 0.01, "imag_horizon": 15,
         "real_success_rate": 0.0}
    s = actor.training_sentence(m)
    assert "+0.030" in s and "rise" in s and "not read as a rise or a fall" in s
    flat = dict(m, imagined_reward_last20_train=-0.319)
    assert "rise**" not in actor.training_sentence(flat)
    w = actor.wiring_sentence(m, flat)
    assert "Dreamer's wiring raised the imagined reward more" in w
