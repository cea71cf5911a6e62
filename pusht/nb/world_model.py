"""Notebook 01's figures, the conclusions its prose draws, and its self-check questions.

Figures (each returns a ``matplotlib`` Figure; the notebook shows it and saves it):

    fig_starts               three random PushT starts                       01_starts.png
    fig_expert               one expert episode                              01_expert.png
    fig_losses               the world model's two training losses           01_wm_losses.png
    fig_copy_last            model error / copy-last error, per dimension    01_copy_last.png
    fig_dream_vs_true        one held-out sequence, dreamed and true         01_dream_vs_true.png

Conclusions (numbers, booleans and the sentences built from them): what moves in the data
(``motion_shares``), how the model compares with copy-last (``copy_last_verdict``), and what the
dreamed block does before the real one is first pushed (``pre_push_motion``,
``open_loop_by_contact``). Every threshold is measured or derived from a measurement, and the
comment beside it says how.
"""

from __future__ import annotations

import numpy as np
import torch

from ..draw import draw_state, setup_arena
from ..env import CONTROL_DT, MAX_STEPS, OBS_NAMES, PushTEnv
from . import figure
from .prose import self_checks

PUSHER, BLOCK_XY, BLOCK = slice(0, 2), slice(2, 4), slice(2, 6)

# A transition "moves" the block (or the pusher) when its centre travels more than this in one
# 0.1 s step. Why 1 mm: an untouched block does not creep at all in this sim (``resting_jitter``
# measures it: exactly 0 m, because the sim wipes every velocity each substep), so any threshold
# above 0 separates resting from pushed steps. Little falls near it: at the default config, seed
# 0, only 9 of the 4,800 training transitions moved the block between 1 micrometre and 1 mm
# (measured), and the notebook shows the share at both thresholds. 1 mm is also the threshold of
# ``prediction_error_vs_copy_last``'s ``block_moving_fraction``, so the two numbers agree.
MOVE_THRESHOLD = 1e-3          # m per step
FINE_THRESHOLD = 1e-6          # m per step: the sensitivity check's lower end


# --- what moves in the data -------------------------------------------------------------------
def resting_jitter(n_starts: int = 20, steps: int = 10, seed0: int = 0) -> float:
    """Largest per-step displacement (m) of an untouched block: ``n_starts`` random starts (the
    reset leaves the pusher clear of the T), each held under a zero command for ``steps`` steps."""
    env, worst = PushTEnv(), 0.0
    for s in range(seed0, seed0 + n_starts):
        prev = env.reset(s)
        for _ in range(steps):
            obs, *_ = env.step(np.zeros(2))
            worst = max(worst, float(np.linalg.norm(obs[BLOCK_XY] - prev[BLOCK_XY])))
            prev = obs
    return worst


def step_lengths(obs: np.ndarray, dims=BLOCK_XY) -> np.ndarray:
    """(N, T+1, 6) observations in metres -> (N, T) distance travelled per step by ``dims``."""
    obs = np.asarray(obs)
    return np.linalg.norm(np.diff(obs[..., dims], axis=-2), axis=-1)


def moving_share(obs: np.ndarray, threshold: float = MOVE_THRESHOLD, dims=BLOCK_XY) -> float:
    """Share of transitions in which ``dims`` (default: the block's centre) move more than
    ``threshold`` metres."""
    return float((step_lengths(obs, dims) > threshold).mean())


def motion_shares(train_obs, val_obs, jitter: float) -> dict:
    """The numbers behind "what does the expert data show?": shares of transitions in which the
    block and the pusher move, on the training and the held-out sequences, at MOVE_THRESHOLD and
    (block only) at FINE_THRESHOLD, plus the measured resting jitter."""
    return {"jitter": float(jitter), "threshold": MOVE_THRESHOLD, "fine": FINE_THRESHOLD,
            "n_train": int(step_lengths(train_obs).size),
            "block_train": moving_share(train_obs), "block_val": moving_share(val_obs),
            "block_train_fine": moving_share(train_obs, FINE_THRESHOLD),
            "block_val_fine": moving_share(val_obs, FINE_THRESHOLD),
            "pusher_train": moving_share(train_obs, dims=PUSHER),
            "pusher_val": moving_share(val_obs, dims=PUSHER)}


def threshold_insensitive(s: dict) -> bool:
    """Do the block's training shares at the two thresholds agree to within their sampling noise
    (two standard errors of a share, sqrt(p (1 - p) / n), over the ``n_train`` transitions)?"""
    p, n = s["block_train"], max(s["n_train"], 1)
    return abs(s["block_train_fine"] - p) <= 2 * np.sqrt(max(p * (1 - p), 1e-12) / n)


def motion_text(s: dict) -> str:
    """The sentence notebook 01 renders from ``motion_shares``."""
    rest = 1 - s["block_train_fine"]
    if s["jitter"] < s["threshold"]:
        most = "exactly 0 m" if s["jitter"] == 0 else f"at most {s['jitter']:.1g} m"
        still = (f"Measured: an untouched block moved **{most}** per step under a zero command, so a block "
                 "moves only when it is pushed.")
    else:
        still = (f"Measured: an untouched block moved up to **{1000 * s['jitter']:.1f} mm** in one step "
                 f"under a zero command, at or above the {1000 * s['threshold']:.0f} mm threshold below: "
                 "the counts that follow mix resting jitter with pushes.")
    return (
        f"{still} In the training sequences the block moves "
        f"(more than {1000 * s['threshold']:.0f} mm) in **{s['block_train']:.0%}** of transitions and "
        f"the pusher in **{s['pusher_train']:.0%}**; on the held-out sequences **{s['block_val']:.0%}** "
        f"and **{s['pusher_val']:.0%}**. With a {1e6 * s['fine']:.0f} micrometre threshold instead the "
        f"block's shares are {s['block_train_fine']:.0%} and {s['block_val_fine']:.0%}: the count does "
        f"{'not' if threshold_insensitive(s) else 'clearly'} hinge on the threshold. So in "
        f"**{rest:.0%}** of the training transitions the block moves {1e6 * s['fine']:.0f} micrometre or "
        "less, and there copy-last (\"the next frame equals this one\") is right to within that.")


def expert_success(n: int = 20, seed0: int = 10, max_steps: int | None = None) -> dict:
    """Run the scripted expert from ``n`` fresh random starts (seeds ``seed0 ...``), all in
    lockstep. Returns ``successes``, ``n`` and ``steps`` (steps to success, per start, -1 if it did
    not succeed within ``max_steps``, the env's 300 by default)."""
    from ..expert import ScriptedExpert

    envs = [PushTEnv() if max_steps is None else PushTEnv(max_steps) for _ in range(n)]
    obs = np.array([env.reset(s) for env, s in zip(envs, range(seed0, seed0 + n))])
    expert, steps, live = ScriptedExpert(n), np.full(n, -1), np.ones(n, dtype=bool)
    while live.any():
        a = expert.act(obs)
        for i in np.flatnonzero(live):
            obs[i], _, done, info = envs[i].step(a[i])
            if done:
                live[i] = False
                steps[i] = info["steps"] if info["success"] else -1
    return {"successes": int((steps > 0).sum()), "n": n, "steps": steps}


# --- the model against copy-last --------------------------------------------------------------
# A model "wins" or "loses" a dimension only when its ratio to copy-last lies more than this many
# bootstrap standard errors from 1 (``copy_last_noise``: the held-out sequences resampled with
# replacement); closer than that, these sequences cannot tell the two apart and it is a tie.
SE_BAND = 2.0


@torch.no_grad()
def per_sequence_errors(wm, norm_obs, act, context: int) -> dict:
    """Per-sequence sums of squared errors (N, D), normalised units, of the two predictions
    ``prediction_error_vs_copy_last`` measures: one step (``one_model``, ``one_copy``) and open
    loop after ``context`` + 1 filtered frames (``open_model``, ``open_copy``)."""
    h, _ = wm.filter(norm_obs, act)
    pred = wm.decode(h[:, 1:], wm.prior(h[:, 1:]))                          # (N, T, D)
    dream = open_loop_dream(wm, norm_obs, act, context)[:, 1:]              # frames context+1..T
    target = norm_obs[:, context + 1:]

    def sq(a, b):
        return ((a - b) ** 2).sum(1).cpu().double().numpy()                 # (N, D)

    return {"one_model": sq(pred, norm_obs[:, 1:]), "one_copy": sq(norm_obs[:, :-1], norm_obs[:, 1:]),
            "open_model": sq(dream, target), "open_copy": sq(norm_obs[:, context:context + 1], target)}


def ratio_se(sq_model, sq_copy, n_boot: int = 500, seed: int = 0) -> np.ndarray:
    """Bootstrap standard error (D,) of the RMSE ratio sqrt(sum sq_model / sum sq_copy), resampling
    the N sequences (rows) with replacement."""
    sq_model, sq_copy = np.asarray(sq_model), np.asarray(sq_copy)
    n = len(sq_model)
    if n < 2:
        return np.full(sq_model.shape[1], np.nan)
    idx = np.random.default_rng(seed).integers(0, n, (n_boot, n))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.sqrt(sq_model[idx].sum(1) / sq_copy[idx].sum(1))        # (n_boot, D)
    return np.nanstd(ratios, axis=0, ddof=1)


def copy_last_noise(wm, norm_obs, act, context: int) -> dict:
    """Bootstrap standard errors (D,) of the one-step and open-loop ratios, and the ratios
    themselves recomputed per sequence (they equal ``prediction_error_vs_copy_last``'s)."""
    e = per_sequence_errors(wm, norm_obs, act, context)
    return {"one": ratio_se(e["one_model"], e["one_copy"]), "open": ratio_se(e["open_model"], e["open_copy"]),
            "one_ratio": np.sqrt(e["one_model"].sum(0) / e["one_copy"].sum(0)),
            "open_ratio": np.sqrt(e["open_model"].sum(0) / e["open_copy"].sum(0)), "n": len(e["one_model"])}


def copy_last_verdict(error: dict, se: dict | None = None) -> dict:
    """Ratios model / copy-last (per dimension, one step and open loop) from
    ``prediction_error_vs_copy_last``, and which dimensions the model wins, loses and ties.

    With ``se`` (``copy_last_noise``) a ratio is a win below 1 - SE_BAND * se, a loss above
    1 + SE_BAND * se and a tie in between; without it, a win below 1 and a loss from 1 up."""
    one = np.asarray(error["one_step_model"]) / np.asarray(error["one_step_copy"])
    open_ = np.asarray(error["open_loop_model"]) / np.asarray(error["open_loop_copy"])
    names = np.array(OBS_NAMES)
    out = {"one": one, "open": open_, "se": se, "n": None if se is None else se.get("n")}
    for part, dims in (("pusher", PUSHER), ("block", BLOCK)):       # the raw comparison, noise aside
        out[f"{part}_one_above"] = names[dims][one[dims] > 1].tolist()
        out[f"{part}_open_below"] = names[dims][open_[dims] < 1].tolist()
    for kind, r in (("one", one), ("open", open_)):
        band = 0.0 if se is None else SE_BAND * np.nan_to_num(np.asarray(se[kind]), nan=np.inf)
        win, loss = r < 1 - band, (r > 1 + band) if se is not None else (r >= 1)
        for part, dims in (("pusher", PUSHER), ("block", BLOCK)):
            out[f"{part}_{kind}_wins"] = names[dims][win[dims]].tolist()
            out[f"{part}_{kind}_losses"] = names[dims][loss[dims]].tolist()
            out[f"{part}_{kind}_ties"] = names[dims][~(win | loss)[dims]].tolist()
    return out


def _count(names, of=4) -> str:
    if not names:
        return f"none of the {of}"
    if len(names) == of:
        return f"all {of}"
    return f"{len(names)} of {of} ({', '.join(names)})"


def _ratios(v, kind, dims) -> str:
    r = v[kind][dims]
    if v["se"] is None:
        return ", ".join(f"{x:.2f}" for x in r)
    return ", ".join(f"{x:.2f} ± {s:.2f}" for x, s in zip(r, np.asarray(v["se"][kind])[dims]))


def _beyond(v, names, of) -> str:
    """', by more than SE_BAND standard errors on ...' (nothing without noise estimates)."""
    if v["se"] is None:
        return ""
    return f"; by more than {SE_BAND:.0f} standard errors on **{_count(names, of)}**"


def copy_last_text(v: dict, open_steps: int) -> str:
    """The paragraph under the bar chart, built from ``copy_last_verdict`` (with noise estimates,
    each count is given twice: the raw comparison with 1, and the part of it beyond the noise)."""
    n_pw = len(v["pusher_one_wins"])
    pusher = (f"On the pusher the model's one-step error is **{_ratios(v, 'one', PUSHER)}** times "
              f"copy-last's: it " + ("wins on both" if n_pw == 2 else "wins on one" if n_pw == 1
                                      else "wins on neither")
              + (f" by more than {SE_BAND:.0f} standard errors" if v["se"] is not None else "") + ". ")
    above, losses = v["block_one_above"], v["block_one_losses"]
    below, wins = v["block_open_below"], v["block_open_wins"]
    block = (f"On the block, one step ahead, copy-last is the better predictor (ratio above 1) on "
             f"**{_count(above)}** dimensions{_beyond(v, losses, 4)} (ratios {_ratios(v, 'one', BLOCK)}). ")
    block += (f"Dreaming open loop for {open_steps} steps, the model is the better one (ratio below 1) on "
              f"**{_count(below)}** block dimensions{_beyond(v, wins, 4)} (ratios {_ratios(v, 'open', BLOCK)}).")
    if v["se"] is not None:
        block += (f" Each ratio is shown ± one bootstrap standard error over the {v['n']} held-out sequences; "
                  "closer to 1 than two of those, these sequences cannot tell the model from copy-last.")
    if losses and wins:
        block += (" So the model is worse one step ahead yet better over a whole dream: the dream below "
                  "shows how that can happen.")
    elif above and below:
        qual = " (on these sequences, not beyond the noise)" if v["se"] is not None and not wins else ""
        block += (f" Worse one step ahead, yet better on some dimensions over a whole dream{qual}: the "
                  "dream below shows where the model's error comes from.")
    return pusher + block


# --- a dream next to the truth ----------------------------------------------------------------
@torch.no_grad()
def open_loop_dream(wm, norm_obs, act, context: int) -> torch.Tensor:
    """Filter ``context`` + 1 real frames, then dream the rest of each sequence under the true
    actions with no frames. ``norm_obs`` (N, T+1, 6) and ``act`` (N, T, 2) are normalised tensors;
    returns the decoded normalised frames ``context .. T``: (N, T - context + 1, 6)."""
    h, z = wm.warm(norm_obs[:, : context + 1], act[:, :context])
    frames = [wm.decode(h, z)]
    for t in range(context, act.shape[1]):
        h, z, o = wm.step(h, z, act[:, t])
        frames.append(o)
    return torch.stack(frames, 1)


def most_moving(val_obs) -> tuple[int, float]:
    """The held-out sequence whose block ends farthest from where it started: (index, metres)."""
    moved = np.linalg.norm(np.asarray(val_obs)[:, -1, BLOCK_XY] - np.asarray(val_obs)[:, 0, BLOCK_XY], axis=-1)
    i = int(moved.argmax())
    return i, float(moved[i])


def first_push(obs, threshold: float = MOVE_THRESHOLD) -> np.ndarray:
    """(N, T+1, 6) metres -> (N,) index of the first transition in which the block moves (the
    pusher's first touch happens during it; frames 0..k all show the block at rest); T if never."""
    moving = step_lengths(obs) > threshold
    return np.where(moving.any(-1), moving.argmax(-1), moving.shape[-1])


def pre_push_motion(true_obs, dream_obs, context: int) -> dict:
    """How far the dreamed block moves while the real block still sits untouched.

    ``true_obs`` (N, T+1, 6) and ``dream_obs`` (N, T - context + 1, 6), metres (the dream covers
    frames ``context .. T``). For every sequence whose first push comes after the dream starts,
    ``moved`` is the largest distance (m) of the dreamed block's centre from its first dreamed
    position over the frames before that push (while the real block moved less than
    ``MOVE_THRESHOLD`` in every step). Sequences never pushed within T count with all their frames.
    """
    first = first_push(true_obs)
    moved, idx = [], []
    for n, k in enumerate(first):
        if k <= context:                    # pushed before the dream began: nothing to compare
            continue
        block = dream_obs[n, : k - context + 1, BLOCK_XY]
        moved.append(float(np.linalg.norm(block - block[0], axis=-1).max()))
        idx.append(n)
    moved = np.array(moved)
    return {"moved": moved, "index": np.array(idx, dtype=int), "first": first,
            "n": len(moved), "of": len(first),
            "mean": float(moved.mean()) if len(moved) else float("nan"),
            "median": float(np.median(moved)) if len(moved) else float("nan")}


def decode_noise(wm, norm_obs, act, std) -> float:
    """RMSE (m) of the block's centre decoded from filtered states, the model seeing every frame:
    how far a decoded block position sits from the truth with no dreaming at all."""
    with torch.no_grad():
        h, z = wm.filter(norm_obs, act)
        err = (wm.decode(h, z) - norm_obs)[..., BLOCK_XY] * norm_obs.new_tensor(np.asarray(std))[BLOCK_XY]
    return float(err.pow(2).sum(-1).mean().sqrt())


def dream_moves_before_contact(pre: dict, noise: float) -> bool:
    """Does the dreamed block move before the real one is touched? Yes when the median pre-push
    motion exceeds twice the decoding noise (``decode_noise``): a wobble of the decoded position
    that size is what the model shows even with the real frame in front of it."""
    return bool(pre["n"] > 0 and pre["median"] > 2 * noise)


def open_loop_by_contact(true_obs, dream_obs, context: int) -> dict:
    """Open-loop error of the block's centre (RMSE, m) split at each sequence's first push: on
    dreamed frames before it (the real block at rest) and from it on, for the model and for
    copy-last (which holds the frame the dream started from). A side with no frames gives nan."""
    first = first_push(true_obs)
    target = np.asarray(true_obs)[:, context:, BLOCK_XY]                 # (N, K, 2), frames context..T
    model = np.linalg.norm(np.asarray(dream_obs)[..., BLOCK_XY] - target, axis=-1)
    copy = np.linalg.norm(target[:, :1] - target, axis=-1)
    frame = np.arange(context, context + target.shape[1])
    before = frame[None, :] <= first[:, None]                           # frames with the block at rest
    before[:, 0] = False                                                 # the dream's own start frame

    def rmse(e, mask):
        return float(np.sqrt((e[mask] ** 2).mean())) if mask.any() else float("nan")

    after = ~before
    after[:, 0] = False
    return {"model_before": rmse(model, before), "copy_before": rmse(copy, before),
            "model_after": rmse(model, after), "copy_after": rmse(copy, after),
            "frames_before": int(before.sum()), "frames_after": int(after.sum())}


def dream_text(pre: dict, split: dict, noise: float, i: int, first_i: int, context: int,
               dt: float = CONTROL_DT) -> str:
    """The paragraph under the dream figure: what the dreamed block does before contact, and how
    the open-loop error splits at the first push."""
    out = []
    if first_i > context:
        j = np.flatnonzero(pre["index"] == i)
        cm = 100 * pre["moved"][j[0]]
        out.append(f"In sequence {i} the real pusher first pushes the block at **t = {first_i * dt:.1f} s** "
                   f"(the solid grey line); until then the real block has not moved more than "
                   f"{1000 * MOVE_THRESHOLD:.0f} mm in any step, yet the dreamed block has already moved "
                   f"**{cm:.1f} cm**.")
    else:
        out.append(f"In sequence {i} the real pusher pushes the block at t = {first_i * dt:.1f} s, before "
                   "the dream starts, so this one sequence cannot show the dream before contact.")
    if pre["n"]:
        verdict = ("moves before any contact" if dream_moves_before_contact(pre, noise)
                   else "does not move clearly beyond its decoding noise before contact")
        out.append(f" Over the **{pre['n']}** of {pre['of']} held-out sequences whose first push comes after "
                   f"the dream starts, the dreamed block moves **{100 * pre['median']:.1f} cm** (median; mean "
                   f"{100 * pre['mean']:.1f} cm) before the real block is first touched. Even with every real "
                   f"frame in front of it the model decodes the block's centre {100 * noise:.1f} cm from the "
                   f"truth (RMSE), so the dreamed block **{verdict}**.")
    mb, cb, ma, ca = (split[k] for k in ("model_before", "copy_before", "model_after", "copy_after"))
    if np.isfinite(mb) and np.isfinite(ma):
        out.append(f" Split the open-loop block error at the first push: before it, copy-last is exact "
                   f"(RMSE {100 * cb:.1f} cm) and the model is off by **{100 * mb:.1f} cm**; from the push "
                   f"on, copy-last is off by **{100 * ca:.1f} cm** and the model by **{100 * ma:.1f} cm**. "
                   + ("So whatever the model gains on copy-last open loop, it gains after the first push; "
                      "before it, where copy-last is exact, the model can only lose." if ma < ca else
                      "The model does not beat copy-last even after the first push here."))
    return "".join(out)


def carry_forward_text(v: dict, pre: dict, noise: float, shares: dict) -> str:
    """The closing summary of notebook 01, each clause from a measured number."""
    n_pw = len(v["pusher_one_wins"])
    pusher = ("The model learned the pusher: one step ahead it beats copy-last on both pusher coordinates. "
              if n_pw == 2 else "The model did not clearly learn the pusher: one step ahead it does not beat "
              f"copy-last on {2 - n_pw} of 2 pusher coordinates. ")
    losses, wins, below = v["block_one_losses"], v["block_open_wins"], v["block_open_below"]
    noisy = v["se"] is not None
    block = (f"On the block it loses to copy-last one step ahead on {_count(losses)} dimensions"
             + (" (beyond the noise)" if noisy else "") + f"; over a whole dream its error is below copy-last's "
             f"on {_count(below)}" + (f", beyond the noise on {_count(wins)}" if noisy else "") + ". ")
    if dream_moves_before_contact(pre, noise):
        contact = ((("A win over copy-last is not a model of pushing: " if wins else "And ")
                    + f"the dreamed block moves {100 * pre['median']:.1f} cm (median) before the real block "
                    f"is touched, while in the data the block moves in only {shares['block_train']:.0%} of "
                    "transitions, and only when pushed. "))
    else:
        contact = (f"In this run the dreamed block shows no clear motion before contact ({100 * pre['median']:.1f} "
                   f"cm median, against {100 * noise:.1f} cm of decoding error). ")
    return (pusher + block + contact + "In the next notebooks an actor learns to act **inside this model**, "
            "and its reward is read off the block pose the model imagines: hold on to the bar chart and "
            "to the dream above.")


def expert_text(runs: dict, dt: float = CONTROL_DT) -> str:
    """One sentence from ``expert_success``."""
    ok = runs["steps"][runs["steps"] > 0]
    median = f" (median {np.median(ok) * dt:.1f} s to success)" if len(ok) else ""
    return (f"From **{runs['n']}** other random starts the expert succeeded **{runs['successes']}** times "
            f"within an episode's {MAX_STEPS * dt:.0f} s{median}.")


def loss_summary(history: dict, n_updates_per_epoch: int) -> dict:
    """Mean of each training loss over the first and the last epoch's updates (MSEs, unitless)."""
    k = max(1, int(n_updates_per_epoch))
    return {name: (float(np.mean(history[name][:k])), float(np.mean(history[name][-k:])))
            for name in ("recon", "dyn")}


def loss_text(s: dict) -> str:
    def went(a, b):
        return f"{'fell' if b < a else 'rose'} from **{a:.3g}** in the first epoch to **{b:.3g}** in the last"
    return (f"The reconstruction MSE {went(*s['recon'])} (a root-mean-square error of "
            f"{np.sqrt(s['recon'][1]):.2f} standard deviations per observation dimension); the dynamics "
            f"MSE {went(*s['dyn'])}. Both are measured while the model filters real frames: neither is a dream.")


# --- figures ----------------------------------------------------------------------------------
@figure
def fig_starts(seeds=(0, 1, 2)):
    """Random PushT starts ``env.reset(seed)``, one panel each."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(seeds), figsize=(3.7 * len(seeds), 3.8), squeeze=False)
    for ax, seed in zip(axes[0], seeds):
        setup_arena(ax, f"random start, seed {seed}")
        draw_state(ax, PushTEnv().reset(seed))
    axes[0, 0].legend(loc="lower left", fontsize=8)
    fig.suptitle(f"{len(seeds)} random PushT starts (the target pose is dashed)")
    fig.tight_layout()
    return fig


@figure
def fig_expert(obs, actions, success: bool, dt: float = CONTROL_DT):
    """One expert episode: the pusher's path and the T fading in from its start pose."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 5))
    setup_arena(ax, f"one expert episode: {len(actions)} steps ({len(actions) * dt:.1f} s)\n"
                    f"success = {success}")
    for t in np.linspace(0, len(obs) - 1, 5).astype(int):
        draw_state(ax, obs[t], target=(t == 0), alpha=0.25 + 0.75 * t / max(len(obs) - 1, 1),
                   label="T-block (fading in over time)" if t == 0 else "_")
    ax.plot(obs[:, 0], obs[:, 1], "-", color="tab:blue", lw=1, label="pusher path")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_losses(history: dict, n_updates_per_epoch: int | None = None, batch_size: int | None = None):
    """The two world-model losses per update, log scale."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    ax.plot(history["recon"], label="reconstruction: decoded vs true observation\n"
                                    "(each dimension in units of its standard deviation)")
    ax.plot(history["dyn"], label="dynamics: prior vs posterior latent z\n(z in [-1, 1], tanh units)")
    if n_updates_per_epoch:
        for e in range(n_updates_per_epoch, len(history["recon"]), n_updates_per_epoch):
            ax.axvline(e, color="gray", lw=0.3, alpha=0.5)
    ax.set_yscale("log")
    batch = f"one batch of {batch_size} sequences" if batch_size else "one batch of sequences"
    ax.set_xlabel(f"world-model update ({batch}" + ("; faint lines: epochs)" if n_updates_per_epoch else ")"))
    ax.set_ylabel("mean squared error\n(unitless, log scale)")
    ax.set_title("World-model training losses on the training batches (MSE)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_copy_last(error: dict, open_steps: int, se: dict | None = None):
    """Per-dimension held-out RMSE of the model divided by copy-last's, one step and open loop;
    with ``se`` (``copy_last_noise``), error bars of two bootstrap standard errors."""
    import matplotlib.pyplot as plt

    v = copy_last_verdict(error, se)
    x = np.arange(len(OBS_NAMES))
    fig, ax = plt.subplots(figsize=(10, 3.8))
    bars = {} if se is None else {"error_kw": {"lw": 1}, "capsize": 3}
    ax.bar(x - 0.2, v["one"], 0.4, label="one step",
           yerr=None if se is None else SE_BAND * np.asarray(se["one"]), **bars)
    ax.bar(x + 0.2, v["open"], 0.4, label=f"open loop ({open_steps} steps)",
           yerr=None if se is None else SE_BAND * np.asarray(se["open"]), **bars)
    if se is not None:
        ax.plot([], [], "k|", label=f"± {SE_BAND:.0f} bootstrap s.e.")
    ax.axhline(1.0, color="k", ls="--", lw=1, label="copy-last (ratio 1)")
    ax.set_xticks(x, OBS_NAMES)
    reach = [v["one"], v["open"]] if se is None else [v["one"] + SE_BAND * np.nan_to_num(se["one"]),
                                                      v["open"] + SE_BAND * np.nan_to_num(se["open"])]
    top = max(1.1, float(np.nanmax(np.concatenate(reach))) * 1.12)
    ax.set_ylim(0, top)
    ax.axvspan(-0.5, 1.5, color="tab:blue", alpha=0.08)
    ax.text(0.5, top * 0.97, "pusher", ha="center", va="top", color="tab:blue")
    ax.text(3.5, top * 0.97, "T-block", ha="center", va="top", color="dimgray")
    ax.set_xlabel("observation dimension (positions in m, sin/cos unitless)")
    ax.set_ylabel("model RMSE / copy-last RMSE\n(unitless ratio)")
    ax.set_title("Held-out prediction error relative to copy-last (below 1: the model is better)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    return fig


@figure
def fig_dream_vs_true(true, dream, context: int, first_push_step: int, index: int,
                         dt: float = CONTROL_DT):
    """The block's four dimensions over one sequence: true (T+1, 6) and the open-loop dream of
    frames ``context .. T``; lines mark where the dream starts and where the block is first pushed."""
    import matplotlib.pyplot as plt

    T = len(true) - 1
    t_true, t_dream = np.arange(T + 1) * dt, np.arange(context, T + 1) * dt
    moved = float(np.linalg.norm(true[-1, BLOCK_XY] - true[0, BLOCK_XY]))
    fig, axes = plt.subplots(1, 4, figsize=(13, 3.4), sharex=True)
    for ax, d in zip(axes, range(2, 6)):
        ax.plot(t_true, true[:, d], "k-", label="true")
        ax.plot(t_dream, dream[:, d], "--", color="tab:red", label="dream (open loop)")
        ax.axvline(context * dt, color="gray", lw=0.8, ls=":", label="dream starts")
        if first_push_step < T:
            ax.axvline(first_push_step * dt, color="gray", lw=1.2, label="first push (real)")
        ax.set_title(OBS_NAMES[d])
        ax.set_xlabel("time (s)")
        ax.set_ylabel("position (m)" if d < 4 else f"{OBS_NAMES[d]} (unitless)")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"Held-out sequence {index}: the true block moved {moved:.3f} m in all; "
                 "the dream starts at the dotted line")
    fig.tight_layout()
    return fig


# --- self-checks --------------------------------------------------------------------------------
SELF_CHECKS = self_checks("01_world_model")  # the words: pusht/nb/text/01_world_model.md
