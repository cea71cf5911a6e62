# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 02 · Reward without a reward head
#
# An actor that learns inside a dream needs a score for every dreamed step. Real Dreamer learns
# that score with a small network, a *reward head*, because on pixels it has no other way to get
# it. We do not have to: the PushT reward is a simple formula of where the T-block is and how it
# is turned. So we compute it directly from the observation the world model **decodes**.
#
# That choice has a consequence this whole chapter is about. In a dream, the formula reads the
# block pose the model *imagined*, and the block is what notebook 01 measured the model against
# copy-last on (its numbers for this run are recalled below).
#
# In this notebook you will:
#
# 1. write the reward function yourself (it then drives every plot below);
# 2. look at its shape: how it falls off with distance and with the block's turn;
# 3. score held-out expert trajectories twice, on the true frames and on the model's decoded
#    frames, and measure how far the dream's score drifts from the truth.

# %%
# Colab only (elsewhere this does nothing): install this chapter's package, pusht-dreamer, from GitHub,
# next to Colab's own torch and numpy. Should the install ever change those, this cell says so and stops.
import sys

if "google.colab" in sys.modules:
    import json, subprocess, tempfile
    from importlib.metadata import version

    package = "pusht-dreamer @ git+https://github.com/zero2robot/world-models-2-dreamer@main"
    print(f"Installing {package}")
    loaded = {name: version(name) for name in ("torch", "numpy")}   # the versions Colab came with
    report = f"{tempfile.gettempdir()}/pusht-install.json"          # pip writes what it installed here
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--report", report, package],
                   check=True)
    with open(report) as f:
        new = {p["metadata"]["name"].lower(): p["metadata"]["version"] for p in json.load(f)["install"]}
    print("Installed:", ", ".join(f"{name} {v}" for name, v in new.items()) or "nothing new")
    changed = [f"{name} {loaded[name]} -> {new[name]}" for name in loaded
               if name in new and new[name] != loaded[name]]
    if changed:
        print(f"The install replaced Colab's {', '.join(changed)}: Python must restart to use it.")
        raise RuntimeError("Restart the runtime (Runtime > Restart session), then run this notebook again.")
    print(f"Colab's torch {loaded['torch']} and numpy {loaded['numpy']} are unchanged.")

# %% tags=["parameters"]
SEED = 0                    # master seed: data, model init, evaluation starts
SMOKE = False               # True: a tiny config that runs in seconds (used by CI)
DEVICE = "cpu"              # results are recorded on the CPU
OUT = "runs/notebooks"      # figures, and a cache of trained models shared by notebooks 01-05

# %%
import inspect

import numpy as np
import torch
from IPython.display import Code, Markdown, display
from tqdm.auto import tqdm

import pusht.nb.reward as nb02           # this notebook's figures and conclusions
import pusht.nb.world_model as nb01      # notebook 01's, for the dreams
import pusht.reward
from pusht.dreamer import world_model_stage
from pusht.env import ANG_SCALE, CONTROL_DT, POS_SCALE, shaped_reward, wrap_angle
from pusht.nb import setup
from pusht.nb.reward import SELF_CHECKS
from pusht.selfcheck import ask

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT)
print(f"config: seed {cfg.seed}, {cfg.n_episodes} expert sequences of {cfg.seq_len} steps, "
      f"{cfg.wm_epochs} epochs" + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

# %%
from pusht.nb.timing import time_note

time_note("02_reward")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## The world model from notebook 01
#
# This loads the model notebook 01 trained (from the cache in `OUT`), or trains it again if the
# cache is missing, so this notebook also runs on its own. It also dreams every held-out sequence
# open loop once, exactly as notebook 01 did; the dreams are scored further down.

# %%
stage = world_model_stage(cfg, cache_dir=CACHE, model_cache=CACHE, progress=tqdm)
data = stage.data
T = data.torch(cfg.device)
MEAN, STD = T["mean"], T["std"]       # (6,) each: the normalisation every network uses


def to_norm(obs_m):
    """Observations in metres (..., 6) -> the normalised float32 tensor the networks see."""
    return nb02.to_norm(obs_m, MEAN, STD)


dream_all = nb01.open_loop_dream(stage.wm, T["val_obs"], T["val_act"], cfg.context)   # frames context..T
pre = nb01.pre_push_motion(data.val_obs, dream_all.cpu().numpy() * data.std + data.mean, cfg.context)
print("observation mean:", np.round(data.mean, 3))
print("observation std: ", np.round(data.std, 3))
se = nb01.copy_last_noise(stage.wm, T["val_obs"], T["val_act"], cfg.context)
display(Markdown(nb02.recap_text(nb01.copy_last_verdict(stage.error, se))))

# %% [markdown]
# ## Why there is no reward head
#
# The real simulator already defines the reward. Here is its definition, straight from the
# environment: the T's distance to the target (metres) and its turn away from the target yaw
# (radians, wrapped so that a full turn counts as no turn), each divided by a scale and added.

# %%
display(Code(inspect.getsource(wrap_angle) + "\n\n" + inspect.getsource(shaped_reward),
             language="python"))
display(Markdown(
    f"With `POS_SCALE = {POS_SCALE}` m and `ANG_SCALE = {ANG_SCALE:.5f}` rad (pi), the reward is 0 exactly on "
    f"the target. Every 10 cm of distance costs {0.5 * 0.1 / POS_SCALE:.2f} per step, and a block turned half a "
    f"turn loses another {0.5 * np.pi / ANG_SCALE:.2f}."))

# %% [markdown]
# Because the formula is known, a learned reward head could at best reproduce it. The package
# computes the same number from an observation instead, and uses that one function in both
# worlds: on the true frame in the real sim, on the decoded frame in a dream. Here is the
# package's reasoning, from the module's own docstring:

# %%
display(Markdown("\n".join("> " + line for line in pusht.reward.__doc__.strip().splitlines())))


# %% [markdown]
# ## Exercise: the reward of a (normalised) observation
#
# Write `reward_from_obs(norm_obs, mean, std)`, the function that scores every dreamed step from
# here on. Its contract:
#
# **Input.** `norm_obs`, a torch tensor of *normalised* observations, `norm_obs = (obs - mean) / std`,
# with any leading shape and a last dimension of 6, where `obs` (in metres) is
#
# `[agent_x, agent_y, tee_x, tee_y, sin(tee_yaw), cos(tee_yaw)]`;
#
# `mean` and `std` are the two (6,) tensors that normalised it.
#
# **Output.** Three tensors `(reward, pos_err, ang_err)`, each with the leading shape of `norm_obs`:
#
# * `pos_err`: the distance in metres from the T's centre to the target at the origin;
# * `ang_err`: the T's absolute yaw error in radians, in `[0, pi]`, the target yaw being 0. The yaw
#   is the direction of the vector `(cos, sin)`. A decoded observation need not lie on the unit
#   circle (its cosine can even exceed 1): `ang_err` must still be that direction's angle, and
#   finite, for any pair of numbers;
# * `reward = -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE)`, the reward per step.
#
# **Requirements.** The pusher plays no part. The results must be differentiable with respect to
# `norm_obs`, because notebook 03's actor gradient flows through this function. `POS_SCALE` and
# `ANG_SCALE` are already imported.
#
# The test cell after it checks these properties on poses whose answers are known.

# %% nbgrader={"grade": false, "grade_id": "reward_impl", "locked": false, "schema_version": 3, "solution": true}
def reward_from_obs(norm_obs, mean, std):
    """Shaped PushT reward of normalised observations (..., 6).

    Returns (reward, pos_err, ang_err), each of the leading shape: reward per step (0 on the
    target, negative elsewhere), position error in metres, |yaw error| in radians in [0, pi].
    Differentiable in ``norm_obs``.
    """
    ### BEGIN SOLUTION
    obs = norm_obs * std + mean                                      # back to metres
    pos_err = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)
    ang_err = torch.abs(torch.atan2(obs[..., 4], obs[..., 5]))      # atan2 tolerates non-unit pairs
    reward = -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE)
    return reward, pos_err, ang_err
    ### END SOLUTION


# %% nbgrader={"grade": true, "grade_id": "reward_impl_tests", "locked": true, "points": 4, "schema_version": 3, "solution": false}
### BEGIN HIDDEN TESTS
# While grading: record your function's raw results on the grader's cases; the verdict
# is made outside this kernel (autograde/checks.py).
__import__("pusht.grading").grading.submit("reward_impl_tests", reward_from_obs)
### END HIDDEN TESTS
import math


def pose(px, py, tx, ty, yaw):
    """One observation in metres: pusher (px, py), T centre (tx, ty), T yaw (radians)."""
    return [px, py, tx, ty, math.sin(yaw), math.cos(yaw)]


# 1. The target pose scores 0, wherever the pusher is.
r, pos, ang = reward_from_obs(to_norm([pose(0.3, -0.2, 0.0, 0.0, 0.0)]), MEAN, STD)
assert r.shape == (1,), f"for input of shape (1, 6) the reward should have shape (1,), got {tuple(r.shape)}"
assert abs(r.item()) < 1e-5, f"the T on the target should score 0, got {r.item():.4f}"
assert abs(pos.item()) < 1e-5 and abs(ang.item()) < 1e-5, "pos_err and ang_err should be 0 on the target"

# 2. Known poses: 0.5 m away, then a quarter turn and a half turn on the target.
r, pos, ang = reward_from_obs(to_norm([pose(0.0, 0.0, 0.3, 0.4, 0.0)]), MEAN, STD)
assert abs(pos.item() - 0.5) < 1e-4, f"the T at (0.3, 0.4) m is 0.5 m away, got pos_err {pos.item():.4f}"
assert abs(r.item() + 0.5) < 1e-4, (f"0.5 m away and not turned should score -0.5, got {r.item():.4f}; "
                                    "did you de-normalise with obs = norm_obs * std + mean?")
r, pos, ang = reward_from_obs(to_norm([pose(0.0, 0.0, 0.0, 0.0, math.pi / 2)]), MEAN, STD)
assert abs(ang.item() - math.pi / 2) < 1e-4, f"yaw pi/2 should give ang_err pi/2, got {ang.item():.4f}"
assert abs(r.item() + 0.25) < 1e-4, f"a quarter turn on the target should score -0.25, got {r.item():.4f}"
r, pos, ang = reward_from_obs(to_norm([pose(0.0, 0.0, 0.0, 0.0, math.pi)]), MEAN, STD)
assert abs(r.item() + 0.5) < 1e-4, f"a half turn on the target should score -0.5, got {r.item():.4f}"

# 3. Many known poses at once, with a leading shape (3, 5): T centres in a +-0.4 m box, yaws over
#    two full turns either way, pushers anywhere.
g = torch.Generator().manual_seed(0)
xy = (torch.rand(3, 5, 2, generator=g) - 0.5) * 0.8
yaw = (torch.rand(3, 5, generator=g) - 0.5) * 4 * math.pi
obs = torch.cat([torch.rand(3, 5, 2, generator=g) - 0.5, xy, yaw.sin()[..., None], yaw.cos()[..., None]], -1)
r, pos, ang = reward_from_obs(to_norm(obs), MEAN, STD)
for name, a in (("reward", r), ("pos_err", pos), ("ang_err", ang)):
    assert tuple(a.shape) == (3, 5), f"{name}: input (3, 5, 6) should give shape (3, 5), got {tuple(a.shape)}"
assert torch.allclose(pos, xy.norm(dim=-1), atol=1e-4), "pos_err should be the T centre's distance from the origin (m)"
wrapped = torch.remainder(yaw + math.pi, 2 * math.pi) - math.pi
assert torch.allclose(ang, wrapped.abs(), atol=1e-4), \
    "ang_err should be |yaw| wrapped into [0, pi]: a full turn counts as no turn"
assert torch.allclose(r, -0.5 * (pos / POS_SCALE + ang / ANG_SCALE), atol=1e-5), \
    "reward should be -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE)"

# 4. Off the unit circle: only the direction of (cos, sin) counts, not its length.
base = torch.tensor([pose(0.1, 0.1, 0.05, -0.02, y) for y in (0.3, 1.2, 2.5, -0.7, -2.9)])
ang_base = reward_from_obs(to_norm(base), MEAN, STD)[2]
for scale in (0.2, 1.3, 3.0):
    off = base.clone()
    off[:, 4:] *= scale
    ang_off = reward_from_obs(to_norm(off), MEAN, STD)[2]
    assert torch.isfinite(ang_off).all(), f"ang_err must be finite when (sin, cos) has length {scale}"
    assert torch.allclose(ang_off, ang_base, atol=1e-4), \
        (f"scaling (sin, cos) by {scale} changed ang_err: the yaw is the direction of (cos, sin), "
         "whatever its length (a decoded pair need not lie on the unit circle)")

# 5. Differentiable, and blind to the pusher: the gradient reaches the T's dimensions only.
x = torch.randn(4, 6, generator=g, requires_grad=True)
r = reward_from_obs(x, MEAN, STD)[0]
assert isinstance(r, torch.Tensor) and r.requires_grad, \
    ("the reward must be a torch tensor that is differentiable in norm_obs "
     "(no numpy, .item() or torch.no_grad)")
r.sum().backward()
assert x.grad is not None and torch.isfinite(x.grad).all(), \
    "the reward's gradient with respect to norm_obs is not finite"
assert (x.grad[:, :2] == 0).all(), "the reward should not depend on the pusher (dimensions 0 and 1)"
print("visible tests passed")

# %% [markdown]
# From here on, every plot in this notebook is drawn with **your** `reward_from_obs`, and every
# sentence about the reward's shape is measured on it. If it were wrong, the pictures and the
# sentences below would be wrong with it.
#
# ## What the reward looks like: position
#
# Fix the block's yaw at 0 and slide its centre over the whole arena. Each pixel below is the
# reward per step the block would earn sitting there. The dotted orange square is where a new
# episode can place the block's centre.

# %%
PUSHER = data.mean[0:2]                     # the pusher's position: the reward should not care
fig = nb02.fig_reward_heatmap(reward_from_obs, MEAN, STD, PUSHER)
show(fig, "02_reward_heatmap.png")
cone = nb02.cone_verdict(reward_from_obs, MEAN, STD, PUSHER)
display(Markdown(nb02.cone_text(cone, pre["median"])))

# %%
ask(SELF_CHECKS["cone_slope"], "")      # put your letter between the quotes and run the cell

# %% [markdown]
# ## What the reward looks like: yaw
#
# Now park the block's centre and turn it. Two cases: on the target, and at the held-out
# expert data's mean starting distance (pushed straight along x).

# %%
spawn_dist = float(np.linalg.norm(data.val_obs[:, 0, 2:4], axis=-1).mean())
fig = nb02.fig_reward_yaw(reward_from_obs, MEAN, STD, PUSHER, spawn_dist)
show(fig, "02_reward_yaw.png")
display(Markdown(nb02.yaw_text(nb02.half_turn(reward_from_obs, MEAN, STD, PUSHER, cone["slope_per_10cm"]))))

# %%
ask(SELF_CHECKS["yaw_vs_position"], "")

# %%
ask(SELF_CHECKS["off_circle"], "")

# %% [markdown]
# ## Scoring a held-out trajectory in both worlds
#
# Now the question that matters: when the reward reads a **decoded** observation instead of a
# true one, how wrong is it? We take the held-out expert sequence in which the block moves the
# most (the same one as at the end of notebook 01) and score it three ways:
#
# * **true**: the real frames, the reward the simulator would give;
# * **filtered reconstruction**: the model sees each real frame, filters it into `(h, z)` and
#   decodes it back: it has the answer in front of it;
# * **open-loop dream**: the model sees the first frames only, then dreams the rest of the
#   sequence under the expert's *true* actions, with no frames, as the actor's dreams will run.

# %%
with torch.no_grad():
    recon = stage.wm.decode(*stage.wm.filter(T["val_obs"], T["val_act"]))     # (N, T+1, 6)
dream = dream_all[:, 1:]                                                      # (N, T - context, 6)
views = nb02.reward_views(reward_from_obs, MEAN, STD, T["val_obs"], recon, dream)
i, moved = nb01.most_moving(data.val_obs)
fig = nb02.fig_reward_one_sequence(views, i, moved, cfg.context)
show(fig, "02_reward_one_sequence.png")

# %% [markdown]
# Where does each view put the block at the end of the sequence? The true T and pusher are grey
# and blue; the dreamed ones are red and see-through.

# %%
dream_m = dream.cpu().numpy() * data.std + data.mean                          # metres
fig = nb02.fig_final_pose(data.val_obs[i, -1], dream_m[i, -1], i, cfg.seq_len * CONTROL_DT)
show(fig, "02_final_pose.png")

# %% [markdown]
# One sequence can be lucky or unlucky. Here is the same comparison over **all** held-out
# sequences: the reward the model's view gives minus the true reward, step by step. Above zero,
# the model's view is **rosier** than the truth. As a yardstick, the grey line is copy-last from
# notebook 01: pretend the block never moves after the dream starts. Its error is simply how much
# the true reward changed since then, so it shows the size of the signal the dream is trying to
# predict.

# %%
errors = nb02.reward_errors(views)                                            # (N, T - context) each
t_dream = np.arange(cfg.context + 1, cfg.seq_len + 1) * CONTROL_DT           # seconds
fig = nb02.fig_reward_error(errors, t_dream)
show(fig, "02_reward_error.png")
summary = nb02.error_summary(errors)
display(Markdown(nb02.error_text(summary, nb02.unit_circle(dream_m))))

# %%
ask(SELF_CHECKS["where_error"], "")

# %% [markdown]
# ## What to carry forward
#
# Keep two things in mind for notebook 03.

# %%
display(Markdown(nb02.carry_forward_text(summary)))
