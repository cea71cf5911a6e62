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
# # 03 · Learning to act inside the dream
#
# This is the move the chapter is named for. We **freeze** the world model from notebook 01 and
# train a policy purely on trajectories it imagines: start from a real state, let the actor pick
# an action, let the model dream the next state, decode it, score it with notebook 02's reward,
# and repeat. The real PushT simulator takes no part in the learning. It only watches, now and
# then, so that we can see what the policy really earns.
#
# In this notebook you will:
#
# 1. meet the actor and the critic, and see why both read the model's state `[h, z]`;
# 2. implement Dreamer's **lambda-return**, the target that mixes dreamed rewards with the
#    critic's values;
# 3. implement the **actor's and the critic's losses**, with the stop-gradients that decide which
#    network learns from what, and measure which of them this training loop really needs (your
#    two functions then drive the training);
# 4. train in imagination, and compare the reward the policy earns in the dream with what the
#    same policy earns in the real sim;
# 5. measure what the critic contributes, by training once more with the chapter page's wiring,
#    in which the critic never reaches the actor.

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
import numpy as np
import torch
import torch.nn.functional as F
from IPython.display import Markdown, display
from tqdm.auto import tqdm

from pusht.agent import ActorCritic
from pusht.dreamer import agent_stage, world_model_stage
from pusht.env import ACT_DIM
from pusht.imagination import imagine, page_losses, set_gradients, train_in_imagination
from pusht.nb import actor as nb03
from pusht.nb import setup
from pusht.nb.actor import SELF_CHECKS
from pusht.reward import reward_from_obs
from pusht.selfcheck import ask
from pusht.sweep import start_many

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT)
print(f"config: seed {cfg.seed}, {cfg.imag_iters} policy updates of {cfg.imag_batch} dreams x "
      f"{cfg.imag_horizon} steps, actor lr {cfg.actor_lr}"
      + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

# %%
from pusht.nb.timing import here, time_note

time_note("03_imagination_actor")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## The world model, frozen
#
# The model notebook 01 trained comes from the cache in `OUT` (or is trained again if the cache
# is missing). Its parameters are frozen: gradients can pass *through* it, but it never changes.

# %%
stage = world_model_stage(cfg, cache_dir=CACHE, model_cache=CACHE, progress=tqdm)
wm = stage.wm
T = stage.data.torch(cfg.device)
MEAN, STD = T["mean"], T["std"]
print(f"world-model parameters that can still learn: {sum(p.requires_grad for p in wm.parameters())} "
      f"of {len(list(wm.parameters()))}")

# %% [markdown]
# ## The actor and the critic
#
# Both are small MLPs, and both read the same input: the world model's state `[h, z]`, the GRU's
# memory `h` next to the latent `z`. Why that input, and not the observation? Because it exists
# in **both** worlds:
#
# * in a dream there are no frames, but there is `[h, z]`: the prior produces it step by step;
# * on the real robot there are frames, and filtering them through the posterior gives `[h, z]`.
#
# So one policy, trained in the dream, can be run unchanged in reality (notebook 04 does exactly
# that). The actor outputs the mean of a Gaussian, adds noise scaled by a learned `log_std`, and
# squashes the result with `tanh` into the env's action range `[-1, 1]`. Because a sample is
# `tanh(mean + std * noise)`, a smooth function of the actor's weights, the imagined reward can
# be differentiated through the frozen model all the way back into the actor.

# %%
import inspect
from IPython.display import Code

display(Code(inspect.getsource(ActorCritic), language="python"))
state_dim = cfg.hidden_dim + cfg.latent_dim
display(Markdown(f"Here `state_dim = hidden_dim + latent_dim = {cfg.hidden_dim} + {cfg.latent_dim} = "
                 f"{state_dim}` and `act_dim = {ACT_DIM}` (the pusher's velocity command)."))


# %% [markdown]
# ## Exercise A: the lambda-return
#
# Each update dreams `H` steps from a batch of `B` start states. That gives the imagined rewards
# `r_0 .. r_{H-1}` (the reward on arriving in state `t+1`) and, from the critic, values
# `V_0 .. V_H` for every dreamed state. What should the actor maximise, and what should the
# critic learn to predict?
#
# Summing the dreamed rewards stops at the horizon and ignores everything after it. Trusting the
# critic after a single step leans on a network that starts out knowing nothing. Dreamer's
# **lambda-return** blends the two. It is defined backwards from the horizon:
#
# $$G_H = V_H, \qquad G_t = r_t + \gamma\,\big((1-\lambda)\,V_{t+1} + \lambda\,G_{t+1}\big).$$
#
# Write `lambda_return(rewards, values, gamma, lam)`. The contract:
#
# * `rewards` is `(H, B)`, `values` is `(H + 1, B)`, the result `(H, B)`: `G_0 .. G_{H-1}`;
# * `gamma` and `lam` are the arguments you are given (the grader tries other values);
# * the result must stay differentiable in both `rewards` and `values`: the actor's gradient
#   arrives through this function, from the rewards *and* from the critic's values.

# %% nbgrader={"grade": false, "grade_id": "lambda_return_impl", "locked": false, "schema_version": 3, "solution": true}
def lambda_return(rewards, values, gamma, lam):
    """Dreamer's lambda-return. rewards (H, B), values (H+1, B) -> returns (H, B)."""
    ### BEGIN SOLUTION
    out, last = [], values[-1]                      # G_H = V_H: the critic closes the horizon
    for t in reversed(range(rewards.shape[0])):
        last = rewards[t] + gamma * ((1 - lam) * values[t + 1] + lam * last)
        out.append(last)
    return torch.stack(out[::-1])                   # (H, B), back in time order
    ### END SOLUTION


# %% nbgrader={"grade": true, "grade_id": "lambda_return_impl_tests", "locked": true, "points": 4, "schema_version": 3, "solution": false}
### BEGIN HIDDEN TESTS
# While grading: record your function's raw results on the grader's cases; the verdict
# is made outside this kernel (autograde/checks.py).
__import__("pusht.grading").grading.submit("lambda_return_impl_tests", lambda_return)
### END HIDDEN TESTS
# 1. A case small enough to do by hand: H = 2, B = 1, gamma = lam = 0.5.
#    G_2 = V_2 = 30
#    G_1 = 2 + 0.5 * (0.5 * 30 + 0.5 * 30) = 17
#    G_0 = 1 + 0.5 * (0.5 * 20 + 0.5 * 17) = 10.25
G = lambda_return(torch.tensor([[1.0], [2.0]]), torch.tensor([[10.0], [20.0], [30.0]]), 0.5, 0.5)
assert tuple(G.shape) == (2, 1), f"rewards (2, 1) should give returns of shape (2, 1), got {tuple(G.shape)}"
assert torch.allclose(G, torch.tensor([[10.25], [17.0]])), f"expected [[10.25], [17.0]], got {G.tolist()}"
#    One step (H = 1): G_0 = r_0 + gamma * ((1 - lam) * V_1 + lam * G_1) with G_1 = V_1, so with
#    r_0 = 2, V_1 = 7 and gamma = 0.5, G_0 = 2 + 0.5 * 7 = 5.5 whatever lam is.
G = lambda_return(torch.tensor([[2.0]]), torch.tensor([[5.0], [7.0]]), 0.5, 0.3)
assert torch.allclose(G, torch.tensor([[5.5]])), f"H = 1: expected [[5.5]], got {G.tolist()}"

# 2. The training's shapes, and the one-step limit: with lam = 0, G_t = r_t + gamma * V_{t+1}.
g = torch.Generator().manual_seed(0)
r, v = torch.randn(cfg.imag_horizon, 64, generator=g), torch.randn(cfg.imag_horizon + 1, 64, generator=g)
G = lambda_return(r, v, cfg.gamma, cfg.lam)
assert tuple(G.shape) == (cfg.imag_horizon, 64), f"expected shape {(cfg.imag_horizon, 64)}, got {tuple(G.shape)}"
assert torch.allclose(lambda_return(r, v, 0.9, 0.0), r + 0.9 * v[1:], atol=1e-5), \
    "with lam = 0 the return should be r_t + gamma * V_{t+1}"
print("visible tests passed")

# %% [markdown]
# What does `lam` change in practice? Here is your function on one batch of real dreams: the
# untrained actor dreams from real start states, and the untrained critic supplies the values.
# Every PushT reward is at most 0 (it is minus the block's distance and yaw error), so every true
# return is negative; an untrained critic knows nothing of that. Small `lam` leans on the critic's
# values at every step, `lam = 1` only at the horizon. The sentence under the figure reads this
# batch.

# %%
torch.manual_seed(cfg.seed)
demo = ActorCritic(state_dim, ACT_DIM, cfg.hidden_dim).to(cfg.device)
with torch.no_grad():
    h0, z0 = wm.warm(T["train_obs"][: cfg.imag_batch, : cfg.context + 1],
                     T["train_act"][: cfg.imag_batch, : cfg.context])
    states, obs_pred, _ = imagine(wm, demo, h0, z0, cfg.imag_horizon)     # (H+1, B, S), (H, B, 6)
    demo_rewards = reward_from_obs(obs_pred, MEAN, STD)[0]               # (H, B)
    demo_values = demo.value(states)                                     # (H+1, B)
    G_by_lam = {lam_: lambda_return(demo_rewards, demo_values, cfg.gamma, lam_).mean(1).numpy()
                for lam_ in (0.0, 0.5, cfg.lam, 1.0)}
fig = nb03.fig_lambda_returns(G_by_lam, cfg.lam, cfg.imag_batch)
show(fig, "03_lambda_returns.png")
display(Markdown(nb03.lambda_sentence(G_by_lam, demo_rewards, demo_values, cfg.gamma)))

# %%
ask(SELF_CHECKS["lam_one"], "")      # your letter between the quotes


# %% [markdown]
# ## Exercise B: the actor's loss and the critic's loss
#
# One batch of dreams gives the imagined states `s_0 .. s_H` (each `[h, z]`), the rewards
# `r_0 .. r_{H-1}` decoded from them, and the actor's entropy. Both networks learn from it, but
# they want different things, and the whole difference is *which gradient is allowed where*.
#
# **The actor** maximises the mean lambda-return of its dreams (plus `ent_coef` times its
# entropy, so it keeps exploring). In DreamerV1 (`danijar/dreamer`, `Dreamer._train`) the values
# inside that return are the critic's values of the imagined states **with their gradient**: the
# return depends on the actor's actions through the rewards *and* through `V(s_t)`, so the
# critic's slope tells the actor which way is better beyond the last dreamed step. The actor's
# optimiser then steps only the actor's weights.
#
# **The critic** regresses `V(s_t)` for `t = 0 .. H-1` on `G_t` (half the mean squared error).
# It must learn to *predict* returns, not change them. So the target it chases is detached:
# otherwise the critic would also move its own values inside the target, and chase a target that
# moves with it. The states it reads are detached too, so that nothing of the critic loss can
# flow back through the dream into the actions, however the loop applies the gradients. (Whether
# this notebook's loop needs that second detach is a question for you after the tests, answered
# before it is measured.)
#
# Write `actor_critic_losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn)`:
#
# * `states` `(H+1, B, S)` and `rewards` `(H, B)` carry gradient back to the actor's actions;
#   `entropy` is a scalar tensor; `agent.value(states)` gives `V` of shape `(H+1, B)`;
# * return `(actor_loss, critic_loss)`, two scalar tensors (a loss is minimised);
# * which gradients must exist: the actor loss reaches the rewards, the entropy, and the states
#   (through the critic's values); the critic loss reaches the critic's weights and **nothing
#   else** (not the states, not the rewards);
# * use `return_fn` for the lambda-return (it defaults to yours).
#
# The training loop then gives each network the gradient of its own loss only
# (`set_gradients`, shown after the tests), as Dreamer's two optimisers do.

# %% nbgrader={"grade": false, "grade_id": "losses_impl", "locked": false, "schema_version": 3, "solution": true}
def actor_critic_losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn=lambda_return):
    """Dreamer's two losses on one batch of dreams: (actor_loss, critic_loss), scalars."""
    ### BEGIN SOLUTION
    values = agent.value(states)                                   # (H+1, B), gradient kept
    returns = return_fn(rewards, values, gamma, lam)               # (H, B)
    actor_loss = -(returns.mean() + ent_coef * entropy)
    critic_loss = 0.5 * F.mse_loss(agent.value(states.detach())[:-1], returns.detach())
    return actor_loss, critic_loss
    ### END SOLUTION


# %% nbgrader={"grade": true, "grade_id": "losses_impl_tests", "locked": true, "points": 4, "schema_version": 3, "solution": false}
### BEGIN HIDDEN TESTS
# While grading: record your function's raw results on the grader's cases; the verdict
# is made outside this kernel (autograde/checks.py).
__import__("pusht.grading").grading.submit("losses_impl_tests", actor_critic_losses)
### END HIDDEN TESTS
# Shapes and signs only: whether each gradient goes where it should is checked by the grader,
# and measured by you in the next cells.
torch.manual_seed(0)
_agent = ActorCritic(10, 2, 8)
_states = torch.randn(6, 4, 10, requires_grad=True)
_rewards = -torch.rand(5, 4, requires_grad=True)
_out = actor_critic_losses(_agent, _states, _rewards, _agent.entropy(), 0.99, 0.95, 3e-4)
assert isinstance(_out, tuple) and len(_out) == 2, "return a tuple (actor_loss, critic_loss)"
_a, _c = _out
assert _a.shape == () and _c.shape == (), f"both losses are scalars; got {tuple(_a.shape)} and {tuple(_c.shape)}"
assert torch.isfinite(_a) and torch.isfinite(_c) and float(_c.detach()) >= 0, "the critic loss is a squared error: >= 0"
assert _a.requires_grad and _c.requires_grad, "both losses must carry gradient (no .item(), no torch.no_grad)"
print("visible tests passed")

# %% [markdown]
# Exercise B asked your critic loss to read the states detached. Is that detach what keeps
# value regression away from the policy? It depends on how the gradients reach the parameters.
# Here is how this loop does it: `set_gradients` asks autograd for the actor loss's gradient on
# the actor's weights, and for the critic loss's gradient on the critic's weights, and for nothing
# else. Answer the question under it first; the cells below measure the answer.

# %%
display(Code(inspect.getsource(set_gradients), language="python"))
ask(SELF_CHECKS["critic_detach"], "")      # your letter between the quotes

# %% [markdown]
# Now measure what your two losses reach, on one batch of real dreams, beside the chapter page's
# version of the same update (`page_losses`: the page computes the values on detached states and
# detaches them again inside the return). Each number is the size of the gradient one loss sends
# into one part. The dreamed states `[h, z]` are the road back to the actor's actions; the rewards
# use that road in both versions, so the table asks whether the *values* use it too (it holds
# the rewards fixed for that row). First, a question on the page's wiring: answer it, then run
# the measurement.

# %%
ask(SELF_CHECKS["page_wiring"], "")      # your letter between the quotes


# %%
def dream_batch():
    """One batch of dreams from the demo agent, with the same action noise every call."""
    torch.manual_seed(cfg.seed)
    states, obs_pred, entropy = imagine(wm, demo, h0, z0, cfg.imag_horizon)
    return states, reward_from_obs(obs_pred, MEAN, STD)[0], entropy


wirings = {"your losses": actor_critic_losses, "the page's losses": page_losses}
reach = {name: nb03.gradient_reach(demo, *dream_batch(), fn, cfg.gamma, cfg.lam, cfg.ent_coef)
         for name, fn in wirings.items()}
change = {name: nb03.actor_grad_change(demo, dream_batch, fn, cfg.gamma, cfg.lam, cfg.ent_coef)
          for name, fn in wirings.items()}
display(Markdown("Gradient norm on one batch of dreams:\n\n" + nb03.reach_table(reach)))
display(Markdown(nb03.reach_reading(reach)))
display(Markdown(nb03.critic_reach_sentence(change["your losses"], change["the page's losses"])))

# %%
# One update's gradients with your losses, and with two variants of your critic loss (the states
# undetached; the target undetached), put on the parameters by set_gradients (this loop) and by a
# single summed backward() of both losses (a loop with one optimiser for both networks).
effects = nb03.detach_effects(demo, dream_batch, actor_critic_losses, cfg.gamma, cfg.lam, cfg.ent_coef)
display(Markdown("How each parameter group's gradient differs from your losses' own:\n\n"
                 + nb03.detach_table(effects) + "\n\n" + nb03.detach_sentence(effects)))

# %% [markdown]
# ## Train in imagination
#
# Now the real thing, with **your** `lambda_return` and **your** losses. Here is the training
# loop from the package; `loss_fn` is where your `actor_critic_losses` goes in.

# %%
display(Code(inspect.getsource(train_in_imagination), language="python"))

# %% [markdown]
# Every `monitor_every` updates, the current policy is also run in the **real** PushT sim from a
# few fixed starts (different from the evaluation starts of notebook 04), and its mean reward per
# step is recorded: this is the *real floor*. The monitor only watches; no gradient ever comes
# from the real sim. The policy it runs is the deterministic one, `tanh(mean)`, acting on `[h, z]`
# filtered from the real frames.

# %%
# The package's run, and the page's wiring that a section below compares it with, start in worker
# processes on the machine's cores (start_many; each gives the numbers it gives alone, both cached)
# while yours trains here in the kernel.
with start_many([cfg, cfg.replace(critic_wiring="page")], cache_dir=CACHE, model_cache=CACHE) as pending:
    mine = agent_stage(cfg, stage, model_cache=CACHE, progress=tqdm, return_fn=lambda_return,
                       loss_fn=actor_critic_losses)
    reference, page = pending.results(progress=tqdm)
diff = float(np.abs(mine.history["imag_reward"] - reference.history["imag_reward"]).max())
took = "" if GRADING else f" took {mine.seconds:.1f} s {here()}"     # no wall-clock times in graded feedback
display(Markdown(nb03.match_sentence(diff, cfg.imag_iters, took)))

# %%
# before the curves: what would a rising imagined reward tell you?
ask(SELF_CHECKS["what_rises"], "")      # your letter between the quotes

# %% [markdown]
# ## The dream and the real sim, during training
#
# The light curve is the mean imagined reward per step of every batch of dreams (one point per
# update, noisy because every batch starts from different states with fresh action noise); the
# dark curve is its moving average. The squares are the real floor.
#
# Compare the **changes** of the curves, not their levels: the dreams last `imag_horizon` steps
# and start from states in the training data, while the real floor runs `eval_horizon` steps
# from fresh starts, so the two levels are not measured on the same footing. Notebook 04 puts
# the same policy in both worlds on identical starts and horizons.

# %%
fig = nb03.fig_training({"Dreamer's wiring": reference.history}, cfg.monitor_episodes)
show(fig, "03_imagined_vs_real.png")
# the real floor's two ends again, start by start (the history keeps only their mean): its noise
floor = nb03.real_floor(stage.wm, reference, cfg, MEAN, STD)
display(Markdown(nb03.training_sentence(reference.history, floor)))

# %%
fig = nb03.fig_critic_and_std(reference.history)
show(fig, "03_critic_and_std.png")
display(Markdown(nb03.objective_sentence(reference.history, cfg.imag_horizon)))

# %% [markdown]
# ## What the critic contributes
#
# The chapter page trains the same actor with the values detached inside the actor's return, so
# its actor never hears from the critic (the perturbation test above checks it). Train it once
# that way, everything else unchanged (same model, same seed, so the same start states and action
# noise), and put both runs side by side.
# (`page`, that run, was trained alongside the package's run above.)

# %%
fig = nb03.fig_training({"Dreamer's wiring": reference.history, "page's wiring": page.history},
                        cfg.monitor_episodes)
show(fig, "03_wirings.png")
# the page's run on the monitor's starts, start by start, as for the package's run above
page_floor = nb03.real_floor(stage.wm, page, cfg, MEAN, STD)
display(Markdown(nb03.wiring_sentence(reference.metrics, page.metrics, reference.history, page.history,
                                      floor, page_floor)))

# %% [markdown]
# ## An honest note on the actor's gradient
#
# Our actor is trained with the **pathwise** (analytic) gradient: the imagined return is
# differentiated through the frozen decoder, prior and GRU back into the actions. That is how
# the first Dreamer (DreamerV1, `danijar/dreamer`) trained its actor. It hands the actor the
# model's own derivatives of the reward with respect to the actions, and those are only as
# informative as the dynamics are smooth. PushT's contact is not smooth: the real block moves only
# while the pusher touches it, so away from contact a small change of the action changes nothing
# in the real world, whatever slope the learned model's smooth version of the dynamics shows.
# DreamerV3's maintainer names non-smooth dynamics as the weak point of backpropagating through
# the rollouts (dreamerv3 issue 168: it "doesn't work that well" where the dynamics are not smooth,
# which he says of discrete actions; for continuous control it "can be slightly faster").
#
# DreamerV3 (`danijar/dreamerv3`, `dreamerv3/agent.py`, `imag_loss`) today does something
# different. It computes the same kind of lambda-return, but its policy sees a stop-gradient copy
# of the state and is trained with **REINFORCE**: the log-probability of the chosen action times a
# stop-gradient, normalised advantage, plus an entropy bonus. No gradient flows through the
# dynamics. Its first release did backpropagate through the dynamics for continuous actions: that
# was the default (`actor_grad_cont: backprop`, with REINFORCE for discrete actions). Its
# maintainer removed the backprop path in 2024, explaining that REINFORCE worked about as well,
# handles discrete actions, and is simpler (dreamerv3 issue 168). Same target, a different way of
# pushing it into the policy.
#

# %% [markdown]
# ## What to carry forward

# %%
display(Markdown(nb03.carry_forward(reference.history, floor)))
