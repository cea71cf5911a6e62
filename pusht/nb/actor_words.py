"""Notebook 03's sentences: what the measured numbers say, each reading guarded by a registered
claim (``actor_claims``), with its true alternative.
"""

from __future__ import annotations

import numpy as np

from .actor_claims import (IMAGINED, OBJECTIVE, REAL_FLOOR, WIRING_FLOOR, WIRING_RISE, critic_loss_fell,
                           critic_reaches_your_actor, critic_spares_page_actor, curve_identical,
                           floor_changes_spread, floor_most_starts_unchanged, floor_reproduces_monitor,
                           page_actor_spares_states, small_lam_higher,
                           states_detach_idle_under_set_gradients, states_detach_needed_in_summed_backward,
                           target_detach_needed, unchanged_starts_untouched, untrained_values_optimistic,
                           verdict, your_actor_reaches_critic_weights, your_actor_reaches_states,
                           your_critic_spares_states)
from .actor_measure import GROUPS, ROUTES, _window, changed_starts, floor_test, metrics_rise_test, rise_test
from .fmt import num
from .stats import MIN_REWARD_EFFECT, Test, outcome, sign_test, t_quantile, welch


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


def rose_beyond_noise(hist: dict) -> bool:
    """Did the imagined reward rise over training beyond its noise and by at least the minimum
    effect? (claim ``03.imagined_rose`` on :func:`rise_test`)."""
    return verdict(rise_test(hist), IMAGINED) == "up"


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
         f"{num(imag.se)}** (standard error from the updates' own spread). {_WORDS[vi]} ({imag.why()}.)\n\n")
    s += (f"**In the real sim.** On the monitor's {n} real starts the same policy went from **{r0:+.3f}** "
          f"(untrained) to **{r1:+.3f}** (trained) per step: a change of **{real.diff:+.3f} ± {num(real.se)}** "
          f"(standard error of the {n} per-start changes; the same starts before and after). {_WORDS[vr]} "
          f"({real.why()}.)")
    spread = floor_changes_spread(se=real.se)
    c = changed_starts(floor)
    mostly_same = floor_most_starts_unchanged(n_changed=c, n=n)
    if vr in ("same", "small") and spread and not mostly_same:
        s += (f" With {n} starts, a change has to exceed about {num(real.k * real.se)} per step "
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


def _older_training_sentence(m: dict) -> str:
    """``training_sentence`` for a notebook of an older release, which passes a run's metrics only:
    the imagined rise is tested (the metrics keep its standard error); the real floor's two means
    are quoted, untested, because the metrics keep no per-start values."""
    imag = metrics_rise_test(m)
    diff, se = imag.diff, imag.se
    vi = verdict(imag, IMAGINED)
    r0, r1 = m["real_reward_monitor_first"], m["real_reward_monitor_last"]
    return (f"Over training, the imagined reward per step changed by **{diff:+.3f} ± {num(se)}** (last 20 "
            f"updates minus the first 20). {_WORDS[vi]} ({imag.why()}; {_bar()}.) On the monitor's real starts "
            f"the policy went from {r0:+.3f} to {r1:+.3f} per step: this notebook, from an older release, does not "
            "keep the per-start values that would give that change a standard error, so it is not read as a "
            "rise or a fall here; the current release of notebook 03 tests it, and notebook 04 compares the "
            "same policy in both worlds on identical starts.")


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
        s += (f"With {name} the real floor changed by **{t.diff:+.3f} ± {num(t.se)}** per step "
              f"({changed_starts(fl)} of {len(fl['first'])} starts changed at all; "
              + {"up": "a rise", "down": "a fall", "small": "beyond the noise but under the minimum effect",
                 "same": "within the noise"}[vr] + "). ")
    a = np.asarray(dreamer_floor["last"], float) - np.asarray(dreamer_floor["first"], float)
    b = np.asarray(page_floor["last"], float) - np.asarray(page_floor["first"], float)
    if len(a) == len(b) and len(a) > 1:
        t = sign_test(a - b, min_effect=MIN_REWARD_EFFECT)
        vw = verdict(t, WIRING_FLOOR)          # evaluated on every run, so the claims are recorded
    if len(a) == len(b) and len(a) > 1 and np.ptp(a - b) > 0:
        s += (f"Dreamer's minus the page's, start by start: **{t.diff:+.3f} ± {num(t.se)}**: " + {
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


def match_sentence(max_diff: float, iters: int, took: str) -> str:
    """How the learner's own training compares with the package's run (largest difference of the
    imagined reward per update)."""
    s = f"{iters} updates in imagination{took}. "
    if curve_identical(max_diff=max_diff):
        return s + "Your training curve is **identical** to the package's run."
    return s + (f"Your training curve differs from the package's run by up to {max_diff:.2g} reward per step "
                "(tiny float differences can grow over many updates; a large one means a loss is not the same).")


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
         f"{n} updates) to **{g[-n:].mean():+.2f}** (last {n}): **{obj.diff:+.3f} ± {num(obj.se)}** ({obj.why()}, "
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
