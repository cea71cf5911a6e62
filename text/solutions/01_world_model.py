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
# # 01 · The world model you will dream in (a 3.1 recap)
#
# This chapter trains a policy **entirely inside a learned world model** and then checks whether
# what it learned works in the real world. Before any of that, we need the world model itself:
# the small encoder-GRU-prior-posterior-decoder network from chapter 3.1, trained on a scripted
# expert pushing a T-shaped block around.
#
# By the end of this notebook you will have trained it and measured, dimension by dimension,
# what it learned well and what it did not. Keep that measurement in mind: every later notebook
# inherits it.

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

from IPython.display import Code, Markdown, display
from tqdm.auto import tqdm

import pusht.nb.world_model as nb01      # this notebook's figures and conclusions
from pusht.dreamer import world_model_stage
from pusht.env import CONTROL_DT
from pusht.expert import expert_episode
from pusht.nb import setup
from pusht.nb.world_model import SELF_CHECKS
from pusht.selfcheck import ask
from pusht.world_model import WorldModel

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT)
print(f"config: seed {cfg.seed}, {cfg.n_episodes} expert sequences of {cfg.seq_len} steps "
      f"({cfg.seq_len * CONTROL_DT:.1f} s), {cfg.wm_epochs} epochs" + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

# %%
from pusht.nb.timing import time_note

time_note("01_world_model")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## The world: PushT
#
# A round **pusher** (blue) moves where you command it; it can only affect the grey **T-block**
# by pushing it. The task is to push the T onto the dashed green **target** at the origin. The
# physics is a 2-D rigid-body simulation (pymunk) built so that the block is frictionless and
# quasi-static: it should move only while it is being pushed (we measure that below).
#
# * observation: `[agent_x, agent_y, tee_x, tee_y, sin(tee_yaw), cos(tee_yaw)]`, in metres;
# * action: the pusher's velocity command in `[-1, 1]^2` (times 0.5 m/s), ten times a second;
# * reward per step: `-0.5 * (distance / 0.5 m + |yaw error| / pi)`, 0 at the target.

# %%
fig = nb01.fig_starts(seeds=(0, 1, 2))
show(fig, "01_starts.png")

# %% [markdown]
# ## The expert that made the data
#
# The world model learns from a scripted expert built to solve the task: it picks a point on the
# T to push, walks the pusher round to it, pushes, and re-plans every step. Here is one full
# episode: the pusher's path, and the T fading from its start pose to the target. Below it: how
# often the expert succeeds from other random starts.

# %%
obs, actions, success = expert_episode(seed=3)
fig = nb01.fig_expert(obs, actions, success)
show(fig, "01_expert.png")
display(Markdown(nb01.expert_text(nb01.expert_success(n=10 if cfg.smoke else 50))))

# %% [markdown]
# ## The model
#
# Here is the world model, straight from the package (this is the code that runs, not a copy).
# Read `observe` first: it filters real sequences and returns the two losses. Then `step`: the
# dream, with no frames at all, only the prior.

# %%
display(Code(inspect.getsource(WorldModel), language="python"))

# %% [markdown]
# ## Train it
#
# 3.1's recipe: the first steps of expert episodes from fresh random starts (the lengths are in the
# config line above). The model is trained on two losses, both **mean squared errors**, both
# unitless:
#
# * **reconstruction**: the observation decoded from each filtered state against the true one, in
#   normalised units (each observation dimension minus its mean, divided by its standard deviation
#   over the training frames);
# * **dynamics**: the prior's latent, predicted without the frame, against the posterior's latent,
#   which saw it (latents lie in [-1, 1]).
#
# The trained model is cached in `OUT`, so the next notebooks reuse it instead of training it again.

# %%
stage = world_model_stage(cfg, cache_dir=CACHE, model_cache=CACHE, progress=tqdm)
per_epoch = -(-cfg.n_episodes // cfg.batch_size)          # updates per pass over the data
fig = nb01.fig_losses(stage.history, per_epoch, cfg.batch_size)
show(fig, "01_wm_losses.png")
display(Markdown(nb01.loss_text(nb01.loss_summary(stage.history, per_epoch))))

# %%
ask(SELF_CHECKS["low_loss"], "")      # put your letter between the quotes and run the cell

# %% [markdown]
# ## What is in the data
#
# Before judging the model, count what it had to learn from. In how many transitions does the
# block move at all, and the pusher? A step "moves" something if it travels more than a threshold
# (`nb01.MOVE_THRESHOLD`, 1 mm per step; the comment beside it in `pusht/nb/world_model.py` says
# why that value): first we measure how much an untouched block creeps on its own, then count,
# at that threshold and at a thousand times smaller one.

# %%
shares = nb01.motion_shares(stage.data.train_obs, stage.data.val_obs, nb01.resting_jitter())
display(Markdown(nb01.motion_text(shares)))

# %%
ask(SELF_CHECKS["resting_steps"], "")

# %% [markdown]
# ## What did it learn? The model against copy-last
#
# A low loss says little by itself. The honest yardstick is the laziest possible predictor,
# **copy-last**: "the next frame equals this frame". On held-out expert sequences we compare,
# for each observation dimension, the model's error with copy-last's, both for one-step
# predictions (filter real frames, dream a single step) and open-loop (filter a couple of frames,
# then dream the rest of the sequence under the true actions, no frames). A bar below the dashed
# line at 1 means the model beats copy-last on that dimension; the error bars show how much
# that ratio would vary over other held-out sequences (a bootstrap), and a bar whose error bar
# crosses 1 is a tie.

# %%
open_steps = cfg.seq_len - cfg.context
T = stage.data.torch(cfg.device)
se = nb01.copy_last_noise(stage.wm, T["val_obs"], T["val_act"], cfg.context)   # bootstrap over sequences
fig = nb01.fig_copy_last(stage.error, open_steps, se)
show(fig, "01_copy_last.png")
verdict = nb01.copy_last_verdict(stage.error, se)
display(Markdown(nb01.copy_last_text(verdict, open_steps)))

# %%
ask(SELF_CHECKS["one_vs_open"], "")

# %% [markdown]
# ## A dream next to the truth
#
# The same comparison as a picture: one held-out sequence (the one where the block moves most),
# dreamed open-loop from its first frames under the expert's true actions. The solid grey line
# marks the step in which the real pusher first pushes the real block (the first step the real
# block moves more than `MOVE_THRESHOLD`, 1 mm): until then the real block has moved less than
# that in every step. Watch what the dreamed block does before that line.

# %%
data = stage.data
dream = nb01.open_loop_dream(stage.wm, T["val_obs"], T["val_act"], cfg.context)   # (N, T-context+1, 6)
dream = dream.cpu().numpy() * data.std + data.mean                                  # back to metres
i, _ = nb01.most_moving(data.val_obs)
first = nb01.first_push(data.val_obs)                                               # (N,) step index
fig = nb01.fig_dream_vs_true(data.val_obs[i], dream[i], cfg.context, first[i], i)
show(fig, "01_dream_vs_true.png")

pre = nb01.pre_push_motion(data.val_obs, dream, cfg.context)
noise = nb01.decode_noise(stage.wm, T["val_obs"], T["val_act"], data.std)
split = nb01.open_loop_by_contact(data.val_obs, dream, cfg.context)
display(Markdown(nb01.dream_text(pre, split, noise, i, first[i], cfg.context)))

# %%
ask(SELF_CHECKS["pre_contact"], "")

# %% [markdown]
# ## What to carry forward

# %%
display(Markdown(nb01.carry_forward_text(verdict, pre, noise, shares)))
