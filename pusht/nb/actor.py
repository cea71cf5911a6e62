"""Notebook 03's figures, conclusions and self-checks: learning to act inside the dream."""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from ..imagination import actor_params, lambda_return, set_gradients
from ..selfcheck import Question
from . import figure
from .claims import claim
from .stats import MIN_REWARD_EFFECT, Test, beyond, outcome, sign_test, t_quantile, welch

# --- what each loss reaches --------------------------------------------------------------------


def gradient_reach(agent, states, rewards, entropy, loss_fn, gamma: float, lam: float,
                   ent_coef: float) -> dict:
    """How large a gradient each loss of ``loss_fn`` sends into each part, on one batch of dreams.

    ``states`` (H+1, B, S), ``rewards`` (H, B) and ``entropy`` come from one dream. The states are
    the road back to the actor's actions; to see whether the critic's values use that road, the
    "states, via the values" row calls ``loss_fn`` once more with the rewards detached, so the
    only way from the loss to the states is through ``agent.value``. Returns
    {(loss, part): gradient norm}.
    """
    states = states.detach().requires_grad_(True)
    actor_loss, critic_loss = loss_fn(agent, states, rewards.detach(), entropy, gamma, lam, ent_coef)
    parts = {"actor's weights": [*agent.actor.parameters(), agent.log_std],
             "critic's weights": list(agent.critic.parameters()), "states, via the values": [states]}

    def norm(loss, params):
        grads = torch.autograd.grad(loss, params, retain_graph=True, allow_unused=True)
        return float(sum((g ** 2).sum() for g in grads if g is not None) ** 0.5)

    out = {}
    for name, loss in (("actor loss", actor_loss), ("critic loss", critic_loss)):
        for part in ("critic's weights", "states, via the values"):
            out[name, part] = norm(loss, parts[part])
    return out


def actor_grad_change(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float,
                      scale: float = 0.5, seed: int = 0) -> float:
    """How much the critic changes the actor's gradient: perturb the critic's weights, recompute
    the actor loss's gradient on the same dreams, and return the largest absolute change (0.0:
    bit-identical).

    ``make_batch()`` must return (states, rewards, entropy) from a fresh dream of ``agent`` with
    the same action noise each call. The critic's weights are restored afterwards. There is no
    noise in this measurement: under the page's wiring the two gradients are bit-identical.
    """
    def actor_grad():
        states, rewards, entropy = make_batch()
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef)
        grads = torch.autograd.grad(actor_loss, [*agent.actor.parameters(), agent.log_std],
                                    allow_unused=True)
        return [torch.zeros(1) if g is None else g for g in grads]

    before = actor_grad()
    saved = [p.detach().clone() for p in agent.critic.parameters()]
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for p in agent.critic.parameters():
            p.add_(scale * torch.randn(p.shape, generator=g))
    try:
        after = actor_grad()
    finally:
        with torch.no_grad():
            for p, s in zip(agent.critic.parameters(), saved):
                p.copy_(s)
    return _max_diff(before, after)


def critic_reaches_actor(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float,
                         scale: float = 0.5, seed: int = 0) -> bool:
    """Does the critic change the actor's gradient? (:func:`actor_grad_change` is not 0.)"""
    return actor_grad_change(agent, make_batch, loss_fn, gamma, lam, ent_coef, scale, seed) > 0


def _max_diff(a: list, b: list) -> float:
    """Largest absolute difference between two lists of same-shaped tensors (0.0: bit-identical;
    NaN where either holds a NaN)."""
    diffs = [float((x - y).abs().max()) for x, y in zip(a, b) if x.numel()]
    return float("nan") if any(d != d for d in diffs) else max(diffs, default=0.0)


@claim("03.critic_reaches_your_actor", "changing the critic's weights changes the actor gradient of "
       "the learner's losses (the critic's slope reaches the actor, Dreamer's wiring)")
def critic_reaches_your_actor(*, change):
    return change > 0


@claim("03.critic_spares_page_actor", "changing the critic's weights leaves the actor gradient of "
       "the page's losses bit-identical")
def critic_spares_page_actor(*, change):
    return change == 0


def critic_reach_sentence(yours: float, page: float) -> str:
    """The critic-perturbation test in words (``yours``, ``page``: :func:`actor_grad_change`)."""
    s = "Change the critic's weights and recompute the actor's gradient on the same dreams: "
    s += ("with your losses it **changes** (by up to {:.3g}): the critic's slope reaches your actor, as "
          "in Dreamer. ".format(yours) if critic_reaches_your_actor(change=yours) else
          "with your losses it **stays bit-identical**: your actor never hears from the critic, which is "
          "the page's wiring, not Dreamer's (Exercise B asks for the values with their gradient). ")
    s += ("With the page's losses it **stays bit-identical**: the page's actor learns from the dreamed "
          "rewards alone." if critic_spares_page_actor(change=page) else
          f"With the page's losses it **changes** (by up to {page:.3g}), which the page's detached values "
          "should rule out: something in this set-up is not the package's `page_losses`.")
    return s


# --- where the critic loss's stop-gradients matter ------------------------------------------------

def states_undetached(loss_fn):
    """``loss_fn`` with its critic loss replaced by one that reads the imagined states WITHOUT
    detaching them (the target stays detached): the actor loss is ``loss_fn``'s own."""
    def losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=lambda_return):
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn)
        values = agent.value(states)
        target = return_fn(rewards, values, gamma, lam).detach()
        return actor_loss, 0.5 * F.mse_loss(values[:-1], target)
    return losses


def target_undetached(loss_fn):
    """``loss_fn`` with its critic loss replaced by one whose states are detached but whose TARGET
    keeps its gradient (through the rewards, the states and the critic's own values)."""
    def losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=lambda_return):
        actor_loss, _ = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn)
        target = return_fn(rewards, agent.value(states), gamma, lam)
        return actor_loss, 0.5 * F.mse_loss(agent.value(states.detach())[:-1], target)
    return losses


ROUTES = ("set_gradients", "one summed backward()")
GROUPS = ("actor's weights", "critic's weights")


def _gradients(agent, make_batch, loss_fn, gamma, lam, ent_coef, route) -> dict:
    """Each parameter group's gradient after one update's backward pass along ``route``."""
    groups = {"actor's weights": actor_params(agent), "critic's weights": list(agent.critic.parameters())}
    every = [p for ps in groups.values() for p in ps]
    for p in every:
        p.grad = None
    states, rewards, entropy = make_batch()
    actor_loss, critic_loss = loss_fn(agent, states, rewards, entropy, gamma, lam, ent_coef)
    if route == "set_gradients":               # the loop's: each loss on its own group only
        set_gradients(agent, actor_loss, critic_loss)
    elif route == "one summed backward()":     # one optimiser for both: every loss on every group
        (actor_loss + critic_loss).backward()
    else:
        raise ValueError(f"route must be one of {ROUTES}, got {route!r}")
    out = {name: [torch.zeros_like(p) if p.grad is None else p.grad.detach().clone() for p in ps]
           for name, ps in groups.items()}
    for p in every:
        p.grad = None
    return out


def detach_effects(agent, make_batch, loss_fn, gamma: float, lam: float, ent_coef: float) -> dict:
    """What each stop-gradient of the critic loss changes, measured on one update.

    For each variant of ``loss_fn`` (:func:`states_undetached`, :func:`target_undetached`) and
    each route of the gradients into the parameters (``set_gradients``, this loop's; one summed
    ``backward()``, a loop with one optimiser for both networks), the largest absolute difference
    of each parameter group's gradient from ``loss_fn``'s own on the same dreams: 0.0 means bit-identical.
    ``make_batch()``: as for :func:`actor_grad_change`. The agent's ``.grad`` are left None.
    Returns {(variant, route, group): difference}, plus {("norm", route, group): the gradient
    norm of ``loss_fn`` itself} for scale.
    """
    variants = {"critic loss reads the states undetached": states_undetached(loss_fn),
                "critic loss's target keeps its gradient": target_undetached(loss_fn)}
    out = {}
    for route in ROUTES:
        base = _gradients(agent, make_batch, loss_fn, gamma, lam, ent_coef, route)
        for group in GROUPS:
            out["norm", route, group] = float(sum((g ** 2).sum() for g in base[group]) ** 0.5)
        for name, fn in variants.items():
            other = _gradients(agent, make_batch, fn, gamma, lam, ent_coef, route)
            for group in GROUPS:
                out[name, route, group] = _max_diff(base[group], other[group])
    return out


def detach_table(effects: dict) -> str:
    """Markdown table of :func:`detach_effects`: one row per variant and route."""
    rows = ["| change to your critic loss | gradients put on the parameters by | "
            + " | ".join(GROUPS) + " |", "|---|---|---|---|"]
    for (variant, route, group) in effects:
        if variant == "norm" or group != GROUPS[0]:
            continue
        cells = []
        for g in GROUPS:
            d = effects[variant, route, g]
            cells.append("bit-identical" if d == 0 else
                         f"**differs** (by up to {d:.3g}; gradient norm {effects['norm', route, g]:.3g})")
        rows.append(f"| {variant} | `{route}` | " + " | ".join(cells) + " |")
    return "\n".join(rows)


@claim("03.states_detach_idle_under_set_gradients", "with set_gradients, a critic loss that reads "
       "the states undetached gives bit-identical gradients to the actor's and the critic's weights")
def states_detach_idle_under_set_gradients(*, actor_diff, critic_diff):
    return actor_diff == 0 and critic_diff == 0


@claim("03.states_detach_needed_in_summed_backward", "with one summed backward(), a critic loss that "
       "reads the states undetached changes the actor's gradient")
def states_detach_needed_in_summed_backward(*, actor_diff):
    return actor_diff > 0


@claim("03.target_detach_needed", "with set_gradients, a critic target that keeps its gradient "
       "changes the critic's gradient")
def target_detach_needed(*, critic_diff):
    return critic_diff > 0


def detach_sentence(effects: dict) -> str:
    """What :func:`detach_effects` measured, in words: where the stop-gradient is needed and where
    the separate optimisers already provide it."""
    sv, tv = "critic loss reads the states undetached", "critic loss's target keeps its gradient"
    sg, sb = ROUTES
    a, c = GROUPS
    if states_detach_idle_under_set_gradients(actor_diff=effects[sv, sg, a], critic_diff=effects[sv, sg, c]):
        s = ("**In this training loop the states' detach changes nothing.** With `set_gradients` the "
             "gradients of both groups are bit-identical whether or not your critic loss reads the states "
             "detached: `set_gradients` differentiates the critic loss with respect to the critic's "
             "weights only, so whatever it would send into the states is never put on any parameter. "
             "The two optimisers already keep value regression off the actor, as DreamerV1's separate "
             "tape for its value model does (`danijar/dreamer`, `Dreamer._train`, which does not detach "
             "the imagined features in the value loss). ")
    else:
        s = (f"With `set_gradients`, reading the states undetached changed the gradients (actor's weights "
             f"by up to {effects[sv, sg, a]:.3g}, critic's by up to {effects[sv, sg, c]:.3g}): this loop's "
             "optimiser split did not make the states' detach redundant here. ")
    if states_detach_needed_in_summed_backward(actor_diff=effects[sv, sb, a]):
        s += ("**With one summed `backward()` it is what stands between the critic and the policy:** "
              f"there the undetached states change the actor's gradient (by up to {effects[sv, sb, a]:.3g}), "
              "because the critic loss's gradient flows back through the dream into the actions and "
              "lands on the actor's weights. ")
    else:
        s += ("With one summed `backward()` the undetached states did not change the actor's gradient on "
              "this batch either. ")
    if target_detach_needed(critic_diff=effects[tv, sg, c]):
        s += ("The target's detach is different: it matters in **both** set-ups. A target that keeps its "
              f"gradient changes the critic's own gradient (by up to {effects[tv, sg, c]:.3g} here, even "
              "with `set_gradients`), because the critic would then also move its values *inside the "
              "target*: it would chase a target that moves with it.")
    else:
        s += ("A target that keeps its gradient left the critic's gradient bit-identical on this batch "
              "with `set_gradients`.")
    return s


def reach_table(reach: dict[str, dict]) -> str:
    """Markdown table of :func:`gradient_reach` results, one column per wiring."""
    names = list(reach)
    first = reach[names[0]]
    rows = ["| loss | its gradient reaches | " + " | ".join(names) + " |",
            "|---|---|" + "---|" * len(names)]
    for (loss, part) in first:
        rows.append(f"| {loss} | {part} | " + " | ".join(f"{reach[n][loss, part]:.3g}" for n in names) + " |")
    return "\n".join(rows)


# --- conclusions -------------------------------------------------------------------------------
# Every sentence below that reads the learner's run goes through a registered claim (claims.py):
# a comparison "rose" only beyond k standard errors (Student's t at the test's degrees of freedom)
# AND by at least MIN_REWARD_EFFECT per step; "fell" likewise; "detected" is beyond k standard
# errors whatever the size. Each sentence has its true alternative.


def _change_claims(name: str, what: str, control: str | None = None):
    """Three registered claims on one measured change ``what`` (keyword inputs diff, se, k,
    min_effect): it rose, it fell (beyond k SE and by at least the minimum effect), it was detected
    (beyond k SE, whatever its size)."""
    @claim(f"03.{name}_rose", f"{what} rose beyond k standard errors and by at least the minimum effect",
           control=control)
    def rose(*, diff, se, k, min_effect):
        return beyond(diff, se, k, min_effect, +1)

    @claim(f"03.{name}_fell", f"{what} fell beyond k standard errors and by at least the minimum effect",
           control=control)
    def fell(*, diff, se, k, min_effect):
        return beyond(diff, se, k, min_effect, -1)

    @claim(f"03.{name}_detected", f"{what} changed beyond k standard errors (whatever its size)")
    def detected(*, diff, se, k, min_effect):
        return beyond(diff, se, k)

    return rose, fell, detected


IMAGINED = _change_claims("imagined", "the imagined reward per step (last 20 updates minus first 20)")
REAL_FLOOR = _change_claims("real_floor", "the real floor (final policy minus untrained, on the monitor's starts)",
                            "the untrained actor")
WIRING_RISE = _change_claims("wiring_rise", "the imagined rise with Dreamer's wiring minus the rise with the page's",
                             "the page's wiring")
WIRING_FLOOR = _change_claims("wiring_floor", "the real floor's change with Dreamer's wiring minus the change with "
                              "the page's (per start, on the monitor's starts)", "the page's wiring")
OBJECTIVE = _change_claims("objective", "the mean lambda-return the actor maximises (last 20 updates minus first 20)")


def verdict(test: Test, claims) -> str:
    """"up", "down", "small" (beyond the noise but under the minimum effect) or "same", decided by
    the three registered ``claims`` of :func:`_change_claims` on ``test`` (each evaluated)."""
    inputs = dict(diff=test.diff, se=test.se, k=test.k, min_effect=test.min_effect)
    up, down, seen = (c(**inputs) for c in claims)    # all three, so every run records each one
    return "up" if up else "down" if down else "small" if seen else "same"


def rise_test(hist: dict, n: int = 20) -> Test:
    """Last-``n`` minus first-``n`` imagined reward per step of a training history, as a Welch's
    t-test with the minimum effect :data:`~pusht.nb.stats.MIN_REWARD_EFFECT`.

    Each update scores a fresh random batch of dreams, so the two windows' spreads measure the
    noise (with 40 updates or more, the standard error is the run's ``imagined_reward_rise_se``).
    A shorter history is split into two halves, so that the windows never overlap.
    """
    r = np.asarray(hist["imag_reward"], dtype=float)
    n = min(n, len(r) // 2)
    return welch(r[:n], r[-n:], min_effect=MIN_REWARD_EFFECT)


def _window(hist: dict, n: int = 20) -> int:
    return min(n, len(hist["imag_reward"]) // 2)


def _num(x: float) -> str:
    """A standard error or a threshold: 3 decimals, or 2 significant figures when smaller."""
    return f"{x:.3f}" if x == 0 or abs(x) >= 0.001 else f"{x:.1e}"


def rise(metrics: dict) -> tuple[float, float]:
    """(last-20 minus first-20 imagined reward per step, its standard error), from a run's metrics."""
    return (metrics["imagined_reward_last20_train"] - metrics["imagined_reward_first20_train"],
            metrics["imagined_reward_rise_se"])


def rose_beyond_noise(hist: dict) -> bool:
    """Did the imagined reward rise over training beyond its noise and by at least the minimum
    effect? (claim ``03.imagined_rose`` on :func:`rise_test`)."""
    return verdict(rise_test(hist), IMAGINED) == "up"


def real_floor(wm, run, cfg, mean, std) -> dict:
    """The real floor's two ends, start by start: the untrained policy (``run.init_agent``, what the
    monitor ran before the first update) and the trained one (``run.agent``, its last point), each
    run again on the monitor's own starts (``MONITOR_SEED_BASE``) for ``cfg.eval_horizon`` steps.

    The training history keeps only the mean over the starts; the per-start values give the
    change its standard error. Returns {"first": (N,), "last": (N,)} reward per step, and
    {"moved_first", "moved_last": (N,)}: how far each start's block ever got from where it spawned (m).
    """
    from ..data import MONITOR_SEED_BASE, start_seeds
    from ..evaluate import policy_of, real_rollout

    seeds = start_seeds(MONITOR_SEED_BASE, cfg.seed, cfg.monitor_episodes)
    out = {}
    for end, agent in (("first", run.init_agent), ("last", run.agent)):
        roll = real_rollout(wm, policy_of(agent), seeds, cfg.eval_horizon, mean, std)
        out[end] = roll.return_per_step
        block = np.asarray(roll.obs)[:, :, 2:4]
        out[f"moved_{end}"] = np.nanmax(np.linalg.norm(block - block[:1], axis=-1), axis=0)
    return out


def floor_test(floor: dict) -> Test:
    """The real floor's change: a one-sample t-test on the per-start changes (the same starts
    before and after, so each start is its own control), minimum effect MIN_REWARD_EFFECT."""
    return sign_test(np.asarray(floor["last"]) - np.asarray(floor["first"]), min_effect=MIN_REWARD_EFFECT)


_WORDS = {
    "up": "That is a **rise**: beyond the noise, and at least the minimum effect that matters.",
    "down": "That is a **fall**: beyond the noise, and at least the minimum effect that matters.",
    "small": ("The noise does not explain it, but it is smaller than the minimum effect that matters, "
              "so it is not read as a change."),
    "same": "That is within the noise: this run cannot tell it from no change.",
}


def _bar() -> str:
    return (f"the minimum effect that matters is {MIN_REWARD_EFFECT:.3f} reward per step, the reward of "
            "holding the block 2 cm (the success tolerance) nearer the target on every step")


def training_sentence(hist: dict, floor: dict | None = None) -> str:
    """What training did to the imagined and to the real reward, with the noise, the test and the
    minimum effect of each, and what the two together say. ``hist``: the run's training history;
    ``floor``: :func:`real_floor` of the same run.

    Notebooks of an older release call ``training_sentence(metrics)`` with a run's metrics alone:
    they get :func:`_older_training_sentence`, which tests what the metrics allow."""
    if floor is None:
        return _older_training_sentence(hist)
    imag, real = rise_test(hist), floor_test(floor)
    vi, vr = verdict(imag, IMAGINED), verdict(real, REAL_FLOOR)
    n = len(floor["first"])
    w = _window(hist)
    r = np.asarray(hist["imag_reward"], dtype=float)
    first, last = float(r[:w].mean()), float(r[-w:].mean())
    r0, r1 = float(np.mean(floor["first"])), float(np.mean(floor["last"]))
    s = (f"**In the dream.** Over training, the imagined reward per step went from **{first:+.3f}** (mean of "
         f"the first {w} updates) to **{last:+.3f}** (the last {w}): a change of **{imag.diff:+.3f} ± "
         f"{_num(imag.se)}** (standard error from the updates' own spread). {_WORDS[vi]} ({imag.why()}.)\n\n")
    s += (f"**In the real sim.** On the monitor's {n} real starts the same policy went from **{r0:+.3f}** "
          f"(untrained) to **{r1:+.3f}** (trained) per step: a change of **{real.diff:+.3f} ± {_num(real.se)}** "
          f"(standard error of the {n} per-start changes; the same starts before and after). {_WORDS[vr]} "
          f"({real.why()}.)")
    spread = floor_changes_spread(se=real.se)
    c = changed_starts(floor)
    mostly_same = floor_most_starts_unchanged(n_changed=c, n=n)
    if vr in ("same", "small") and spread and not mostly_same:
        s += (f" With {n} starts, a change has to exceed about {_num(real.k * real.se)} per step "
              f"({real.k:.2f} standard errors) before this test can tell it from none.")
    elif not spread and c:
        s += (f" (All {n} per-start changes are equal, {real.diff:+.2g} each, so their spread gives no "
              "standard error, and the t-test cannot weigh it.)")
    s += _unchanged_text(floor)
    mon = hist.get("monitor_real_reward")
    if mon is not None and len(mon) and not floor_reproduces_monitor(
            rerun=[r0, r1], monitor=[float(mon[0]), float(mon[-1])]):
        s += (f" (Re-run start by start, the two ends do not reproduce the monitor's own means, "
              f"{float(mon[0]):+.3f} and {float(mon[-1]):+.3f}: the standard error above belongs to the re-run.)")
    s += f"\n\n(In both, {_bar()}.) "
    s += _reading(vi, vr)
    return s


def metrics_rise_test(m: dict) -> Test:
    """:func:`rise_test` from a run's metrics alone (the two 20-update means and the standard error
    of their difference; 38 degrees of freedom, as two windows of 20 with equal spreads give)."""
    diff, se = rise(m)
    df = 38.0
    k = t_quantile(df)
    return Test(diff, se, df, k, outcome(diff, k * se, MIN_REWARD_EFFECT), MIN_REWARD_EFFECT, "Welch's t-test")


def _older_training_sentence(m: dict) -> str:
    """``training_sentence`` for a notebook of an older release, which passes a run's metrics only:
    the imagined rise is tested (the metrics keep its standard error); the real floor's two means
    are quoted, untested, because the metrics keep no per-start values."""
    imag = metrics_rise_test(m)
    diff, se = imag.diff, imag.se
    vi = verdict(imag, IMAGINED)
    r0, r1 = m["real_reward_monitor_first"], m["real_reward_monitor_last"]
    return (f"Over training, the imagined reward per step changed by **{diff:+.3f} ± {_num(se)}** (last 20 "
            f"updates minus the first 20). {_WORDS[vi]} ({imag.why()}; {_bar()}.) On the monitor's real starts "
            f"the policy went from {r0:+.3f} to {r1:+.3f} per step: this notebook, from an older release, does not "
            "keep the per-start values that would give that change a standard error, so it is not read as a "
            "rise or a fall here; the current release of notebook 03 tests it, and notebook 04 compares the "
            "same policy in both worlds on identical starts.")


@claim("03.floor_changes_spread", "the real floor's per-start changes differ between starts (a "
       "standard error above 0)")
def floor_changes_spread(*, se):
    return se > 0


@claim("03.floor_most_starts_unchanged", "on most of the monitor's starts the real reward per step is "
       "exactly the same before and after training")
def floor_most_starts_unchanged(*, n_changed, n):
    return n_changed < n / 2


@claim("03.critic_loss_fell", "the critic's loss is lower over the last 20 updates than over the first 20")
def critic_loss_fell(*, first, last):
    return last < first


@claim("03.unchanged_starts_untouched", "on every monitor start whose real reward did not change, neither "
       "the untrained nor the trained policy moved the block (by more than 1 micrometre)")
def unchanged_starts_untouched(*, moved):
    return all(x <= 1e-6 for x in moved)


def changed_starts(floor: dict) -> int:
    """How many of the monitor's starts changed their real reward per step at all with training."""
    d = np.asarray(floor["last"], dtype=float) - np.asarray(floor["first"], dtype=float)
    return int(np.sum(d != 0))


def _unchanged_text(floor: dict) -> str:
    """How many of the monitor's starts changed at all, and what that leaves the test to weigh."""
    n = len(floor["first"])
    c = changed_starts(floor)
    s = f" **{c} of the {n} starts changed at all**"
    if not floor_most_starts_unchanged(n_changed=c, n=n):
        return s + "; the rest gave exactly the same reward per step before and after training."
    d = np.asarray(floor["last"], dtype=float) - np.asarray(floor["first"], dtype=float)
    same = d == 0
    s += (f": on {'every start' if c == 0 else f'the other {n - c}'} the reward per step is identical, to the last "
          "digit, before and after training, so the block followed exactly the same path under both policies")
    if "moved_first" in floor and "moved_last" in floor:
        moved = [float(x) for x in np.r_[np.asarray(floor["moved_first"])[same], np.asarray(floor["moved_last"])[same]]]
        if unchanged_starts_untouched(moved=moved):
            s += ": neither policy's real pushes ever moved it"
    if c == 0:
        return s + ". The test above has nothing to weigh: training changed nothing the real reward can see here."
    s += (f". The test above has almost nothing to weigh: its mean and its standard error come from the "
          f"{c} start{'s' * (c != 1)} that changed, so read it as a count of starts, not as a measurement of the "
          "policy's skill.")
    return s


@claim("03.floor_reproduces_monitor", "re-running the untrained and the trained policy on the monitor's "
       "starts reproduces the monitor's first and last means (to 1e-6 per step)")
def floor_reproduces_monitor(*, rerun, monitor):
    return all(abs(a - b) <= 1e-6 for a, b in zip(rerun, monitor))


def _reading(vi: str, vr: str) -> str:
    """What the two verdicts say together (each verdict from registered claims)."""
    if vi == "up" and vr == "up":
        return ("**Reading:** both rose, so on these starts the policy also earns more in reality. Whether "
                "by as much as the dream says is another question: the two are measured on different starts "
                "and horizons. Notebook 04 puts the same policy in both worlds on identical starts.")
    if vi == "up":
        real = {"down": "reality got **worse** on the same starts",
                "small": "reality's change is too small to matter",
                "same": "reality's change cannot be told from none"}[vr]
        return ("**Reading:** the dream reports an improvement that the real starts do not confirm: "
                f"{real}. A rise in the dream is the policy scored by the model it was trained on; do not "
                "read it as a better robot. Notebook 04 measures how much of it is real.")
    real = {"up": "yet reality improved on these starts", "down": "and reality got worse",
            "small": "and reality's change is too small to matter", "same": "and neither did reality"}[vr]
    return (f"**Reading:** on this run the dream itself does not show the policy improving beyond its noise "
            f"and the minimum effect, {real}. Notebook 04 compares the trained policy with the untrained "
            "one and with doing nothing, in both worlds, on identical starts.")


def wiring_sentence(dreamer: dict, page: dict, dreamer_hist: dict | None = None,
                    page_hist: dict | None = None, dreamer_floor: dict | None = None,
                    page_floor: dict | None = None) -> str:
    """Compare the two wirings' runs on what this notebook measures: the imagined rise of each
    (training history, or the metrics alone), and, given each run's :func:`real_floor`, the real
    floor's change of each and their difference, start by start. Nothing here reads the deployed
    evaluation (notebook 04's subject).

    Notebooks of an older release pass the two metrics only: the rises then come from the metrics
    (:func:`metrics_rise_test`), and the real floor is not compared."""
    d = rise_test(dreamer_hist) if dreamer_hist is not None else metrics_rise_test(dreamer)
    p = rise_test(page_hist) if page_hist is not None else metrics_rise_test(page)
    se = float(np.hypot(d.se, p.se))
    df = (se ** 4 / (d.se ** 4 / d.df + p.se ** 4 / p.df)) if d.se > 0 and p.se > 0 else d.df + p.df
    k = t_quantile(df)
    diff = Test(d.diff - p.diff, se, df, k, outcome(d.diff - p.diff, k * se, MIN_REWARD_EFFECT),
                MIN_REWARD_EFFECT, "Welch's t-test on the difference of the two rises")
    v = verdict(diff, WIRING_RISE)
    s = (f"**In the dream.** With the critic reaching the actor (Dreamer's wiring) the imagined reward per step "
         f"changed by **{d.diff:+.3f}** (± {d.se:.3f}) over training; with the page's wiring, where the actor sees "
         f"only the dreamed rewards, by **{p.diff:+.3f}** (± {p.se:.3f}). The difference, **{diff.diff:+.3f} ± "
         f"{se:.3f}**: ")
    s += {"up": "Dreamer's wiring raised the imagined reward more, beyond the noise and by at least the "
                "minimum effect. ",
          "down": "the page's wiring raised the imagined reward more, beyond the noise and by at least the "
                  "minimum effect. ",
          "small": "beyond the noise, but smaller than the minimum effect that matters, so the two wirings "
                   "are not read as different here. ",
          "same": "within the noise: this run cannot tell the two wirings apart on the imagined reward. "}[v]
    s += f"({diff.why()}.) "
    s += ("Keep in mind what each one maximises: the page's actor pushes only the rewards of its "
          f"{dreamer['imag_horizon']} dreamed steps, Dreamer's pushes the lambda-return, in which the "
          "critic's values stand for everything after them.")
    if dreamer_floor is None or page_floor is None:
        return s
    s += "\n\n**On the monitor's real starts.** "
    for name, fl in (("Dreamer's wiring", dreamer_floor), ("the page's wiring", page_floor)):
        t = floor_test(fl)
        vr = verdict(t, REAL_FLOOR)
        s += (f"With {name} the real floor changed by **{t.diff:+.3f} ± {_num(t.se)}** per step "
              f"({changed_starts(fl)} of {len(fl['first'])} starts changed at all; "
              + {"up": "a rise", "down": "a fall", "small": "beyond the noise but under the minimum effect",
                 "same": "within the noise"}[vr] + "). ")
    a = np.asarray(dreamer_floor["last"], float) - np.asarray(dreamer_floor["first"], float)
    b = np.asarray(page_floor["last"], float) - np.asarray(page_floor["first"], float)
    if len(a) == len(b) and len(a) > 1:
        t = sign_test(a - b, min_effect=MIN_REWARD_EFFECT)
        vw = verdict(t, WIRING_FLOOR)          # evaluated on every run, so the claims are recorded
    if len(a) == len(b) and len(a) > 1 and np.ptp(a - b) > 0:
        s += (f"Dreamer's minus the page's, start by start: **{t.diff:+.3f} ± {_num(t.se)}**: " + {
            "up": "Dreamer's wiring raised the real floor more, beyond the noise and by at least the minimum effect",
            "down": "the page's wiring raised the real floor more, beyond the noise and by at least the minimum effect",
            "small": "beyond the noise, but smaller than the minimum effect that matters",
            "same": "within the noise: on these few starts the two wirings cannot be told apart in reality"}[vw]
              + f" ({t.why()}). ")
    else:
        s += ("The two wirings' per-start changes differ by the same amount on every start (or not at all), so "
              "there is no spread to test their difference against. ")
    s += ("These are the monitor's few starts, a first hint; notebook 04 deploys a policy in both worlds on "
          "held-out starts.")
    return s


@claim("03.curve_identical", "the learner's training curve is identical to the package's run")
def curve_identical(*, max_diff):
    return max_diff == 0


def match_sentence(max_diff: float, iters: int, took: str) -> str:
    """How the learner's own training compares with the package's run (largest difference of the
    imagined reward per update)."""
    s = f"{iters} updates in imagination{took}. "
    if curve_identical(max_diff=max_diff):
        return s + "Your training curve is **identical** to the package's run."
    return s + (f"Your training curve differs from the package's run by up to {max_diff:.2g} reward per step "
                "(tiny float differences can grow over many updates; a large one means a loss is not the same).")


@claim("03.small_lam_higher", "with the untrained critic, the lam = 0 returns come out higher than "
       "the lam = 1 returns (mean over the dreamed steps)")
def small_lam_higher(*, mean_lam0, mean_lam1):
    return mean_lam0 > mean_lam1


@claim("03.untrained_values_optimistic", "the untrained critic's mean value of the first dreamed state "
       "is above the mean discounted sum of the dreamed rewards over the horizon (an upper bound on the "
       "dream's return from that state: every reward is at most 0)")
def untrained_values_optimistic(*, mean_value, mean_partial_return):
    return mean_value > mean_partial_return


def lambda_sentence(returns_by_lam: dict, rewards, values, gamma: float) -> str:
    """What the lambda-return figure shows on this batch: how optimistic the untrained critic is,
    and whether the returns that lean on it most (lam = 0) come out higher than lam = 1's.

    ``rewards`` (H, B) and ``values`` (H+1, B): the batch's dreamed rewards and untrained values;
    ``returns_by_lam`` must hold lam = 0.0 and lam = 1.0.
    """
    r = np.asarray(rewards, dtype=float)
    v = np.asarray(values, dtype=float)
    H = r.shape[0]
    partial = float((r * gamma ** np.arange(H)[:, None]).sum(0).mean())   # discounted H-step sum from s_0
    v0 = float(v[0].mean())
    g0, g1 = float(np.mean(returns_by_lam[0.0])), float(np.mean(returns_by_lam[1.0]))
    s = (f"On these dreams the untrained critic's values lie between {v.min():+.3f} and {v.max():+.3f} "
         f"(mean **{v0:+.3f}** on the start states), and the dreamed reward averages **{r.mean():+.3f}** per "
         f"step. Every PushT reward, dreamed or real, is at most 0, so the dream's return from a start "
         f"state is at most the discounted sum of its {H} dreamed rewards, **{partial:+.3f}** on average, "
         "and every step after them only lowers it. ")
    if untrained_values_optimistic(mean_value=v0, mean_partial_return=partial):
        s += "The untrained critic is more optimistic than that bound. "
    else:
        s += "On this batch the untrained critic is not above that bound: it is not optimistic here. "
    if small_lam_higher(mean_lam0=g0, mean_lam1=g1):
        s += (f"The returns that lean on it most (lam = 0, mean **{g0:+.3f}** over the steps) come out higher "
              f"than the ones that lean on it only at the horizon (lam = 1, mean **{g1:+.3f}**).")
    else:
        s += (f"Yet the returns that lean on it most (lam = 0, mean **{g0:+.3f}** over the steps) do not come "
              f"out higher than lam = 1's (mean **{g1:+.3f}**) on this batch.")
    return s


@claim("03.your_actor_reaches_states", "the learner's actor loss sends gradient into the states through "
       "the critic's values")
def your_actor_reaches_states(*, norm):
    return norm > 0


@claim("03.your_actor_reaches_critic_weights", "the learner's actor loss has a gradient on the critic's weights")
def your_actor_reaches_critic_weights(*, norm):
    return norm > 0


@claim("03.your_critic_spares_states", "the learner's critic loss sends no gradient into the states")
def your_critic_spares_states(*, norm):
    return norm == 0


@claim("03.page_actor_spares_states", "the page's actor loss sends no gradient into the states through "
       "the values")
def page_actor_spares_states(*, norm):
    return norm == 0


def reach_reading(reach: dict, yours: str = "your losses", page: str = "the page's losses") -> str:
    """The :func:`gradient_reach` table read row by row, each reading guarded by its claim."""
    y, pg = reach[yours], reach[page]
    s = []
    if your_actor_reaches_critic_weights(norm=y["actor loss", "critic's weights"]):
        s.append("Your actor loss has a gradient on the **critic's weights**: the values in its return are "
                 "computed by the critic. The loop never applies it: `set_gradients` (shown above) takes the "
                 "actor loss's gradient with respect to the actor's weights only. One summed `backward()` "
                 "would put it on the critic, and teach the critic to raise its own values.")
    else:
        s.append("Your actor loss has no gradient on the critic's weights: its return does not use the "
                 "critic's values with their gradient.")
    if your_actor_reaches_states(norm=y["actor loss", "states, via the values"]):
        s.append("It also sends gradient into the **states through the values**: that is the critic's slope "
                 "reaching the actions, Dreamer's wiring.")
    else:
        s.append("It sends nothing into the states through the values: that is the page's wiring, not "
                 "Dreamer's (Exercise B asks for the values with their gradient).")
    if your_critic_spares_states(norm=y["critic loss", "states, via the values"]):
        s.append("Your critic loss sends nothing into the states, as Exercise B asks. Whether that detach "
                 "changes training in this loop is measured below.")
    else:
        s.append(f"Your critic loss sends {y['critic loss', 'states, via the values']:.3g} into the states: "
                 "Exercise B asks it to read them detached (the grader checks it). The measurement below "
                 "shows what that changes.")
    if page_actor_spares_states(norm=pg["actor loss", "states, via the values"]):
        s.append("With the page's losses the actor loss sends nothing into the states through the values: "
                 "the page's actor learns from the rewards alone.")
    else:
        s.append("With the page's losses the actor loss does send gradient into the states through the "
                 "values, which its detached values should rule out.")
    return " ".join(s)


def objective_sentence(hist: dict, horizon: int) -> str:
    """Read the "What the actor maximises" panel: did the mean lambda-return fall while the imagined
    reward did not, and why that is the critic learning, not the actor getting worse (claims).

    The minimum effect for the return is MIN_REWARD_EFFECT times ``horizon``: the change of the
    return if each of the ``horizon`` dreamed rewards changed by the minimum effect."""
    g = np.asarray(hist["imag_return"], dtype=float)
    n = min(20, len(g) // 2)
    obj = welch(g[:n], g[-n:], min_effect=MIN_REWARD_EFFECT * horizon)
    vo, vi = verdict(obj, OBJECTIVE), verdict(rise_test(hist), IMAGINED)
    s = (f"The middle panel, the mean lambda-return the actor maximises, went from **{g[:n].mean():+.2f}** (first "
         f"{n} updates) to **{g[-n:].mean():+.2f}** (last {n}): **{obj.diff:+.3f} ± {_num(obj.se)}** ({obj.why()}, "
         f"the return of {horizon} dreamed rewards each changed by {MIN_REWARD_EFFECT:.2f}). ")
    if vo == "down" and vi != "down":
        s += ("It **fell**, while the imagined reward per step "
              + {"up": "rose", "small": "barely moved", "same": "did not measurably move"}[vi]
              + (". That is not the actor getting worse. The lambda-return is the dreamed rewards *plus the "
                 "critic's values* (at the horizon, and with weight 1 - lam at every step), and the critic is "
                 "learning too: it starts as an untrained network that knows nothing of PushT's rewards (the "
                 "lambda-return figure above showed one), and it learns that returns here are negative, since every "
                 "reward is at most 0. As its values fall toward the true returns, they pull the lambda-return down "
                 "with them. So the panel mostly tracks the critic learning what the returns are, and the imagined "
                 "reward is the actor's own progress."))
        cl = np.asarray(hist.get("critic_loss", []), dtype=float)
        if len(cl) >= 2 and critic_loss_fell(first=float(cl[:n].mean()), last=float(cl[-n:].mean())):
            s += (f" The left panel shows the critic learning: its loss fell from {cl[:n].mean():.3g} to "
                  f"{cl[-n:].mean():.3g} (means of the first and last {n} updates).")
    elif vo == "down":
        s += ("It fell, and so did the imagined reward per step: the dreamed rewards inside it fell, whatever the "
              "critic's values did.")
    elif vo == "up":
        s += ("It rose: the dreamed rewards and the critic's values inside it rose together, or one more than the "
              "other fell.")
    else:
        s += ("That is " + ("beyond the noise but smaller than the minimum effect" if vo == "small" else
                            "within the noise") + ": the panel shows no change that matters.")
    return s


def carry_forward(hist: dict, floor: dict) -> str:
    """The notebook's closing paragraph, guarded by the same claims as :func:`training_sentence`."""
    vi, vr = verdict(rise_test(hist), IMAGINED), verdict(floor_test(floor), REAL_FLOOR)
    s = ("The policy trained, and by its own measure, the dream's, it improved. " if vi == "up" else
         "The policy trained, but on this run even its own measure, the dream's, does not show it improving "
         "beyond the noise and the minimum effect. ")
    s += ("Every gradient it ever received was computed on the dream's picture of the world, a picture "
          "learned from data and not the world itself, and the actor was free to find actions that make "
          "that picture's errors work in its favour. ")
    s += {"up": "On the monitor's few real starts the real floor rose too, ",
          "down": "On the monitor's few real starts the real floor fell, ",
          "small": "On the monitor's few real starts the real floor moved by less than matters, ",
          "same": "On the monitor's few real starts the real floor's change cannot be told from none, "}[vr]
    s += ("which is a first hint, not a measurement of the gap. Notebook 04 deploys the final policy in both "
          "worlds on held-out starts, next to the untrained policy and doing nothing, and takes the gap apart.")
    return s


# --- figures -----------------------------------------------------------------------------------


def _smooth(x: np.ndarray, w: int) -> np.ndarray:
    return np.convolve(x, np.ones(w) / w, mode="valid")


@figure
def fig_lambda_returns(returns_by_lam: dict, train_lam: float, n_dreams: int):
    """Mean lambda-return per dreamed step for several lambdas (dict lam -> (H,) array)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.8))
    for (lam, G), style in zip(returns_by_lam.items(), (":", "-.", "-", "--", "-")):
        ax.plot(np.arange(len(G)), G, style, lw=2, marker="o", ms=3,
                label=f"lam = {lam:g}" + (" (training)" if lam == train_lam else ""))
    ax.set_xlabel("dreamed step t")
    ax.set_ylabel("lambda-return $G_t$ (reward units):\ndiscounted dreamed rewards from t on\n+ the critic's values")
    ax.set_title(f"Your lambda-return on {n_dreams} dreams, untrained critic (mean over dreams)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_training(hists: dict, monitor_episodes: int):
    """Imagined reward per update (moving average) and the real monitor, for each named run.

    ``hists`` maps a label (e.g. "Dreamer's wiring") to a training history.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 4.3))
    colors = ["tab:red", "tab:blue", "tab:green", "tab:purple"]
    for (label, h), color in zip(hists.items(), colors):
        imag = np.asarray(h["imag_reward"])
        w = max(1, min(20, len(imag) // 10))
        it = np.arange(len(imag))
        ax.plot(it, imag, color=color, alpha=0.15, lw=1)
        ax.plot(it[w - 1:], _smooth(imag, w), color=color, lw=2.2,
                label=f"{label}: imagined (moving average of {w} updates)")
        ax.plot(h["monitor_iters"], h["monitor_real_reward"], "s--", color=color, lw=1.2, ms=6,
                label=f"{label}: real sim, same policy ({monitor_episodes} starts)")
    ax.set_xlabel("policy update (iteration)")
    ax.set_ylabel("reward per step")
    ax.set_title("The same policy during training, in the dream and in the real sim")
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


@figure
def fig_critic_and_std(hist: dict):
    """The critic's loss and the actor's exploration noise over training."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 3.4), sharex=True)
    cl = np.asarray(hist["critic_loss"])
    it = np.arange(len(cl))
    w = max(1, min(20, len(cl) // 10))
    axes[0].plot(it, cl, color="tab:purple", alpha=0.3, lw=1, label="every update")
    axes[0].plot(it[w - 1:], _smooth(cl, w), color="tab:purple", lw=2, label=f"moving average of {w}")
    axes[0].set_title("Critic loss")
    axes[0].set_ylabel("0.5 x squared error\n(return units squared)")
    axes[0].legend(fontsize=8)
    ret = np.asarray(hist["imag_return"])
    axes[1].plot(it, ret, color="tab:red", alpha=0.3, lw=1)
    axes[1].plot(it[w - 1:], _smooth(ret, w), color="tab:red", lw=2)
    axes[1].set_title("What the actor maximises")
    axes[1].set_ylabel("mean lambda-return\n(critic's bootstrap included)")
    axes[2].plot(it, hist["log_std"], color="tab:green", lw=2)
    axes[2].set_title("Actor's exploration noise")
    axes[2].set_ylabel("log std of the action noise\n(before tanh, mean over both axes)")
    for ax in axes:
        ax.set_xlabel("policy update (iteration)")
    fig.tight_layout()
    return fig


# --- self-checks -------------------------------------------------------------------------------
SELF_CHECKS = {
    "lam_one": Question(
        "With `lam = 1`, which critic value still enters the return G_0?",
        {"a": "None: lam = 1 is the pure sum of the dreamed rewards",
         "b": "Only V_H, the value of the last dreamed state, discounted by gamma^H",
         "c": "All of V_1 .. V_H, each weighted equally"},
        "b", "G_H = V_H closes the recursion; every (1 - lam) V_{t+1} term vanishes, but the last "
             "state's value is still added, discounted by gamma^H."),
    "critic_detach": Question(
        "Suppose your critic loss read the imagined states WITHOUT detaching them, and the loop "
        "put the gradients on the parameters with `set_gradients`, as shown above. What would change?",
        {"a": "Nothing: `set_gradients` differentiates the critic loss with respect to the critic's "
              "weights only, so what it would send into the states lands on no parameter. The detach "
              "becomes essential when both losses go into one summed `backward()`",
         "b": "Its gradient would reach the actor's weights through the dream, so value regression "
              "would move the policy (toward states that are easy to predict)",
         "c": "The critic would learn faster because it sees more gradient"},
        "a", "`torch.autograd.grad(critic_loss, critic_params)` computes the gradient on the critic's "
             "weights and nothing else; the states' part of it is never put on any parameter. DreamerV1 "
             "works the same way: its value loss reads the imagined features without a stop-gradient, "
             "on a tape of its own whose gradient only the value model's optimiser applies "
             "(`danijar/dreamer`, `Dreamer._train`). (b) is what happens in a loop that sums both losses "
             "into one `backward()` (one optimiser for both networks): every gradient then lands on "
             "every parameter it reaches. The cells below measure both set-ups on your losses. Keep the detach anyway: "
             "it makes the critic loss safe under either set-up, and costs nothing."),
    "page_wiring": Question(
        "Under the chapter page's wiring (values detached inside the actor's return), what does "
        "the actor learn from the critic?",
        {"a": "Nothing: its gradient comes only from the H dreamed rewards, so replacing the "
              "critic by zeros gives the same actor",
         "b": "The value of the states beyond the horizon, through V_H",
         "c": "Only the sign of the advantage"},
        "a", "A detached value is a constant to the actor's gradient. The perturbation test below "
             "checks exactly this: it changes the critic's weights and compares the page's actor "
             "gradient before and after."),
    "what_rises": Question(
        "Suppose the imagined reward rises during training. What would that, on its own, tell you "
        "about the real robot?",
        {"a": "That it improves too, maybe more slowly",
         "b": "Nothing yet: it measures the policy against the dream's picture of the block, which "
              "is the very thing the actor is free to exploit",
         "c": "That the world model is accurate"},
        "b", "Only a measurement in reality can say: the real floor below gives a first, noisy one, and "
             "notebook 04 makes it on identical starts in both worlds."),
}
