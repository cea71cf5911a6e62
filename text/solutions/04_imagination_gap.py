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
# # 04 · The imagination gap: one policy, two worlds
#
# In notebook 03 an actor learned to push the T-block without ever touching the real simulator:
# every gradient it received came from a dream of the frozen world model. Training was built to
# raise its imagined reward, and the imagined reward is the only thing the training loop can see.
#
# This notebook asks the question the training loop cannot: **does the skill work in the real
# world?** We take the very same deterministic policy and run it twice from the same starts,
# once inside the world model's dream and once in the real PushT simulator, score both with the
# same reward function, and compare.
#
# You will:
#
# 1. write the dreaming half of that evaluation yourself (the rest of the notebook uses your
#    version);
# 2. predict what the comparison will show, then run it on two seeds;
# 3. take the gap apart with controls, over the actor's own training horizon and over the whole
#    evaluation: how much is the model drifting on its own, how much is the actor exploiting it;
# 4. measure how far the deployed policy takes the model from the data it was trained on;
# 5. see how the real DreamerV3 handles the same problem.

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
import json

import numpy as np
import torch
from IPython.display import HTML, Code, Markdown, display
from tqdm.auto import tqdm

import pusht.evaluate
from pusht.analysis import at_wall, expert_replay_error, replay_error
from pusht.data import EVAL_SEED_BASE, start_seeds
from pusht.draw import animate_two_worlds
from pusht.evaluate import TOUCH_TOL, policy_of, two_world_eval
from pusht.nb import gap as nb04
from pusht.nb import setup
from pusht.nb.gap import SELF_CHECKS
from pusht.page import PAGE  # the chapter page's own figures: quoted for comparison only
from pusht.predict import lock_prediction, reconcile, run_exercise
from pusht.selfcheck import ask
from pusht.sweep import run_many

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
# METRICS: one json per seed, read by `make chapter`
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT, metrics="metrics")
print(f"config: seed {cfg.seed}, {cfg.imag_iters} policy updates in imagination, "
      f"{cfg.eval_episodes} held-out starts of {cfg.eval_horizon} steps"
      + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

SEEDS = [SEED, SEED + 1] if GRADING else [SEED, SEED + 1, SEED + 2]   # the seeds compared (the autograder skips a third)
RUNS = {}         # seed -> RunResult, so each seed trains (or loads from the cache) once


def run_seed(seed: int):
    """The whole pipeline for one seed, reusing cached stages from earlier notebooks.

    The first call trains every seed of SEEDS not trained yet, side by side on the machine's cores
    (``run_many``: one worker process per core, each run's numbers exactly those of running it alone).
    """
    if seed not in RUNS:
        todo = [s for s in dict.fromkeys([seed, *SEEDS]) if s not in RUNS]
        for s, res in zip(todo, run_many([cfg.replace(seed=s) for s in todo], cache_dir=CACHE,
                                         model_cache=CACHE, progress=tqdm, desc="seeds")):
            (METRICS / f"seed{s}.json").write_text(json.dumps(res.metrics, sort_keys=True, indent=2) + "\n")
            RUNS[s] = res
    return RUNS[seed]


# %%
from pusht.nb.timing import time_note

time_note("04_imagination_gap")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## Two ways to run one policy
#
# The actor reads the world model's state `[h, z]` and outputs a pusher velocity. We can produce
# that state in two ways, and that is what makes a fair comparison possible:
#
# * **in reality**, at every step we *filter* the true frame into `z` with the posterior, act,
#   step the real simulator, and feed the action into the GRU to get the next `h`;
# * **in the dream**, we filter only the *first* frame. After that there are no frames: the GRU
#   and the **prior** alone carry the state forward, and the decoder tells us what the model
#   believes the world looks like.
#
# Both worlds are scored with the same `reward_from_obs`: on the true pose in reality, on the
# decoded pose in the dream. So any difference between the two scores is a difference between
# the two *states*, never between two reward definitions.
#
# Here is the real half, exactly as the package runs it. Notice that all starts run as one
# batch (one network call per step for all of them), and that the reward is computed once, at
# the end, from the true observations.

# %%
display(Code(inspect.getsource(pusht.evaluate.real_rollout), language="python"))


# %% [markdown]
# ### Your turn: write the dream
#
# Write `dream(wm, policy, norm_obs0, horizon)`, the imagined half, in the model's own normalised
# units. The contract:
#
# * the dream gets **one** real frame per start, `norm_obs0` `(B, D)`, and no memory before it:
#   its start state is the posterior of that frame given a zero memory. After that no frame
#   exists, so the model must carry the state forward on its own (with the prior);
# * at every step the policy acts on the state `[h, z]`, and that action drives the next step;
# * return `(decoded, actions)`: every state decoded, the start included, `(horizon + 1, B, D)`,
#   and the actions `(horizon, B, A)`;
# * it is called under `torch.inference_mode()`, so it must not need gradients.
#
# The world model's methods (read their docstrings with `help(wm.img_step)` and so on):
# `wm._init(B)` (zero memory), `wm.filter_step(h, norm_obs)` (posterior of a real frame),
# `wm.img_step(h, z, action)` (one step of the prior), `wm.decode(h, z)` (any leading shape).

# %% nbgrader={"grade": false, "grade_id": "dream_impl", "locked": false, "schema_version": 3, "solution": true}
def dream(wm, policy, norm_obs0, horizon):
    """Dream ``horizon`` steps from the start frames ``norm_obs0`` (B, D), normalised.

    Returns (decoded observations (horizon+1, B, D), actions (horizon, B, A)); decoded[0] is the
    decoded posterior of the start frame, every later frame comes from the prior alone.
    """
    ### BEGIN SOLUTION
    h, _ = wm._init(norm_obs0.shape[0])
    z = wm.filter_step(h, norm_obs0)          # the one real frame this dream ever sees
    hs, zs, actions = [h], [z], []
    for _ in range(horizon):
        a = policy(torch.cat([h, z], dim=-1))
        h, z = wm.img_step(h, z, a)           # the prior alone: nothing corrects it from here on
        hs.append(h)
        zs.append(z)
        actions.append(a)
    return wm.decode(torch.stack(hs), torch.stack(zs)), torch.stack(actions)
    ### END SOLUTION


# %% nbgrader={"grade": true, "grade_id": "dream_impl_tests", "locked": true, "points": 3, "schema_version": 3, "solution": false}
### BEGIN HIDDEN TESTS
# While grading: record your function's raw results on the grader's cases; the verdict
# is made outside this kernel (autograde/checks.py).
__import__("pusht.grading").grading.submit("dream_impl_tests", dream)
### END HIDDEN TESTS
from pusht.agent import ActorCritic
from pusht.world_model import WorldModel

torch.manual_seed(0)
_wm = WorldModel(6, 2, latent_dim=4, hidden_dim=8, embed_dim=5).eval()
_policy = policy_of(ActorCritic(8 + 4, 2, 8))
_o0 = torch.randn(3, 6)
with torch.no_grad():
    _obs, _act = dream(_wm, _policy, _o0, 5)
    _h0 = torch.zeros(3, 8)
    _first = _wm.decode(_h0, _wm.filter_step(_h0, _o0))
assert tuple(_obs.shape) == (6, 3, 6), \
    f"decoded observations should have shape (horizon+1, B, D) = (6, 3, 6); got {tuple(_obs.shape)}"
assert tuple(_act.shape) == (5, 3, 2), \
    f"actions should have shape (horizon, B, A) = (5, 3, 2); got {tuple(_act.shape)}"
assert torch.allclose(_obs[0], _first, atol=1e-6), \
    "frame 0 should be the decoded start state: h = 0 and z = wm.filter_step(h, norm_obs0)"
assert float(_act.abs().max()) <= 1.0, "actions come from the policy, so they lie in [-1, 1]"
print("visible tests passed")

# %% [markdown]
# ## Exercise 1 · Predict, then run
#
# The trained policy now runs from held-out starts it has never seen, in the dream and in the
# real simulator, on two seeds (two independently trained world models and actors). Alongside
# it, the same evaluation runs a **control**: a pusher that never moves (zero actions), in the
# dream and in reality, from the same starts. What do you expect, over the 10 s evaluation?

# %%
display(Markdown("\n".join(f"* **({k})** {v}" for k, v in nb04.EX1_OPTIONS.items())))

# %% [markdown]
# Lock your prediction below: a letter and one sentence of why. The experiment refuses to run
# until you have, and the first lock is the one that counts.

# %% nbgrader={"grade": false, "grade_id": "ex1_prediction", "locked": false, "schema_version": 3, "solution": true}
PREDICTION = ""     # "a", "b", "c" or "d"
REASON = ""         # one sentence: why?
### BEGIN SOLUTION
PREDICTION = "b"
REASON = ("The actor maximises a reward read off the block the model imagines, so it will find "
          "pushes that move the dreamed block but not the real one.")
### END SOLUTION
receipt = lock_prediction("ex1", PREDICTION, REASON)

# %% [markdown]
# **One sentence, before the reconciliation.** Training is built to raise the imagined reward.
# If it does, what exactly has the actor become good at, and why could that skill be worth
# nothing in the real simulator? Write your answer in the cell below.

# %% [markdown] nbgrader={"grade": true, "grade_id": "ex1_sentence", "locked": false, "points": 1, "schema_version": 3, "solution": true}
# If training raised the imagined reward, the actor got good at its training dreams: choosing
# pusher motions after which the model *decodes* the block nearer the target and better turned.
# Nothing guarantees those motions move the real block: the dreamed block can get there through the
# model's errors (it may move without real contact, or slide toward the poses most common in the
# expert data), and the actor's gradient pays for such errors exactly as for real pushes. A skill
# at being rewarded by the model is worth nothing in the real simulator wherever the model is wrong.
# (Whether your actor did learn such a skill is measured below: the *training* term of the gap.)

# %% [markdown]
# Now the experiment. For each seed it trains the world model and the actor (or loads them from
# the cache that notebooks 01 and 03 left behind), then evaluates the policy and the controls in
# both worlds with `two_world_eval`, handing it **your** `dream`. (Its first training also trains
# the third seed that the table at the end of this notebook adds, side by side with the others.)

# %%
EX1_SEEDS = [SEED, SEED + 1]                 # two independently trained seeds, from your SEED


def experiment_ex1(seeds):
    """Train (or load) each seed, then evaluate the same policy in the dream and in reality."""
    out = {}
    for seed in seeds:
        res = run_seed(seed)
        T = res.data.torch(cfg.device)
        eval_seeds = start_seeds(EVAL_SEED_BASE, seed, cfg.eval_episodes)
        metrics, rollouts = two_world_eval(res.wm, res.agent, res.init_agent, eval_seeds, cfg.eval_horizon,
                                           T["mean"], T["std"], dream_fn=dream, train_horizon=cfg.imag_horizon)
        out[seed] = {"res": res, "metrics": metrics, "rollouts": rollouts}
    return out


results = run_exercise("ex1", experiment_ex1, EX1_SEEDS)

# %%
n_eval = cfg.eval_episodes
M = {s: {**r["metrics"], "eval_episodes": n_eval} for s, r in results.items()}   # n sets each test's k
mismatch = max(abs(M[s]["imagined_return_per_step"] - r["res"].metrics["imagined_return_per_step"])
               for s, r in results.items())
display(Markdown(nb04.dream_check_text(mismatch)))
reconcile("ex1", *nb04.ex1_reconciliation(M, n_eval))   # the words python -m pusht.exercise ex1 prints too
display(Markdown(nb04.exploitation_text(M, min(cfg.imag_horizon, cfg.eval_horizon))))

# %% [markdown] nbgrader={"grade": false, "grade_id": "ex1_order", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": true}
# **Completion point (Exercise 1).** Earned from the receipts in your cell outputs: the prediction
# receipt must come before the experiment receipt. There is nothing to write here; just keep
# the outputs when you save and hand in the notebook.
#
# Only the receipt printed by the prediction cell and the one printed by the experiment cell count, in that order (execution counts and times). Being honest here is on you: restarting, deleting `.pusht_predictions.json` and re-running everything in order would leave a record the grader cannot tell from an honest one, and the point is worth far less than the prediction itself.

# %% [markdown]
# ## Same policy, two worlds
#
# Here is the headline for one seed, drawn from the evaluation your `dream` just ran. Each dot
# is one held-out start; the bars are the means. The right panel counts a start as solved when
# the block is within the environment's success thresholds at some step. Reality applies that
# test itself; for the dream we apply the same thresholds to the decoded block pose.

# %%
head = results[cfg.seed] if cfg.seed in results else experiment_ex1([cfg.seed])[cfg.seed]
hm, hr = {**head["metrics"], "eval_episodes": n_eval}, head["rollouts"]
dream_roll, real_roll = hr["dream"], hr["real"]
fig = nb04.fig_two_worlds(dream_roll, real_roll, hm["imagination_gap"], cfg.seed, cfg.eval_horizon * 0.1)
show(fig, "04_two_worlds.png")
display(Markdown(nb04.headline_text(hm, int(nb04.solved_at_some_step(dream_roll).sum()),
                                    int(real_roll.success.sum()), n_eval, PAGE)))

# %% [markdown]
# ### Watch one start in both worlds
#
# The same start, the same policy: the dream on the left, the real simulator on the right. The
# start shown is a *typical* one: the median of all starts ranked by the dream's final block
# distance minus reality's (not the most flattering one).

# %%
i = nb04.median_start(dream_roll, real_roll)
if GRADING:     # rendering the frames is the slowest cell and grades nothing: the autograder skips it
    print("(animation skipped while grading)")
else:
    anim = animate_two_worlds(dream_roll.obs[:, i], real_roll.obs[:, i], every=5 if not cfg.smoke else 2,
                              titles=(f"in the dream (start {i})", f"in the real sim (start {i})"), dpi=50)
    page = anim.to_jshtml(default_mode="once")
    display(HTML(page))
    print(f"(animation: {len(page) / 1e6:.2f} MB)")
display(Markdown(nb04.median_start_text(i, dream_roll, real_roll)))

# %% [markdown]
# ## Who earned the dream's reward? The gap, taken apart
#
# A gap by itself does not prove that the actor *learned to exploit* the dream: the model could
# be optimistic all on its own. `two_world_eval` ran three policies from exactly the same starts,
# each in both worlds: **zero actions** (in reality nothing can happen to the block), the
# **untrained actor** (its weights before a single update), and the **trained actor**. The gap
# splits exactly into three terms (`pusht/analysis.py`):
#
# * **drift** = zero-action dream minus zero-action reality: the model's optimism with nobody
#   pushing;
# * **motion** = what the untrained actor's actions add in the dream beyond what they add in
#   reality;
# * **training** = what training adds in the dream beyond what it adds in reality: positive when
#   the actor learned something only the dream pays for, that is, when it exploits the model.
#
# We measure it twice: over the first `imag_horizon` steps, the dreams the actor's gradient
# actually saw, and over the whole evaluation. Each term carries a standard error over the starts.
#
# The reward has two terms, one for the block's distance to the target and one for its yaw error
# (notebook 02), so every number below also splits into a **position** half and a **yaw** half
# that add up to it: they say *what* the dream gets wrong.

# %%
steps = {"train_horizon": min(cfg.imag_horizon, cfg.eval_horizon), "eval_horizon": cfg.eval_horizon}
fig = nb04.fig_decomposition(hm, steps)
show(fig, "04_controls.png")
display(Markdown("\n\n".join(nb04.split_sentence(hm, span, n, hr) for span, n in steps.items())
                 + "\n\n" + nb04.split_story(hm, steps["train_horizon"], hr)))

# %% [markdown]
# The same dreams step by step, beside reality: on the left where the block is, on the right how
# it is turned (its yaw error). The dashed line marks the actor's training horizon; the dotted one
# the length of the clips the world model was trained on. Everything to the right of the dotted
# line is a dream longer than any the model was ever taught. The green line is the expert data's
# mean block pose: the pose the model's normalised units put at zero.

# %%
res_h = head["res"]
data_mean_dist, data_mean_yaw = nb04.typical_pose(res_h.data.mean)   # the expert data's mean block pose
fig = nb04.fig_block_over_time(hr, cfg.imag_horizon, cfg.seq_len, data_mean_dist, data_mean_yaw)
show(fig, "04_block_over_time.png")
display(Markdown(nb04.dip_sentence(hr, cfg.imag_horizon, res_h.data.mean)))
ask(SELF_CHECKS["zero_control"], "")
ask(SELF_CHECKS["two_horizons"], "")

# %% [markdown]
# ## Could the dream recognise success?
#
# Was there anything in the dream for the actor to learn? A control answers that: the **scripted
# expert**, written to solve the real task (the text below says how many starts it solves here),
# runs in the real simulator from the same starts, and its very actions are replayed open-loop in
# the dream (the same `dream`, the actions given instead of chosen). If the dream pays the
# expert's pushes more than standing still, an actor that found those pushes would have been
# rewarded for them: the dream held a learnable signal. If it pays them no more, or less, the
# dream's reward gives an actor no reason to push that way.
#
# A control is only as good as its own stillness: "more than standing still" means something only
# if, in the dream, standing still leaves the block where it is. Where the zero-action dream carries
# a block nobody touches beyond the 2 cm success tolerance, the comparison is reported as invalid,
# and the text reads the expert's own gap instead: what the dream pays the expert's pushes against
# what reality pays the very same pushes.

# %%
fig = nb04.fig_expert_control(hm, steps)
show(fig, "04_expert_control.png")
display(Markdown(nb04.expert_text(hm, steps)))

# %% [markdown]
# ## What did the policy actually do?
#
# Below: the real pusher's path for six starts (the grey T is the block where it spawned), and
# what the reward says the policy did to the real block, against a pusher that never moves.

# %%
fig = nb04.fig_pusher_paths(real_roll, TOUCH_TOL, cfg.eval_horizon * 0.1, cfg.seed)
show(fig, "04_pusher_paths.png")
display(Markdown(nb04.pusher_paths_text(hm, hr, n_eval, TOUCH_TOL)))

# %% [markdown]
# ## Does the policy leave the data the model knows?
#
# The world model was trained on the scripted expert's first 1.6 s of each episode: a pusher
# travelling to the block and the first pushes. Does the deployed policy go elsewhere? Three
# measurements:
#
# * **where the pusher spends its time**: the share of steps with the pusher pinned against a
#   wall, in the expert data and in the policy's real runs;
# * **the model replaying actions it is given**: from each real start, dream under the actions
#   the policy *really* took, and compare the dreamed pusher and block with the real ones, step
#   by step; the same on held-out expert clips for reference;
# * **where the blocks end**: the 10 s dream is many times longer than the model's training
#   clips; do its end points still depend on where they started?

# %%
T_h = res_h.data.torch(cfg.device)
replay = replay_error(res_h.wm, real_roll, T_h["mean"], T_h["std"])
expert_replay = expert_replay_error(res_h.wm, res_h.data.val_obs, res_h.data.val_act, T_h["mean"], T_h["std"])
alive = ~np.isnan(real_roll.rewards)
fig = nb04.fig_distribution_shift(real_roll, dream_roll, np.where(alive, at_wall(real_roll.obs[1:]), np.nan),
                                  float(at_wall(res_h.data.train_obs).mean()), replay, expert_replay, cfg.seq_len)
show(fig, "04_distribution_shift.png")
display(Markdown(nb04.shift_sentence(res_h.metrics, replay=replay, expert_replay=expert_replay)))
ask(SELF_CHECKS["shift"], "")

# %% [markdown]
# ## Is it the seed?
#
# One more seed, and the numbers side by side (the package's own evaluation; the two seeds of
# Exercise 1 were trained above, so they come from memory). The yaw columns split the gap as
# above; the expert column is how much more than standing still the dream pays the scripted
# expert's pushes over the training horizon, valid only where the next column (how far the
# zero-action dream moves a block nobody touches) is within 2 cm; the column after it is the
# expert's own gap, dream minus reality, which needs no such control.

# %%
seed_runs = {s: run_seed(s) for s in tqdm(SEEDS, desc="seeds", leave=False)}
seed_metrics = {s: r.metrics for s, r in seed_runs.items()}
display(Markdown(nb04.seeds_table(seed_metrics) + "\n\n"
                 + nb04.seeds_sentence(seed_metrics, {s: r.rollouts for s, r in seed_runs.items()})))

# %% [markdown]
# ## Read the real thing: DreamerV3
#
# Our loop is a miniature of Danijar Hafner's DreamerV3 (`danijar/dreamerv3`; the two files
# below are unchanged at commit `e3f0224`). Read these places next to our package:
#
# * **Imagining.** `dreamerv3/rssm.py`, method `RSSM.imagine`: a scan that rolls the prior
#   forward under a policy function, with no observations at all. The policy is given a
#   stop-gradient copy of the state. Ours is `pusht.imagination.imagine` (training) and the
#   `dream` you wrote (evaluation).
# * **The actor and critic losses.** `dreamerv3/agent.py`, function `imag_loss`. It builds the
#   same lambda-return we use (`lambda_return`, each value paired with the reward received on
#   arriving in that state, discounted by a *learned* continue probability). Then the actor
#   learns by **REINFORCE**: log-probability of the imagined action times a stop-gradient
#   advantage, where advantages are divided by a running estimate of the spread between the 5th
#   and 95th percentiles of the returns, plus an entropy bonus of weight 3e-4 (our `ent_coef`
#   borrows that value). No gradient flows through the dynamics.
# * **Where we part ways.** We differentiate the imagined return *through* the frozen model into
#   the actor (a pathwise gradient), as the first Dreamer did (`danijar/dreamer`, "Dream to
#   Control"). So did DreamerV3's own code for continuous actions at first: from its first commit
#   (January 2023) its `dreamerv3/configs.yaml` defaulted to `actor_grad_cont: backprop`
#   (REINFORCE, `actor_grad_disc: reinforce`, for discrete actions), until commit `2411f7d` of
#   April 2024 removed the option. The author explained in the repository's issue 168 that
#   REINFORCE works almost as well, also handles discrete actions, and is simpler. Note what that
#   means for this notebook: a pathwise gradient hands the actor the model's own derivatives, a
#   very direct way to find where the model is wrong in a flattering direction.
# * **Reward and continue heads.** `self.rew` predicts the reward from the latent state as a
#   two-hot distribution over 255 bins, and `self.con` predicts whether the episode goes on. We
#   read the reward analytically off the decoded block pose and always imagine a fixed number of
#   steps. A learned reward head would not save us: it reads the same imagined state.
# * **A stochastic latent, KL balancing and free bits.** `RSSM.loss` trains a stochastic latent
#   with two KL terms weighted differently, each ignored below 1 nat ("free bits"). Our latent
#   is deterministic and trained with a plain squared error.

# %% [markdown]
# ### We are in good company
#
# A dream that a policy can exploit is a known failure of learning inside a model. *These are
# published figures, quoted, not results of our runs:* in World Models (Ha & Schmidhuber,
# 2018), a controller trained inside a nearly deterministic VizDoom dream (temperature 0.1)
# scored 2086 in the dream and 193 in the real game, below the 210 of a random policy. Making
# the dream noisier (temperature 1.15) made it harder to cheat: 918 in the dream, 1092 in the
# real game.
#
# The known remedies are about data and doubt:
#
# * **close the loop**: run the policy in the real environment, add what it sees to the world
#   model's training data, retrain, repeat. World Models' iterative procedure and Dreamer's own
#   replay loop do this, so wherever the policy goes, real experience corrects the model;
# * **distrust the dream where models disagree**: train an ensemble and penalise the reward where
#   its members disagree (MOPO), or end the imagined episode there (MOReL).
#
# Our chapter so far does neither, on purpose, so that the gap can be seen whole; whether either
# would close it here is a question for a measurement, not for this sentence. Notebook 05 asks
# first whether dreaming further ahead helps.

# %%
display(Markdown(nb04.company_text(hm, steps["train_horizon"])))
