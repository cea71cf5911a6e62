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
# # 06 · Closing the gap: Dreamer's real-data loop, and two other fixes
#
# Notebooks 01-05 were offline: one batch of expert data, one world model trained on it and frozen,
# one actor trained inside it. Notebook 04 measured the **imagination gap** (how much more, or less,
# the dream rates the actor than the real simulator pays it), split it into what the model does on its
# own, what any motion adds and what training the actor adds, and looked at where the deployed policy
# takes the pusher compared with where the expert data went.
#
# Real Dreamer is not offline. It **loops**: act in the real world with the current policy, add what
# happened to the data, train the world model on everything seen so far, train the actor in the new
# model, repeat. This notebook runs that loop on PushT, round by round, and measures both worlds after
# every round. Then it tries two other fixes that are often proposed for the same problem:
#
# * a world model that predicts **changes** instead of states (as many dynamics models do), and
# * an **ensemble** of world models whose disagreement is subtracted from the imagined reward (MOPO's
#   pessimism), so the actor is paid less where the models are unsure.
#
# For every run it reads the gap in both of its halves (the reward has a term for the block's
# position and one for its angle, yaw) and runs a control: the scripted expert, which solves the real
# task, replayed in the dream. Does the dream pay its pushes more than standing still?
#
# Nothing here is tuned to make a fix look good. Every conclusion below is computed from the numbers
# your run measures, with their noise and a minimum effect that matters; another seed may tell a
# different story, and the table at the end sets side by side every seed found in your output folder.

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
OUT = "runs/notebooks"      # figures, and a cache of trained models shared by notebooks 01-06

# %%
import inspect
import json
import time

import numpy as np
import torch
from IPython.display import Code, Markdown, display
from tqdm.auto import tqdm

from pusht import loop
from pusht.config import field_docs
from pusht.dreamer import run
from pusht.ensemble import EnsembleWorldModel
from pusht.nb import closing as nb06
from pusht.nb import setup
from pusht.nb.closing import SELF_CHECKS
from pusht.predict import lock_prediction, reconcile, run_exercise
from pusht.selfcheck import ask

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
# METRICS: the loop's rounds and the two fixes, as json
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT, metrics="metrics/closing")
print(f"config: seed {cfg.seed}; the loop runs {cfg.loop_rounds} rounds of {cfg.loop_episodes} real episodes "
      f"of {cfg.loop_episode_len} steps (exploration noise {cfg.loop_noise}), evaluated on {cfg.eval_episodes} "
      f"held-out starts" + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

# %%
from pusht.nb.timing import here, time_note

time_note("06_closing_the_gap")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## Round 0: where notebooks 01-05 left us
#
# The offline run of notebook 04, loaded from the cache when an earlier notebook left it there.

# %%
base = run(cfg, cache_dir=CACHE, model_cache=CACHE, progress=tqdm, log=None)
b = base.metrics
display(Markdown(
    f"Offline, the dream rates the policy **{b['trained_dream_return_per_step_eval_horizon']:+.3f}** per step and "
    f"reality pays **{b['trained_real_return_per_step_eval_horizon']:+.3f}**: a gap of "
    f"**{b['imagination_gap_eval_horizon']:+.3f}** ± "
    f"{b['imagination_gap_se_eval_horizon']:.3f} over the {cfg.eval_horizon}-step evaluation "
    f"(**{b['imagination_gap_train_horizon']:+.3f}** over the actor's {cfg.imag_horizon}-step training horizon). "
    f"Real success: **{b['real_success_rate']:.0%}**; the pusher is against a wall in "
    f"**{b['real_pusher_at_wall_share']:.0%}** of real steps (expert data: {b['expert_pusher_at_wall_share']:.0%})."))

# %% [markdown]
# ## Dreamer's loop
#
# One round of `pusht/loop.py`, the three steps of every Dreamer:
#
# 1. **collect**: the current policy runs in the real simulator from fresh starts, with Gaussian noise
#    added to its actions (DreamerV1 explores the same way, `expl_amount = 0.3`). Every episode is cut
#    into clips of the world model's training length and added to the data;
# 2. **model**: the world model goes on training on *everything* seen so far, expert and policy data
#    alike, so the states the policy seeks out are now in its training data, with what really happened
#    there;
# 3. **behave**: the actor-critic goes on training in the new model, its dreams now also starting
#    from the states the policy visited.
#
# After each round both worlds are measured exactly as in notebook 04, on the same held-out starts,
# and the world model is scored against copy-last on the **policy's** data (clips of that round's real
# evaluation episodes, never trained on) as well as on held-out expert data.

# %%
display(Code(inspect.getsource(loop.collect_episodes), language="python"))
docs = field_docs()
display(Markdown("\n".join(f"* `{k}` = **{getattr(cfg, k)}**: {docs[k]}" for k in loop.LOOP_FIELDS)))

# %%
ask(SELF_CHECKS["fixed_norm"], "")

# %% [markdown]
# ## Exercise 3 · Predict, then run
#
# We run a few rounds of the loop from round 0 (the default is three). The number to predict is the
# imagination gap over the whole evaluation (imagined minus real reward per step, as in notebooks 04
# and 05), and whether the policy starts to **succeed** in reality. The note below defines what
# "shrinks" means: beyond the noise of the two measurements, and by at least a minimum effect.
#
# Which outcome do you expect?

# %%
display(Markdown(nb06.EX3_NOTE))

# %%
display(Markdown("\n".join(f"* **({k})** {v}" for k, v in nb06.EX3_OPTIONS.items())))

# %% nbgrader={"grade": false, "grade_id": "ex3_prediction", "locked": false, "schema_version": 3, "solution": true}
PREDICTION = ""     # "a", "b", "c" or "d"
REASON = ""         # one sentence: why?
### BEGIN SOLUTION
PREDICTION = "a"
REASON = ("Once the model has trained on the states the policy really visits, it can no longer be "
          "exploited there, so the dream should agree with reality and the actor should learn to push.")
### END SOLUTION
receipt = lock_prediction("ex3", PREDICTION, REASON)


# %% [markdown]
# **One sentence, before the run.** The loop retrains the world model on what the policy really did.
# Why might that make the dream agree with reality *without* the policy getting any better in reality?
# Write your answer in the cell below.

# %% [markdown] nbgrader={"grade": true, "grade_id": "ex3_sentence", "locked": false, "points": 1, "schema_version": 3, "solution": true}
# The loop fixes the model where the policy goes, not the policy: trained on what this policy's
# motions really do, the model can stop promising what they do not deliver, so the dream's rating can
# fall to what reality pays; nothing in the policy's own data needs to show the actor how to push the
# block to the target, so the gap can close from the dream's side while the real return stays where it
# was.

# %% [markdown]
# The loop itself: round 0 comes from the cache; each later round collects, retrains and re-measures
# (a progress bar per round). One line per round is printed as it finishes.

# %%
def experiment_ex3(cfg):
    """Round 0 and cfg.loop_rounds rounds of collect, model, behave; both worlds after each."""
    return loop.run_loop(cfg, cache_dir=CACHE, model_cache=CACHE, log=None, progress=tqdm,
                         on_round=lambda m: print(loop.round_line(m)))


t0 = time.perf_counter()
result = run_exercise("ex3", experiment_ex3, cfg)
rounds = result.rounds
loop.save_loop(result, METRICS / f"loop_seed{cfg.seed}")
print(f"{len(rounds) - 1} rounds" + ("" if GRADING else   # no wall-clock times in graded feedback
      f" in {time.perf_counter() - t0:.0f} s {here()} (round 0 included when not cached)"))

# %%
display(Markdown(nb06.rounds_table(rounds)))
fig = nb06.fig_rounds(rounds)
show(fig, "06_rounds.png")
display(Markdown(nb06.rounds_sentence(rounds)))

# %%
display(Code(inspect.getsource(nb06.gap_change), language="python"))
reconcile("ex3", *nb06.ex3_reconciliation(rounds))   # the words python -m pusht.exercise ex3 prints too

# %% [markdown] nbgrader={"grade": false, "grade_id": "ex3_order", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": true}
# **Completion point (Exercise 3).** Earned from the receipts in your cell outputs: the prediction
# receipt must come before the experiment receipt. There is nothing to write here; just keep
# the outputs when you save and hand in the notebook.
#
# Only the receipt printed by the prediction cell and the one printed by the experiment cell count, in that order (execution counts and times). Being honest here is on you: restarting, deleting `.pusht_predictions.json` and re-running everything in order would leave a record the grader cannot tell from an honest one, and the point is worth far less than the prediction itself.

# %% [markdown]
# ## What the loop did to the model
#
# The world model's error per round, on the policy's own data (clips of that round's real evaluation
# episodes) and on held-out expert data, against copy-last (dashed), which predicts that nothing moves.

# %%
fig = nb06.fig_model_error(rounds)
show(fig, "06_model_error.png")
display(Markdown(nb06.model_error_sentence(rounds)))

# %%
ask(SELF_CHECKS["dream_side"], "")

# %% [markdown]
# ## What the policy does with the block
#
# Touches (the pusher's rim within 3 mm of the T at some step), how far the block moved, and whether it
# ended nearer the target than it spawned (positive) or farther (negative), per round.

# %%
fig = nb06.fig_block(rounds)
show(fig, "06_block.png")
display(Markdown(nb06.block_sentence(rounds)))

# %% [markdown]
# ## Fix 2: predict changes, not states
#
# Notebook 01's model decodes the whole frame from its latent state, and one step ahead it has to
# beat copy-last, which predicts that nothing moves (the sentence below prints both models' ratios to
# copy-last on your run). A common way to make that easier is to predict the **change** `o_t - o_(t-1)` (scaled by the
# changes' own spread) and add it to the previous frame, so "nothing moves" is the easy default. Here
# the same offline chapter run with `wm_predicts="delta"`: same data, same sizes, same actor-critic.

# %%
delta = run(cfg.replace(wm_predicts="delta"), cache_dir=CACHE, model_cache=CACHE, progress=tqdm, log=None)
(METRICS / f"delta_seed{cfg.seed}.json").write_text(json.dumps(delta.metrics, sort_keys=True, indent=2) + "\n")
display(Markdown(nb06.delta_sentence(b, delta.metrics)))

# %%
ask(SELF_CHECKS["delta_runaway"], "")


# %% [markdown]
# ## Fix 3: pessimism from an ensemble
#
# MOPO (Yu et al., 2020) trains an ensemble of models and subtracts an estimate of the model's
# uncertainty, read from that ensemble, from the reward (its own estimate is the largest predicted
# standard deviation among the members; their disagreement is a common alternative). The hope: where
# the data covered a state the members agree, where it did not they part ways, and the policy is paid
# less for states it could only exploit. Our estimate is the simplest one: how far apart the members
# put the dreamed block, in metres.

# %% [markdown]
# ## Exercise: how far apart do the members put the block?
#
# An ensemble of K world models, trained on the same expert data from different initial weights,
# agrees where the data pinned the dynamics down. Where the actor steers a dream away from the
# data, nothing constrained the members there: each one may extrapolate in its own way, and their
# predictions drift apart. MOPO-style pessimism (Yu et al. 2020) reads that spread as an estimate of
# the model's error, and trains the actor on `reward - lambda * disagreement`: a dream pays less where
# the models disagree, so the actor profits less from mistakes the members do not share (mistakes
# they all share, it cannot see).
#
# The task is pushing the T-block, so the penalty watches the block. At one dreamed state, each
# member decodes a frame; the disagreement is the **root-mean-square distance of the members' block
# centres from their mean block centre**, `sqrt(var_x + var_y)`, where the variances are taken
# across the K members, which are the whole ensemble (not a sample of a larger population).
#
# Write `block_disagreement(frames, std)`:
#
# * `frames` `(K, ..., D)`: the K members' decoded frames, **normalised** observations
#   (`(obs - mean) / std`), stacked on the first dimension; any shape in between (one state, a
#   batch, a whole dream `(H, B)`); `D = 6`: pusher `(x, y)`, block centre `(x, y)`, block yaw as
#   `(sin, cos)`;
# * `std` `(D,)`: the normalisation's standard deviation;
# * return a tensor of shape `(...)` (one number per state), in **metres**, `>= 0`;
# * only the block centre counts, not the pusher or the block's angle;
# * where all members agree the disagreement is exactly 0;
# * the actor is trained through this penalty, so the result must be differentiable in `frames`,
#   and its gradient must be finite everywhere, including where the members agree.
#
# The visible tests below check shapes and a few properties; the grader checks the numbers.

# %% nbgrader={"grade": false, "grade_id": "block_disagreement_impl", "locked": false, "schema_version": 3, "solution": true}
def block_disagreement(frames, std):
    """The members' spread of the block centre: frames (K, ..., D), std (D,) -> (...), metres."""
    ### BEGIN SOLUTION
    block = frames[..., 2:4] * std[2:4]                     # (K, ..., 2), metres
    var = block.var(dim=0, correction=0).sum(-1)            # var_x + var_y across members
    # sqrt's slope is infinite at 0: take the root only where the members disagree
    positive = var > 0
    return torch.where(positive, torch.where(positive, var, 1.0).sqrt(), 0.0)
    ### END SOLUTION


# %% nbgrader={"grade": true, "grade_id": "block_disagreement_impl_tests", "locked": true, "points": 4, "schema_version": 3, "solution": false}
### BEGIN HIDDEN TESTS
# While grading: record your function's raw results on the grader's cases; the verdict
# is made outside this kernel (autograde/checks.py).
__import__("pusht.grading").grading.submit("block_disagreement_impl_tests", block_disagreement)
### END HIDDEN TESTS
# Shapes, properties and one case by hand: the grader checks the values on cases of its own.
_g = torch.Generator().manual_seed(0)
_std = torch.tensor([0.2, 0.2, 0.15, 0.15, 0.7, 0.7])

# 1. The training's shapes: K = 3 members, a dream of (H, B) states.
_frames = torch.randn(3, cfg.imag_horizon, 64, 6, generator=_g, requires_grad=True)
_d = block_disagreement(_frames, _std)
assert isinstance(_d, torch.Tensor), f"return a torch tensor, got {type(_d).__name__}"
assert tuple(_d.shape) == (cfg.imag_horizon, 64), \
    f"frames (3, {cfg.imag_horizon}, 64, 6) should give shape {(cfg.imag_horizon, 64)}, got {tuple(_d.shape)}"
assert torch.isfinite(_d).all() and (_d >= 0).all(), "a spread is finite and >= 0"
assert _d.requires_grad, "the result must carry gradient to the frames (stay in torch: no .item(), numpy, no_grad)"

# 2. A case by hand (std 1, so normalised units are metres): two members put the block centre at
#    (0.1, 0.2) and (0.4, 0.6), 0.5 m apart; each is 0.25 m from their mean, so they disagree by 0.25
#    (population variances: var_x + var_y = 0.15^2 + 0.2^2 = 0.0625, divided by K, not K - 1).
_pair = torch.tensor([[[0.0, 0.0, 0.1, 0.2, 0.0, 1.0]], [[0.0, 0.0, 0.4, 0.6, 0.0, 1.0]]])   # (K, B, D) = (2, 1, 6)
_d = block_disagreement(_pair, torch.ones(6))
assert tuple(_d.shape) == (1,), f"frames (2, 1, 6) should give shape (1,), got {tuple(_d.shape)}"
assert torch.allclose(_d, torch.tensor([0.25]), atol=1e-6), \
    f"two members 0.5 m apart should disagree by 0.25 (half the distance; divide by K, not K - 1), got {_d.tolist()}"

# 3. Members that agree do not disagree.
_same = torch.tensor([0.5, -0.25, 0.125, 0.75, 0.0, 1.0]).repeat(3, 4, 1)      # (K, B, D) = (3, 4, 6)
_d = block_disagreement(_same, _std)
assert tuple(_d.shape) == (4,), f"frames (3, 4, 6) should give shape (4,), got {tuple(_d.shape)}"
assert torch.allclose(_d, torch.zeros(4)), f"identical members should give 0, got {_d.tolist()}"

# 4. Moving every member by the same amount changes nothing: only their spread counts.
_x = torch.randn(3, 5, 6, generator=_g)
assert torch.allclose(block_disagreement(_x + 0.3, _std), block_disagreement(_x, _std), atol=1e-5), \
    "shifting all members together should not change their disagreement"
print("visible tests passed")

# %% [markdown]
# Now the ensemble: three world models on the same expert data (member 0 is the chapter's model), the
# actor trained on the reward minus the disagreement (`disagreement_penalty = 1`, a metre of
# disagreement costing as much as a metre of block error).

# %%
ens = run(cfg.replace(ensemble_size=3, disagreement_penalty=1.0), cache_dir=CACHE, model_cache=CACHE,
          progress=tqdm, log=None)
(METRICS / f"ensemble_seed{cfg.seed}.json").write_text(json.dumps(ens.metrics, sort_keys=True, indent=2) + "\n")
# your block_disagreement on the ensemble's own dream of the first evaluation start
states = []
with torch.no_grad():
    T = ens.data.torch(cfg.device)
    norm0 = (torch.as_tensor(ens.rollouts["real"].obs[0], dtype=torch.float32) - T["mean"]) / T["std"]
    h, _ = ens.wm._init(norm0.shape[0])
    z = ens.wm.filter_step(h, norm0)
    for a in torch.as_tensor(ens.rollouts["dream"].actions, dtype=torch.float32):
        h, z = ens.wm.img_step(h, z, a)
        states.append(torch.cat([h, z], dim=-1))
    hs, zs = torch.stack(states).split([ens.wm.hidden_dim, ens.wm.latent_dim], dim=-1)
    mine = block_disagreement(ens.wm.member_outputs(hs, zs), T["std"])
    package = ens.wm.disagreement(torch.stack(states), T["std"])
print(f"your disagreement along the evaluation dream: {float(mine.mean()):.4f} m; the package's: "
      f"{float(package.mean()):.4f} m")
display(Markdown(nb06.ensemble_sentence(b, ens.metrics, penalty=1.0,
                                        train_disagreement=ens.history.get("imag_disagreement"))))

# %%
ask(SELF_CHECKS["shared_bias"], "")

# %% [markdown]
# ## The three fixes side by side

# %%
fig = nb06.fig_fixes(b, rounds[-1], delta.metrics, ens.metrics)
show(fig, "06_fixes.png")
display(Markdown(nb06.fixes_table(b, rounds[-1], delta.metrics, ens.metrics)))
display(Markdown(nb06.conclusion(rounds, b, delta.metrics, ens.metrics)))

# %% [markdown]
# ## Every seed in your output folder
#
# One run is one seed. This table reads every seed's results written into `OUT`: notebook 04's offline
# runs (`metrics/seed<s>.json`) and this notebook's loop and two fixes (`metrics/closing/`). Run this
# notebook with another `SEED` into the same `OUT` (or `make claims`, which runs seeds 0-5) and the
# table grows. A pattern that holds on one seed only is not yet a pattern.

# %%
display(Markdown(nb06.summary_table(OUT)))

# %% [markdown]
# ## Read next
#
# * **DreamerV1**: Hafner et al. (2020), *Dream to Control*: the loop of this notebook, with 5,000
#   random prefill steps, exploration noise and 100 training steps per 1,000 environment steps.
# * **DreamerV3**: Hafner et al. (2023), *Mastering Diverse Domains through World Models*: the same
#   loop run continuously, at a fixed ratio of replayed to collected steps.
# * **MBPO**: Janner et al. (2019), *When to Trust Your Model*: short model rollouts branched from
#   real states, because model error compounds with rollout length.
# * **PETS**: Chua et al. (2018): an ensemble of probabilistic models, with planning that re-plans
#   every step.
# * **MOPO**: Yu et al. (2020) and **MOReL**: Kidambi et al. (2020): pessimism from an ensemble's
#   disagreement, for when no more real data can be collected.
# * **Causal confusion in imitation learning**: de Haan et al. (2019): a model (or a policy) that
#   learns a correlation in the expert's data ("the block approaches the target") instead of its
#   cause ("the block moves when pushed").
