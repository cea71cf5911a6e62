"""Notebook 02's figures, the conclusions its prose draws, and its self-check questions.

Every figure and conclusion that scores a pose takes the reward function as an argument, so the
notebook draws them with the learner's own ``reward_from_obs`` (signature ``(norm_obs, mean, std)
-> (reward, pos_err, ang_err)``, see ``pusht.reward``).

Figures (each returns a ``matplotlib`` Figure; the notebook shows it and saves it):

    fig_reward_heatmap           reward over the block's position, yaw 0        02_reward_heatmap.png
    fig_reward_yaw               reward against the block's yaw error           02_reward_yaw.png
    fig_reward_one_sequence      one held-out sequence scored three ways        02_reward_one_sequence.png
    fig_final_pose               truth and dream at the end of that sequence    02_final_pose.png
    fig_reward_error             decoded-frame reward minus true reward         02_reward_error.png

Conclusions: the shape of the reward (``cone_verdict``, ``half_turn``) and how far a reward read
off decoded frames is from the true one (``reward_errors``, ``error_summary``).
"""

from __future__ import annotations

import numpy as np
import torch

from ..draw import TARGET_COLOR, draw_state, setup_arena
from ..env import (ARENA_HALF, CONTROL_DT, SUCCESS_ANG, SUCCESS_POS, TEE_RESET_HALF, tee_outline)
from .world_model import _count
from . import figure
from .prose import self_checks

# A signed mean counts as "not zero" only beyond this many standard errors of the mean over the
# held-out sequences (each sequence's mean error is one sample): about a 95% two-sided band.
SE_BAND = 2.0
# The cone test allows this many times the float32 rounding noise of the function under test,
# measured on the very same poses (float32 minus float64 evaluation, ``cone_verdict``).
ROUNDING_MARGIN = 10.0


def to_norm(obs_m, mean, std, dtype=torch.float32) -> torch.Tensor:
    """Observations in metres (..., 6) -> the normalised tensor the networks see."""
    mean, std = torch.as_tensor(mean, dtype=dtype), torch.as_tensor(std, dtype=dtype)
    return (torch.as_tensor(np.asarray(obs_m), dtype=dtype) - mean) / std


def _score(reward_fn, obs_m, mean, std, dtype=torch.float32):
    """(reward, pos_err, ang_err) of poses in metres, as float64 numpy arrays."""
    m, s = torch.as_tensor(mean, dtype=dtype), torch.as_tensor(std, dtype=dtype)
    with torch.no_grad():
        out = reward_fn(to_norm(obs_m, mean, std, dtype), m, s)
    return tuple(np.asarray(o.detach().cpu().double()) for o in out)


def poses(tee_xy, yaw, pusher_xy) -> np.ndarray:
    """Observations (..., 6) in metres for T centres ``tee_xy`` (..., 2) and yaws (...) (rad)."""
    tee_xy, yaw = np.asarray(tee_xy, dtype=float), np.asarray(yaw, dtype=float)
    obs = np.zeros(np.broadcast_shapes(tee_xy.shape[:-1], yaw.shape) + (6,))
    obs[..., 0:2] = pusher_xy
    obs[..., 2:4] = tee_xy
    obs[..., 4], obs[..., 5] = np.sin(yaw), np.cos(yaw)
    return obs


# --- the shape of the reward ------------------------------------------------------------------
def radial_profile(reward_fn, mean, std, pusher_xy, n_dirs: int = 8, max_dist: float = 0.3,
                   n: int = 31, dtype=torch.float32):
    """Reward along ``n_dirs`` rays from the target (yaw 0): distances (n,) m, rewards (n_dirs, n)."""
    d = np.linspace(0.0, max_dist, n)
    a = 2 * np.pi * np.arange(n_dirs) / n_dirs
    xy = d[None, :, None] * np.stack([np.cos(a), np.sin(a)], -1)[:, None, :]     # (n_dirs, n, 2)
    return d, _score(reward_fn, poses(xy, 0.0, pusher_xy), mean, std, dtype)[0]


def cone_verdict(reward_fn, mean, std, pusher_xy, max_dist: float = 0.3) -> dict:
    """Is the reward a cone with its tip on the target (linear in distance, same slope in every
    direction)? Fits a line to the reward along each of 8 rays and compares the misfit, the
    spread of the slopes and the tip's value with the function's own float32 rounding noise."""
    d, r = radial_profile(reward_fn, mean, std, pusher_xy, max_dist=max_dist)
    try:                               # the same poses in float64: the difference is rounding noise
        _, r64 = radial_profile(reward_fn, mean, std, pusher_xy, max_dist=max_dist, dtype=torch.float64)
        noise = float(np.nanmax(np.abs(r - r64)))
    except Exception:  # noqa: BLE001  a function that only takes float32: float32's own resolution
        noise = float(np.finfo(np.float32).eps * max(1.0, np.nanmax(np.abs(r))))
    tol = ROUNDING_MARGIN * max(noise, np.finfo(np.float32).eps)
    A = np.stack([np.ones_like(d), d], 1)                                          # (n, 2)
    coef, *_ = np.linalg.lstsq(A, r.T, rcond=None)                                 # (2, n_dirs)
    fit = (A @ coef).T
    slope = coef[1]                                                                # reward per m
    out = {"slope_per_10cm": float(slope.mean() * 0.1),
           "slope_min": float(slope.min() * 0.1), "slope_max": float(slope.max() * 0.1),
           "misfit": float(np.nanmax(np.abs(r - fit))), "tip": float(np.nanmax(np.abs(r[:, 0]))),
           "noise": noise, "tol": tol, "n_dirs": len(slope), "max_dist": max_dist}
    out["is_cone"] = bool(np.isfinite(r).all() and out["misfit"] <= tol and out["tip"] <= tol
                          and (slope.max() - slope.min()) * max_dist <= tol and slope.mean() < 0)
    return out


def cone_text(c: dict, pre_push_m: float | None = None) -> str:
    """The paragraph under the heat map, from ``cone_verdict`` (and notebook 01's median pre-push
    motion of the dreamed block, metres, if given)."""
    s = (f"Measured on your function along {c['n_dirs']} rays from the target: the reward changes by "
         f"**{c['slope_per_10cm']:+.3f} per 10 cm** of distance (from {c['slope_min']:+.3f} to "
         f"{c['slope_max']:+.3f} across the rays), it is {c['tip']:.1g} on the target, and a straight line "
         f"fits each ray to within {c['misfit']:.1g} (this function's float32 rounding on the same poses: "
         f"{c['noise']:.1g}). ")
    if not c["is_cone"]:
        return s + ("That is **not** a cone with its tip on the target: check your function against the "
                    "contract above before reading on.")
    s += ("So it is a **cone with its tip on the target**: no plateau and no cliff, every centimetre "
          "closer pays the same, in every direction. Convenient for learning, and it means a dream that "
          "moves the block towards the target earns reward for it, whether or not the real block moved.")
    if pre_push_m is not None and np.isfinite(pre_push_m):
        s += (f" Notebook 01 measured the dreamed block moving **{100 * pre_push_m:.1f} cm** (median) before "
              f"the real block was touched: straight at the target, that would be worth "
              f"**{abs(c['slope_per_10cm']) * pre_push_m / 0.1:.3f}** per step.")
    return s


def half_turn(reward_fn, mean, std, pusher_xy, slope_per_10cm: float) -> dict:
    """The reward of a block on the target turned half a turn, the distance an unturned block
    would need for the same reward (from the measured slope), and the reward at the farthest point
    a block can spawn (a corner of the reset box, yaw 0)."""
    r_half = float(_score(reward_fn, poses([0.0, 0.0], np.pi, pusher_xy), mean, std)[0])
    far = float(np.hypot(TEE_RESET_HALF, TEE_RESET_HALF))
    r_far = float(_score(reward_fn, poses([TEE_RESET_HALF, TEE_RESET_HALF], 0.0, pusher_xy), mean, std)[0])
    eq = r_half / slope_per_10cm * 0.1 if slope_per_10cm < 0 else float("nan")
    return {"r_half": r_half, "equivalent_m": eq, "far_m": far, "r_far": r_far}


def yaw_text(h: dict) -> str:
    s = (f"A block sitting on the target but turned half a turn scores **{h['r_half']:.2f}** per step: the "
         f"same as an unturned block **{h['equivalent_m']:.2f} m** away. ")
    if h["r_half"] < h["r_far"]:
        s += (f"That is worse than an unturned block at the farthest point a block can spawn "
              f"({h['far_m']:.2f} m away, {h['r_far']:.2f}): the yaw can cost more than the whole position "
              "term of any start. ")
    else:
        s += (f"An unturned block at the farthest spawn point ({h['far_m']:.2f} m away) scores "
              f"{h['r_far']:.2f}, no better. ")
    return s + ("And the yaw is read from two decoded numbers, `sin` and `cos`, that the model has to keep "
                "consistent (how consistent it keeps them is measured below).")


# --- scoring decoded frames -------------------------------------------------------------------
def reward_views(reward_fn, mean, std, norm_obs, recon, dream) -> dict:
    """Score true normalised frames (N, T+1, 6), their filtered reconstructions (N, T+1, 6) and an
    open-loop dream (N, K, 6) of the last K frames. Returns numpy (reward, pos_err, ang_err)
    triples under ``true``, ``recon`` and ``dream``."""
    out = {}
    with torch.no_grad():
        for name, x in (("true", norm_obs), ("recon", recon), ("dream", dream)):
            out[name] = tuple(np.asarray(o.detach().cpu().double()) for o in reward_fn(x, mean, std))
    return out


def reward_errors(views: dict) -> dict:
    """Per-sequence, per-dreamed-step errors (N, K) of the reward read off decoded frames: the
    filtered reconstruction's, the dream's and copy-last's (the true reward at the frame the dream
    started from, held), each minus the true reward; and the dream's absolute errors of the block's
    distance to the target (m) and of its |yaw error| (degrees)."""
    tr, tp, ta = views["true"]
    dr, dp, da = views["dream"]
    K = dr.shape[1]
    start = tr.shape[1] - K - 1                                   # the frame the dream started from
    return {"recon": views["recon"][0][:, -K:] - tr[:, -K:], "dream": dr - tr[:, -K:],
            "copy": tr[:, start:start + 1] - tr[:, -K:],
            "pos": np.abs(dp - tp[:, -K:]), "ang_deg": np.degrees(np.abs(da - ta[:, -K:]))}


def error_summary(e: dict) -> dict:
    """The numbers of the paragraph under the error figure. ``sign`` is 'higher' or 'lower' when
    the dream's mean signed error lies more than SE_BAND standard errors from zero (the standard
    error of the mean of the per-sequence mean errors), else 'neither'."""
    per_seq = e["dream"].mean(1)
    n = len(per_seq)
    se = float(per_seq.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan")
    signed = float(per_seq.mean())
    sign = ("higher" if signed > SE_BAND * se else "lower" if signed < -SE_BAND * se else "neither") \
        if np.isfinite(se) else "neither"
    abs_copy = float(np.abs(e["copy"]).mean())
    # Reading frames against dreaming them, paired per sequence: each sequence's mean |error| of
    # the dream minus that of the reconstruction, and its standard error over the sequences.
    paired = np.abs(e["dream"]).mean(1) - np.abs(e["recon"]).mean(1)
    paired_se = float(paired.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan")
    worse = bool(np.isfinite(paired_se) and paired.mean() > SE_BAND * paired_se)
    return {"n": n, "steps": e["dream"].shape[1],
            "recon_abs": float(np.abs(e["recon"]).mean()), "dream_abs": float(np.abs(e["dream"]).mean()),
            "dream_abs_last": float(np.abs(e["dream"][:, -1]).mean()), "copy_abs": abs_copy,
            "pos_last_m": float(e["pos"][:, -1].mean()), "ang_last_deg": float(e["ang_deg"][:, -1].mean()),
            "signed": signed, "se": se, "sign": sign, "dream_worse": worse,
            "paired": float(paired.mean()), "paired_se": paired_se,
            "share_of_change": float(np.abs(e["dream"]).mean() / abs_copy) if abs_copy > 0 else float("nan")}


def unit_circle(dream_m) -> tuple[float, float]:
    """Smallest and largest length of the dreamed (sin, cos) pairs (1 on the unit circle)."""
    length = np.hypot(np.asarray(dream_m)[..., 4], np.asarray(dream_m)[..., 5])
    return float(length.min()), float(length.max())


def error_text(s: dict, circle: tuple[float, float], dt: float = CONTROL_DT) -> str:
    ratio = s["dream_abs"] / s["recon_abs"] if s["recon_abs"] > 0 else float("inf")
    out = (f"Averaged over {s['n']} held-out sequences, the filtered reconstruction's reward is off by "
           f"**{s['recon_abs']:.3f}** per step, the open-loop dream's by **{s['dream_abs']:.3f}** "
           f"({ratio:.1f}x as much), and by **{s['dream_abs_last']:.3f}** after {s['steps']} dreamed steps "
           f"({s['steps'] * dt:.1f} s). ")
    if s["dream_worse"]:
        out += (f"With the frames in front of it the model reads the block better than it dreams it: the "
                f"dream's error is larger by {s['paired']:.3f} per step, more than {SE_BAND:.0f} standard "
                f"errors ({s['paired_se']:.3f}) from zero. ")
    else:
        out += (f"These sequences do not show the dream's error to be larger than the reconstruction's "
                f"(difference {s['paired']:+.3f} per step, standard error {s['paired_se']:.3f}). ")
    out += (f"By the end of the dream the block's distance to the target is off by **{100 * s['pos_last_m']:.1f} "
            f"cm** on average and its yaw error by **{s['ang_last_deg']:.0f} degrees**; the dreamed (sin, cos) "
            f"pairs have lengths from {circle[0]:.2f} to {circle[1]:.2f} (1 on the unit circle). ")
    if s["sign"] == "neither":
        out += (f"On average the dream's reward is {s['signed']:+.3f} per step from the truth, within "
                f"{SE_BAND:.0f} standard errors of zero (one standard error over these sequences: "
                f"{s['se']:.3f}): they do not show it rosier or gloomier on average. ")
    else:
        out += (f"On average the dream's reward is **{s['sign']}** than the truth, by **{abs(s['signed']):.3f}** "
                f"per step, more than {SE_BAND:.0f} standard errors from zero (one standard error: "
                f"{s['se']:.3f}). ")
    out += (f"Over the same steps the true reward itself changed by **{s['copy_abs']:.3f}** per step on "
            f"average (copy-last's error): the dream's error is **{s['share_of_change']:.0%}** of the "
            "change it is trying to predict.")
    return out


def carry_forward_text(s: dict) -> str:
    """The closing points of notebook 02, from ``error_summary``."""
    if s["sign"] == "neither":
        sign = (f"under the expert's actions the dream's reward errors roughly cancel on average (signed mean "
                f"{s['signed']:+.3f} per step, within noise), but an optimiser does not average: it looks for "
                "the states where the dream is wrong in its favour.")
    elif s["sign"] == "higher":
        sign = (f"under the expert's actions the dream's reward is already rosier than the truth on average "
                f"(by {s['signed']:+.3f} per step), and an optimiser will look for the states where it is "
                "rosier still.")
    else:
        sign = (f"under the expert's actions the dream's reward is gloomier than the truth on average "
                f"(by {s['signed']:+.3f} per step), but an optimiser does not average: it looks for the "
                "states where the dream is wrong in its favour.")
    return (f"* These errors ({s['dream_abs']:.3f} per step on average) were measured under the **expert's** "
            f"actions, the kind the model was trained on. An actor learning in the dream is bound to no such "
            f"actions. And {sign}\n"
            f"* The reward is a fixed formula; the **state** it reads is not exact. Read off the filtered "
            f"reconstruction it errs by {s['recon_abs']:.3f} per step, off the dream by {s['dream_abs']:.3f}. "
            "A learned reward head would read the same imagined state, so it would inherit the same error: "
            "any gap between the dream and reality from here on comes from the world model's picture of "
            "the block.")


def recap_text(v: dict) -> str:
    """Notebook 01's verdict, re-measured on this run (``world_model.copy_last_verdict``)."""
    one = v["one"]
    ties = v.get("block_one_ties", [])
    tie = f" (ties on {_count(ties)})" if ties else ""
    return (f"Notebook 01's measurement, on this run: one step ahead the model's error is "
            f"{one[0]:.2f}x and {one[1]:.2f}x copy-last's on the pusher, and it loses to copy-last on "
            f"**{_count(v['block_one_losses'])}** block dimensions{tie}. The block is exactly what the "
            "reward looks at.")


# --- figures ----------------------------------------------------------------------------------
@figure
def fig_reward_heatmap(reward_fn, mean, std, pusher_xy, n: int = 201):
    """The reward per step over the block's centre (yaw 0) across the arena."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Rectangle

    xs = np.linspace(-ARENA_HALF, ARENA_HALF, n)
    gx, gy = np.meshgrid(xs, xs)                                              # (n, n), metres
    heat = _score(reward_fn, poses(np.stack([gx, gy], -1), 0.0, pusher_xy), mean, std)[0]
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    im = ax.imshow(heat, origin="lower", extent=(-ARENA_HALF, ARENA_HALF, -ARENA_HALF, ARENA_HALF),
                   cmap="viridis")
    levels = [v for v in (-0.6, -0.5, -0.4, -0.3, -0.2) if np.nanmin(heat) < v < np.nanmax(heat)]
    if levels:
        cs = ax.contour(gx, gy, heat, levels=levels, colors="white", linewidths=0.7)
        ax.clabel(cs, fmt="%.1f", fontsize=8)
    for i, box in enumerate(tee_outline((0.0, 0.0, 0.0))):
        ax.add_patch(Polygon(box, closed=True, fill=False, ls="--", lw=1.4, ec="w",
                             label="target pose" if i == 0 else None))
    ax.plot(0, 0, "+", color="red", ms=12, mew=2, label="target centre")
    ax.add_patch(Rectangle((-TEE_RESET_HALF, -TEE_RESET_HALF), 2 * TEE_RESET_HALF, 2 * TEE_RESET_HALF,
                           fill=False, ls=":", lw=1.4, ec="orange", label="where episodes spawn the block"))
    ax.set_xlabel("block centre x (m)")
    ax.set_ylabel("block centre y (m)")
    ax.set_title("Reward per step over block position (yaw 0)")
    ax.legend(loc="lower left", fontsize=8, framealpha=0.8)
    fig.colorbar(im, ax=ax, label="reward per step (white rings: equal reward)")
    fig.tight_layout()
    return fig


@figure
def fig_reward_yaw(reward_fn, mean, std, pusher_xy, spawn_dist: float):
    """The reward per step against the block's yaw, on the target and ``spawn_dist`` m along x."""
    import matplotlib.pyplot as plt

    yaw = np.linspace(-np.pi, np.pi, 361)
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for dist, style, label in ((0.0, "-", "block centre on the target"),
                               (spawn_dist, "--", f"block centre {spawn_dist:.2f} m away (mean spawn distance)")):
        xy = np.stack([np.full_like(yaw, dist), np.zeros_like(yaw)], -1)
        ax.plot(np.degrees(yaw), _score(reward_fn, poses(xy, yaw, pusher_xy), mean, std)[0], style, lw=2,
                label=label)
    ax.axvspan(-np.degrees(SUCCESS_ANG), np.degrees(SUCCESS_ANG), color=TARGET_COLOR, alpha=0.2,
               label=(f"success needs |yaw| < {np.degrees(SUCCESS_ANG):.0f} deg "
                      f"(and < {100 * SUCCESS_POS:.0f} cm)"))
    ax.set_xticks(np.arange(-180, 181, 45))
    ax.set_xlabel("block yaw relative to the target (degrees)")
    ax.set_ylabel("reward per step")
    ax.set_title("Reward per step against the block's yaw error")
    ax.legend(fontsize=8, loc="lower center")
    fig.tight_layout()
    return fig


@figure
def fig_reward_one_sequence(views: dict, i: int, moved: float, context: int, dt: float = CONTROL_DT):
    """Reward, block distance and yaw error of sequence ``i``, read off the true frames, the
    filtered reconstruction and the open-loop dream (``reward_views``)."""
    import matplotlib.pyplot as plt

    n_frames, K = views["true"][0].shape[1], views["dream"][0].shape[1]
    t_all = np.arange(n_frames) * dt
    t_dream = t_all[-K:]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), sharex=True)
    panels = (("reward per step", "reward per step", 0, 1.0),
              ("block-to-target distance", "distance (m)", 1, 1.0),
              ("block yaw error", "|yaw error| (degrees)", 2, 180 / np.pi))
    for ax, (title, ylabel, j, k) in zip(axes, panels):
        ax.plot(t_all, k * views["true"][j][i], "k-", lw=2, label="true frames")
        ax.plot(t_all, k * views["recon"][j][i], ":", color="tab:blue", lw=2, label="filtered reconstruction")
        ax.plot(t_dream, k * views["dream"][j][i], "--", color="tab:red", lw=2, label="open-loop dream")
        ax.axvline(context * dt, color="gray", lw=0.8, ls=":")
        ax.set_title(title)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(ylabel)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"Held-out sequence {i} (block moved {moved:.3f} m), scored on true and on decoded "
                 "frames; the dream starts at the dotted line")
    fig.tight_layout()
    return fig


@figure
def fig_final_pose(true_end, dream_end, i: int, t_end: float):
    """The true and the dreamed state (metres) at the end of sequence ``i``, one arena."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.8, 4.8))
    setup_arena(ax, f"sequence {i} at t = {t_end:.1f} s: truth and dream")
    draw_state(ax, true_end, label="true T-block")
    draw_state(ax, dream_end, target=False, alpha=0.5, tee_color="tab:red", pusher_color="tab:red",
               label="dreamed T-block and pusher")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_reward_error(e: dict, t_dream):
    """Signed and absolute error of the reward read off decoded frames, over dreamed time, for
    the reconstruction, the dream and copy-last (``reward_errors``)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8), sharex=True)
    for key, name, style, color in (("recon", "filtered reconstruction", ":", "tab:blue"),
                                    ("dream", "open-loop dream", "--", "tab:red"),
                                    ("copy", "copy-last (block frozen since the dream began)", "-", "gray")):
        x = e[key]
        axes[0].plot(t_dream, x.mean(0), style, color=color, lw=2, label=name)
        axes[0].fill_between(t_dream, np.percentile(x, 25, axis=0), np.percentile(x, 75, axis=0),
                             color=color, alpha=0.12)
        axes[1].plot(t_dream, np.abs(x).mean(0), style, color=color, lw=2, label=name)
    axes[0].axhline(0, color="k", lw=0.8)
    axes[0].set_title("Signed error (mean, band = middle 50% of sequences)")
    axes[0].set_ylabel("model reward - true reward\n(reward per step; > 0: rosier)")
    axes[1].set_title("Size of the error (mean over sequences)")
    axes[1].set_ylabel("|model reward - true reward|\n(reward per step)")
    for ax in axes:
        ax.set_xlabel("time (s)")
        ax.legend(fontsize=8)
    fig.suptitle(f"Reward read off decoded frames vs true frames, {len(e['dream'])} held-out expert sequences")
    fig.tight_layout()
    return fig


# --- self-checks --------------------------------------------------------------------------------
SELF_CHECKS = self_checks("02_reward")  # the words: pusht/nb/text/02_reward.md
