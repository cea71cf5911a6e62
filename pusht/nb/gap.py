"""Notebook 04's figures, conclusions and self-checks: the imagination gap, taken apart.

Every threshold that decides a sentence here is a multiple of a standard error measured on the
same run (``pusht.analysis``: per-start spread over the evaluation starts, or the training
updates' own spread), never a typed-in amount. ``K_SE = 2``: a difference smaller than twice its
standard error is reported as "not told apart from zero by these starts".
"""

from __future__ import annotations

import numpy as np

from ..env import SUCCESS_ANG, SUCCESS_POS, obs_to_pose
from ..selfcheck import Question
from . import figure

K_SE = 2.0
# 5 mm: the smallest distance difference these sentences read as a difference (a sixth of the
# pusher's radius; the per-start spread of final distances is several centimetres).
NEAR = 0.005
COLORS = {"dream": "tab:purple", "real": "tab:orange"}
POLICY_LABELS = {"zero": "zero actions", "untrained": "untrained actor", "trained": "trained actor"}
TERMS = {"drift": "drift (zero actions)", "motion": "untrained actor's motion",
         "training": "training (exploitation)"}
SPANS = {"train_horizon": "training horizon", "eval_horizon": "whole evaluation"}


# --- Exercise 1 ---------------------------------------------------------------------------------
EX1_OPTIONS = {
    "a": "It transfers: real successes appear.",
    "b": "No real success, and the dream rates the trained policy well above reality; the rosy "
         "part comes with the actor's actions (a pusher that never moves would be rated about as "
         "reality rates it).",
    "c": "No real success, and the dream rates the trained policy well above reality; but it is "
         "rosy even for a pusher that never moves (zero actions already get at least half of the "
         "trained policy's gap).",
    "d": "No real success, and the dream is no rosier than reality.",
}


def clearly_positive(value: float, se: float, k: float = K_SE) -> bool:
    """``value`` exceeds ``k`` standard errors (``se`` measured on the same starts)."""
    return bool(value > k * se)


def ex1_verdict(metrics: list[dict]) -> str:
    """Exercise 1's measured outcome (a letter of ``EX1_OPTIONS``) from each seed's evaluation
    metrics (``two_world_eval`` with ``train_horizon``). Decided on the whole evaluation, the
    deployed 10 s that the question is about; "well above" means beyond ``K_SE`` standard errors
    of the per-start gaps; a mixed result across seeds is decided on the seeds' means."""
    if any(m["real_success_rate"] > 0 for m in metrics):
        return "a"
    if not all(clearly_positive(m["imagination_gap"], m["imagination_gap_se_eval_horizon"]) for m in metrics):
        return "d"
    zero_rosy = [clearly_positive(m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"])
                 and m["gap_drift_eval_horizon"] >= 0.5 * m["imagination_gap"] for m in metrics]
    if all(zero_rosy):
        return "c"
    if not any(zero_rosy):
        return "b"
    drift = np.mean([m["gap_drift_eval_horizon"] for m in metrics])
    return "c" if drift >= 0.5 * np.mean([m["imagination_gap"] for m in metrics]) else "b"


def ex1_sentence(seed: int, m: dict, n_eval: int) -> str:
    return (f"Seed {seed}: deployed, the policy earns {m['imagined_return_per_step']:+.3f} per step in the dream "
            f"and {m['real_return_per_step']:+.3f} in reality (gap {m['imagination_gap']:+.3f} ± "
            f"{m['imagination_gap_se_eval_horizon']:.3f}); with zero actions the dream is "
            f"{m['gap_drift_eval_horizon']:+.3f} ± {m['gap_drift_se_eval_horizon']:.3f} rosier than reality; "
            f"{round(m['real_success_rate'] * n_eval)}/{n_eval} real successes.")


# --- reading the split of the gap ----------------------------------------------------------------
def describe(value: float, se: float) -> str:
    """A term in words, judged against its own standard error."""
    if value > K_SE * se:
        return "clearly positive"
    if value < -K_SE * se:
        return "clearly negative"
    return "not told apart from zero"


def split_sentence(m: dict, span: str, steps: int) -> str:
    """The gap and its three terms over ``span`` ("train_horizon" or "eval_horizon")."""
    gap, gse = m[f"imagination_gap_{span}"], m[f"imagination_gap_se_{span}"]
    parts = []
    for term, label in TERMS.items():
        v, se = m[f"gap_{term}_{span}"], m[f"gap_{term}_se_{span}"]
        share = f", {v / gap:.0%} of the gap" if gap > K_SE * gse else ""
        parts.append(f"{label} **{v:+.3f}** ± {se:.3f} ({describe(v, se)}{share})")
    return (f"Over the first **{steps} steps** ({SPANS[span]}) the gap is **{gap:+.3f}** ± {gse:.3f} per step: "
            + "; ".join(parts) + ".")


def split_story(m: dict, H: int) -> str:
    """What the two horizons say together about drift and exploitation."""
    tr_h, tr_e = m["gap_training_train_horizon"], m["gap_training_eval_horizon"]
    se_h, se_e = m["gap_training_se_train_horizon"], m["gap_training_se_eval_horizon"]
    drift_h = m["gap_drift_train_horizon"]
    s = ""
    if clearly_positive(tr_h, se_h):
        gap_h = m["imagination_gap_train_horizon"]
        share = f", {tr_h / gap_h:.0%} of the gap over those steps" if gap_h > 0 else ""
        s += (f"Within the {H} steps its gradient saw, training made the dream rosier than it made reality "
              f"by {tr_h:+.3f} per step (beyond twice its standard error{share}): that part the actor "
              "learned and only the dream pays for, which is exploitation. ")
    else:
        s += (f"Within the {H} steps its gradient saw, training did not make the dream measurably rosier "
              f"than reality ({tr_h:+.3f} ± {se_h:.3f}): on this seed the actor found little to exploit. ")
    if not clearly_positive(tr_e, se_e) and clearly_positive(tr_h, se_h):
        s += ("Over the whole evaluation that advantage is gone: past its training horizon the actor's "
              "dream is no better than the untrained one's. ")
    s += (f"The drift, the model's own optimism with the pusher standing still, is {drift_h:+.3f} per step "
          f"already over the first {H} steps.")
    return s


def min_of_mean_distance(rollout, dt: float = 0.1) -> tuple[float, float]:
    """(smallest mean block-to-target distance over time in m, the time in s it happens)."""
    d = np.linalg.norm(rollout.obs[:, :, 2:4], axis=-1).mean(1)
    i = int(np.argmin(d))
    return float(d[i]), i * dt


def dip_sentence(rollouts: dict, H: int, dt: float = 0.1) -> str:
    """Read the over-time panel: where and when the trained dream's block comes closest."""
    d_min, t_min = min_of_mean_distance(rollouts["dream_trained"], dt)
    z_min, z_t = min_of_mean_distance(rollouts["dream_zero"], dt)
    end = float(np.linalg.norm(rollouts["dream_trained"].obs[-1, :, 2:4], axis=-1).mean())
    where = (f"inside the {H * dt:.1f} s the actor trained on" if t_min <= H * dt
             else f"after the {H * dt:.1f} s the actor trained on")
    s = (f"In the trained actor's dream the mean block distance is smallest, **{d_min:.3f} m**, at "
         f"**{t_min:.1f} s** ({where}), and ends the evaluation at **{end:.3f} m**; the zero-action "
         f"dream's smallest is {z_min:.3f} m at {z_t:.1f} s. ")
    if t_min <= H * dt and end > d_min + NEAR:
        s += "After its best moment the trained dream's block drifts back out. "
    if z_min < d_min - NEAR:
        s += ("A pusher that never moves gets the dreamed block closer to the target than the trained "
              "actor does: the model's drift, not the actor, brings the dream nearest to success.")
    return s


# --- distribution shift ---------------------------------------------------------------------------
def shift_sentence(m: dict, dt: float = 0.1) -> str:
    """Distribution shift, in words, from the metrics of ``analysis.shift_metrics``."""
    H = m["imag_horizon"]
    s = (f"The expert data has the pusher against a wall in **{m['expert_pusher_at_wall_share']:.0%}** of its "
         f"steps; the deployed policy in **{m['real_pusher_at_wall_share']:.0%}** of its real steps. ")
    s += (f"Replaying the policy's own real actions, the model's pusher is **{100 * m['replay_pusher_err_train_horizon']:.1f} cm** "
          f"off after {H * dt:.1f} s, against {100 * m['expert_replay_pusher_err_train_horizon']:.1f} cm on held-out "
          f"expert clips; its block is {100 * m['replay_block_err_train_horizon']:.1f} cm off (expert clips: "
          f"{100 * m['expert_replay_block_err_train_horizon']:.1f} cm). ")
    worse = m["replay_pusher_err_train_horizon"] > m["expert_replay_pusher_err_train_horizon"]
    s += ("So the model tracks the pusher worse on the policy's data than on the expert's: the policy "
          "has left the data the model knows. " if worse else
          "On the pusher, the model tracks the policy's data about as well as the expert's. ")
    s += (f"The evaluation dream runs **{m['dream_steps_per_train_clip']:.2f}x** longer than the "
          f"{m['train_clip_steps']}-step clips the model trained on. Its end points collapse: the dreamed "
          f"blocks end a mean **{m['dream_final_block_spread']:.3f} m** from their common centre, the real "
          f"ones {m['real_final_block_spread']:.3f} m (they spawned {m['spawn_block_spread']:.3f} m apart, "
          "measured the same way).")
    return s


# --- across seeds --------------------------------------------------------------------------------
def seeds_sentence(metrics: dict) -> str:
    """Seeds side by side: the range of the gap and what the largest one is made of."""
    gaps = {s: m["imagination_gap"] for s, m in metrics.items()}
    lo, hi = min(gaps.values()), max(gaps.values())
    big = max(gaps, key=gaps.get)
    mb = metrics[big]
    s = (f"Across seeds {', '.join(map(str, metrics))} the gap runs from **{lo:+.3f}** to **{hi:+.3f}** per step "
         f"and real success is zero on **{sum(m['real_success_rate'] == 0 for m in metrics.values())}/"
         f"{len(metrics)}** seeds. The largest gap is seed {big}'s: over the whole evaluation its drift is "
         f"{mb['gap_drift_eval_horizon']:+.3f} and training adds {mb['gap_training_eval_horizon']:+.3f} "
         f"(± {mb['gap_training_se_eval_horizon']:.3f}); over the training horizon training adds "
         f"{mb['gap_training_train_horizon']:+.3f} (± {mb['gap_training_se_train_horizon']:.3f}). ")
    drifts = [m["gap_drift_eval_horizon"] for m in metrics.values()]
    s += (f"The drift alone ranges from {min(drifts):+.3f} to {max(drifts):+.3f}: "
          + ("on every seed it is most of the gap." if all(m["gap_drift_eval_horizon"] >= 0.5 * m["imagination_gap"]
                                                        for m in metrics.values())
             else "on some seeds the actor's own contribution is the larger part."))
    return s


# --- figures -------------------------------------------------------------------------------------
def solved_at_some_step(rollout) -> np.ndarray:
    """(B,) whether the block pose meets the env's success thresholds at any step after the start."""
    _, tee = obs_to_pose(rollout.obs[1:])
    yaw_err = np.abs(np.arctan2(np.sin(tee[..., 2]), np.cos(tee[..., 2])))
    return ((np.linalg.norm(tee[..., :2], axis=-1) < SUCCESS_POS) & (yaw_err < SUCCESS_ANG)).any(axis=0)


@figure
def fig_two_worlds(dream_roll, real_roll, gap: float, seed: int, seconds: float):
    """Reward per step, final block distance and success of one policy in both worlds."""
    import matplotlib.pyplot as plt

    spawn = np.linalg.norm(real_roll.obs[0, :, 2:4], axis=-1)
    rng = np.random.default_rng(0)                       # horizontal jitter for the dots only
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    ax = axes[0]
    vals = [dream_roll.return_per_step, real_roll.return_per_step]
    for x, (name, v) in enumerate(zip(["dream", "real"], vals)):
        ax.bar(x, v.mean(), 0.6, color=COLORS[name], alpha=0.8,
               label=f"{'imagined (in the dream)' if name == 'dream' else 'real (true PushT)'}: {v.mean():+.3f}")
        ax.scatter(x + rng.uniform(-0.15, 0.15, len(v)), v, s=10, color="k", alpha=0.5, zorder=3)
    ax.annotate("", xy=(0.5, vals[0].mean()), xytext=(0.5, vals[1].mean()),
                arrowprops=dict(arrowstyle="<->", color="k", lw=1.5))
    ax.text(0.55, (vals[0].mean() + vals[1].mean()) / 2, f"gap\n{gap:+.3f}", va="center")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks([0, 1], ["in the dream", "in reality"])
    ax.set_ylabel("mean reward per step (0 = block on target)")
    ax.set_title("Reward per step")
    ax.legend(loc="lower left", fontsize=8)
    ax = axes[1]
    vals = [dream_roll.final_tee_dist, real_roll.final_tee_dist]
    for x, (name, v) in enumerate(zip(["dream", "real"], vals)):
        ax.bar(x, v.mean(), 0.6, color=COLORS[name], alpha=0.8, label=f"{name}: {v.mean():.3f} m")
        ax.scatter(x + rng.uniform(-0.15, 0.15, len(v)), v, s=10, color="k", alpha=0.5, zorder=3)
    ax.axhline(spawn.mean(), color="k", ls="--", lw=1, label=f"where the block spawned: {spawn.mean():.3f} m")
    ax.set_xticks([0, 1], ["in the dream", "in reality"])
    ax.set_ylabel("block-to-target distance at the end (m)")
    ax.set_title(f"Where the block ends ({seconds:.0f} s)")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_ylim(0, max(v.max() for v in vals) * 1.25)
    ax = axes[2]
    solved = [solved_at_some_step(dream_roll), real_roll.success]
    for x, s in enumerate(solved):
        ax.bar(x, s.mean(), 0.6, color=list(COLORS.values())[x], alpha=0.8)
        ax.text(x, s.mean() + 0.03, f"{int(s.sum())}/{len(s)} starts", ha="center")
    ax.set_ylim(0, 1.05)
    ax.set_xticks([0, 1], ["dream (same thresholds\non the decoded block)", "reality (env's flag)"])
    ax.set_ylabel("fraction of starts solved at some step")
    ax.set_title("Task solved?")
    fig.suptitle(f"The same policy in two worlds (seed {seed}, {len(spawn)} held-out starts)")
    fig.tight_layout()
    return fig


@figure
def fig_decomposition(m: dict, steps: dict):
    """The controls in both worlds at both horizons, and the gap's three terms with 2-SE bars.

    ``steps`` maps "train_horizon" and "eval_horizon" to their number of steps.
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4), gridspec_kw={"width_ratios": [1, 1, 1.2]})
    x = np.arange(3)
    for ax, span in zip(axes[:2], SPANS):
        for dx, world in ((-0.2, "dream"), (0.2, "real")):
            ax.bar(x + dx, [m[f"{p}_{world}_return_per_step_{span}"] for p in POLICY_LABELS], 0.4,
                   color=COLORS[world], alpha=0.85, label="in the dream" if world == "dream" else "in reality")
        ax.set_xticks(x, list(POLICY_LABELS.values()))
        ax.axhline(0, color="k", lw=0.8)
        ax.set_ylabel("mean reward per step")
        ax.set_title(f"First {steps[span]} steps ({SPANS[span]})")
        ax.legend(fontsize=8, loc="lower center")
    lo = min(m[f"{p}_{w}_return_per_step_{s}"] for p in POLICY_LABELS for w in ("dream", "real") for s in SPANS)
    for ax in axes[:2]:
        ax.set_ylim(1.3 * lo, 0)
    ax = axes[2]
    width = 0.18
    for j, span in enumerate(SPANS):
        keys = ["imagination_gap", *(f"gap_{t}" for t in TERMS)]
        vals = [m[f"{k}_{span}"] for k in keys]
        errs = [K_SE * m[f"{k}_se_{span}"] for k in keys]
        ax.bar(np.arange(4) + (j - 0.5) * 2 * width, vals, 2 * width, yerr=errs, capsize=3,
               color=("tab:cyan", "tab:blue")[j], label=f"first {steps[span]} steps ({SPANS[span]})")
    ax.set_xticks(np.arange(4), ["gap", *(v.replace(" (", "\n(").replace("actor's ", "actor's\n")
                                          for v in TERMS.values())], fontsize=8)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylabel("reward per step (dream minus reality)")
    ax.set_title("The gap = drift + motion + training (bars: ±2 standard errors)")
    ax.legend(fontsize=8)
    fig.suptitle("Three policies, two worlds, two horizons (same starts)")
    fig.tight_layout()
    return fig


@figure
def fig_block_over_time(rollouts: dict, H: int, clip: int, data_mean_dist: float, dt: float = 0.1):
    """Mean block-to-target distance over time: three policies in the dream, the trained one in
    reality, with the training horizon and the model's training-clip length marked."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.2))
    T = len(rollouts["dream_trained"].obs)
    t = np.arange(T) * dt
    for p, ls in zip(POLICY_LABELS, [":", "-.", "-"]):
        d = np.linalg.norm(rollouts[f"dream_{p}"].obs[:, :, 2:4], axis=-1).mean(1)
        ax.plot(t, d, ls=ls, color=COLORS["dream"], label=f"dream, {POLICY_LABELS[p]}")
    ax.plot(t, np.linalg.norm(rollouts["real_trained"].obs[:, :, 2:4], axis=-1).mean(1), color=COLORS["real"],
            label="reality, trained actor")
    ax.axvline(H * dt, color="k", ls="--", lw=1, label=f"the actor's training horizon ({H} steps)")
    ax.axvline(clip * dt, color="tab:gray", ls=":", lw=1.2, label=f"the model's training clips ({clip} steps)")
    ax.axhline(data_mean_dist, color="tab:green", ls=":", lw=1.5, label="mean block position in the expert data")
    ax.set_xlabel("time in the evaluation rollout (s)")
    ax.set_ylabel("mean block-to-target distance (m)")
    ax.set_title("Where the block is, step by step (mean over the starts)")
    ax.set_ylim(0, None)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


@figure
def fig_distribution_shift(real_roll, dream_roll, at_wall_real: np.ndarray, expert_share: float,
                           replay: dict, expert_replay: dict, clip: int, dt: float = 0.1):
    """Three views of the policy leaving the data: the pusher at the walls, the model replaying the
    policy's real actions, and where the dreamed and the real blocks end."""
    import matplotlib.pyplot as plt

    from ..draw import setup_arena

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), gridspec_kw={"width_ratios": [0.7, 1.2, 1]})
    ax = axes[0]
    shares = [expert_share, float(np.nanmean(at_wall_real))]
    ax.bar([0, 1], shares, 0.6, color=["tab:green", COLORS["real"]], alpha=0.85)
    for x, v in enumerate(shares):
        ax.text(x, v + 0.02, f"{v:.0%}", ha="center")
    ax.set_xticks([0, 1], ["expert data\n(the model's training set)", "deployed policy\n(real sim)"])
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("share of steps with the pusher against a wall")
    ax.set_title("Where the pusher spends its time")
    ax = axes[1]
    for key, color in (("pusher", "tab:blue"), ("block", "tab:red")):
        e = replay[key]
        t = (np.arange(len(e)) + 1) * dt
        ax.plot(t, e.mean(1), color=color, lw=2, label=f"{key}, replaying the policy's real actions")
        ex = expert_replay[key]
        ax.plot((np.arange(len(ex)) + 1) * dt, ex.mean(1), color=color, ls="--", lw=1.5,
                label=f"{key}, replaying held-out expert clips")
    ax.axvline(clip * dt, color="tab:gray", ls=":", lw=1.2, label=f"length of the training clips ({clip} steps)")
    ax.set_xlabel("time since the start frame (s)")
    ax.set_ylabel("dreamed minus true position (m, mean)")
    ax.set_title("The model replaying actions it is given")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_ylim(0, None)
    ax = axes[2]
    setup_arena(ax, "Where the blocks end (one dot per start)")
    ax.scatter(real_roll.obs[0, :, 2], real_roll.obs[0, :, 3], s=60, facecolors="none", edgecolors="k",
               lw=1, label="spawn")
    ax.scatter(real_roll.obs[-1, :, 2], real_roll.obs[-1, :, 3], s=16, color=COLORS["real"], label="reality, end")
    ax.scatter(dream_roll.obs[-1, :, 2], dream_roll.obs[-1, :, 3], s=16, color=COLORS["dream"], label="dream, end")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=7, loc="lower right")
    fig.suptitle("The deployed policy leaves the data the model knows")
    fig.tight_layout()
    return fig


@figure
def fig_pusher_paths(real_roll, touch_tol: float, seconds: float, seed: int, n: int = 6):
    """The real pusher's path for the first ``n`` starts, with the block at spawn and at the end."""
    import matplotlib.pyplot as plt

    from ..draw import draw_state, setup_arena
    from ..evaluate import pusher_gap

    closest = np.nanmin(pusher_gap(real_roll), axis=0)
    show = np.arange(min(n, real_roll.obs.shape[1]))
    fig, axes = plt.subplots(2, 3, figsize=(12, 9.2))
    for ax, j in zip(axes.flat, show):
        setup_arena(ax, f"start {j}: " + ("the pusher touches the block" if closest[j] < touch_tol
                                          else f"closest approach {100 * closest[j]:.1f} cm"))
        draw_state(ax, real_roll.obs[0, j], alpha=0.6, label="T-block at spawn")
        draw_state(ax, real_roll.obs[-1, j], target=False, alpha=0.5, tee_color="none", label="T-block at the end")
        ax.plot(real_roll.obs[:, j, 0], real_roll.obs[:, j, 1], color="tab:blue", lw=1.2, label="pusher path")
        ax.plot(*real_roll.obs[-1, j, :2], "x", color="tab:red", ms=9, mew=2, label="pusher at the end")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    for ax in axes.flat[len(show):]:
        ax.axis("off")
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="lower center", ncol=5, fontsize=9)
    fig.suptitle(f"Where the trained policy drives the real pusher ({seconds:.0f} s, seed {seed})")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


def median_start(dream_roll, real_roll) -> int:
    """The start whose dream-minus-real final distance is the median one: a typical start."""
    d = dream_roll.final_tee_dist - real_roll.final_tee_dist
    return int(np.argsort(d)[len(d) // 2])


# --- self-checks ---------------------------------------------------------------------------------
SELF_CHECKS = {
    "zero_control": Question(
        "Why does the zero-action control need to be run in reality too, not only in the dream?",
        {"a": "It does not: in reality a pusher that never moves changes nothing",
         "b": "Because only the difference between the two worlds, for the same policy and the same "
              "starts, says how rosy the dream is; the real run gives the reward of the spawn pose",
         "c": "To check that pymunk is deterministic"},
        "b", "Drift is defined as dream minus reality for the same policy; with zero actions, "
             "reality is the spawn pose's reward, the baseline the dream is judged against."),
    "two_horizons": Question(
        "Training's share of the gap can differ between the first 15 steps and the full 100. Why "
        "measure it at the training horizon at all?",
        {"a": "Because the actor's gradient only ever saw dreams of that length: exploitation, if "
              "any, must show up there first",
         "b": "Because the evaluation is too noisy at 100 steps",
         "c": "Because the critic is only trained for 15 steps"},
        "a", "The actor optimised the lambda-return of its training dreams; what it learned to "
             "exploit is exploited within them. Past that horizon the model drifts on its own."),
    "shift": Question(
        "On expert data the model beats 'copy the last frame' on the pusher (notebook 01). Why is "
        "that not enough to trust it on the deployed policy's data?",
        {"a": "It is enough: the pusher's kinematics do not depend on who commands it",
         "b": "Because the policy visits states the expert data never shows (the pusher pinned "
              "against a wall), and a model is only measured where its data was",
         "c": "Because the policy's actions are larger than the expert's"},
        "b", "A wall stops the real pusher; in the expert data it never met one, so the model "
             "never saw a commanded motion that does not happen. The replay error above measures it."),
}
