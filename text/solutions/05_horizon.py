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
# # 05 · Dream further? The imagination horizon
#
# Notebook 04 measured the imagination gap: how differently the dream and the real simulator rate
# one and the same policy. Each update, the actor dreams only a short stretch of the future
# (`imag_horizon` steps) and leaves the rest to the critic's estimate. A natural hope is that it
# simply did not look far enough ahead: let it dream longer, and perhaps it plans better, in the
# dream *and* in the world.
#
# This notebook sweeps that horizon on one frozen world model, with several actors per horizon, so
# that you can tell an effect of the horizon from seed-to-seed luck. You predict what happens to
# the gap, run the sweep, and take the answer apart. It closes with what a real Dreamer does about
# model error, what this chapter left out, and what to read next.

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
import time

import numpy as np
from IPython.display import Code, Markdown, display
from tqdm.auto import tqdm

from pusht.config import field_docs
from pusht.imagination import imagine
from pusht.nb import horizon as nb05
from pusht.nb import setup
from pusht.nb.horizon import SELF_CHECKS
from pusht.page import PAGE  # the chapter page's own figures: quoted for comparison only
from pusht.predict import lock_prediction, prediction, reconcile, run_exercise
from pusht.selfcheck import ask
from pusht.sweep import run_many

# the config (reduced while GRADING), the folders under OUT, and show(fig, name): see pusht.nb.setup
# METRICS: one json per (horizon, actor seed)
cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT, metrics="metrics/horizon_sweep")
print(f"config: world model of seed {cfg.seed}, {cfg.imag_iters} policy updates per run, evaluated on "
      f"{cfg.eval_episodes} held-out starts of {cfg.eval_horizon} steps" + ("  [SMOKE: tiny config]" if cfg.smoke else ""))

# %%
from pusht.nb.timing import here, time_note

time_note("05_horizon")   # how long this notebook takes, measured (make times)

# %% [markdown]
# ## Where the horizon enters
#
# Here is the imagination rollout the actor trains on, straight from the package. `horizon` is the
# number of prior steps it rolls forward from each real start state before the lambda-return hands
# over to the critic. The evaluation does not use it: every policy is judged by dreaming the same
# fixed number of steps (`eval_horizon`) from the same held-out starts, and by running it for as
# many steps in the real simulator, so runs trained with different horizons are compared on equal
# terms.
#
# `actor_seed` is the other knob of this notebook: on the same frozen world model, it changes only
# the actor-critic's initial weights and the random dreams it trains on.

# %%
display(Code(inspect.getsource(imagine), language="python"))
docs = field_docs()
display(Markdown(f"`imag_horizon`, as the config documents it: *{docs['imag_horizon']}* The default is "
                 f"**{cfg.imag_horizon}** steps; the evaluation runs **{cfg.eval_horizon}**.\n\n"
                 f"`actor_seed`: *{docs['actor_seed']}*"))

# %%
ask(SELF_CHECKS["same_model"], "")

# %% [markdown]
# ## Exercise 2 · Predict, then run
#
# We train the actor with three imagination horizons, **5, 15 and 30 steps** (0.5, 1.5 and 3 s of
# dreamed time per update), and at each horizon with four actor seeds (0, 1, 2, 3), all on the
# **same frozen world model** of seed `SEED`. Every one of the twelve policies is then evaluated the
# same way, in the dream and in reality.
#
# The number to predict is the **imagination gap**: imagined minus real reward per step over the
# whole evaluation. Positive means the dream rates the policy above what reality pays it; negative
# means below. The four actors at one horizon give a spread: how much the gap moves when nothing
# changes but the actor's seed. A change with the horizon counts only if it is larger than that
# spread allows **and** at least a minimum effect that matters (the rule is printed with the options
# below; the function that applies it is shown after the run). The letter is decided by the shortest horizon
# against the longest; the 15-step runs show the way between.
#
# From 5 to 30 steps, what happens to the gap?

# %%
display(Markdown(nb05.EX2_RULE + "\n\n" + "\n".join(f"* **({k})** {v}" for k, v in nb05.EX2_OPTIONS.items())))

# %% nbgrader={"grade": false, "grade_id": "ex2_prediction", "locked": false, "schema_version": 3, "solution": true}
PREDICTION = ""     # "a", "b" or "c"
REASON = ""         # one sentence: why?
### BEGIN SOLUTION
PREDICTION = "a"
REASON = ("A longer training dream gives the actor more steps of the model's wrong block dynamics to "
          "optimise against, so the dream should rate it higher while reality pays it the same.")
### END SOLUTION
receipt = lock_prediction("ex2", PREDICTION, REASON)

# %% [markdown]
# **One sentence, before the run.** Every run uses the same frozen world model and the same
# evaluation. How, then, can the horizon the actor was trained with change how far the evaluation
# dream over- or underrates the policy? Write your answer in the cell below.

# %% [markdown] nbgrader={"grade": true, "grade_id": "ex2_sentence", "locked": false, "points": 1, "schema_version": 3, "solution": true}
# The horizon changes the policy, not the model: the actor is optimised only on what the dream shows
# it within its H training steps (plus the critic's estimate of what follows), so each horizon gives
# a different policy, and the evaluation dream can misjudge different policies by different amounts,
# within the span their training saw and in the later steps it never reached: a longer horizon can let the actor exploit
# more of the model's errors, a shorter one can leave it doing, in those later steps, what the model
# misjudges; reality does not share those errors, so the gap moves with the policy while the model
# stays the same.

# %% [markdown]
# The sweep: three horizons times four actor seeds. Each run loads the world model of `SEED` from
# the cache (an earlier notebook may have left it there; otherwise one run trains it first and the
# others wait for it) and trains only its actor-critic; a run that an earlier notebook already
# trained with the same config is loaded too. The runs do not depend on each other, so
# `run_many` trains them side by side, one worker process per CPU core (each run uses one core):
# every run gives exactly the numbers it gives on its own; only the wall-clock time changes.

# %%
EX2_HORIZONS, EX2_ACTOR_SEEDS = [5, 15, 30], list(range(8))
if GRADING:     # the autograder needs the cells to run, not the spread: the two ends, two seeds each
    EX2_HORIZONS, EX2_ACTOR_SEEDS = [5, 30], [0, 1]


def experiment_ex2(horizons, actor_seeds):
    """Train and evaluate one actor per (horizon, actor seed) on the world model of SEED."""
    keys = [(h, a) for h in horizons for a in actor_seeds]
    runs = run_many([cfg.replace(imag_horizon=h, actor_seed=a) for h, a in keys], cache_dir=CACHE,
                    model_cache=CACHE, progress=tqdm, desc="sweep runs")
    for (h, a), res in zip(keys, runs):
        (METRICS / f"seed{cfg.seed}_h{h}_actor{a}.json").write_text(
            json.dumps(res.metrics, sort_keys=True, indent=2) + "\n")
    return dict(zip(keys, runs))


t0 = time.perf_counter()
sweep = run_exercise("ex2", experiment_ex2, EX2_HORIZONS, EX2_ACTOR_SEEDS)
print(f"{len(sweep)} runs" + ("" if GRADING else f" in {time.perf_counter() - t0:.0f} s {here()}"))   # no wall-clock times in graded feedback

# %%
n_eval = cfg.eval_episodes
M = {key: res.metrics for key, res in sweep.items()}
display(Markdown(nb05.sweep_table(M, n_eval)))

# %% [markdown]
# The same numbers as a picture. Each dot is one actor seed (coloured by horizon, drawn just left of its
# horizon); the black bar beside the dots is their mean with a 95% interval from the seeds' own spread.

# %%
by = lambda key: nb05.by_horizon(M, key)        # {horizon: [value per actor seed]}
gaps, imagined, real = by("imagination_gap"), by("imagined_return_per_step"), by("real_return_per_step")
fig = nb05.fig_gap_vs_horizon(gaps, imagined, real, cfg.eval_horizon)
show(fig, "05_gap_vs_horizon.png")
display(Markdown(nb05.interval_note(len(EX2_ACTOR_SEEDS))))

# %% [markdown]
# ### How "changed" is judged
#
# Every verdict below asks two things, and says which test it used and what it found:
#
# * **beyond the noise**: a t-test on the per-seed values (for two horizons, paired by actor seed:
#   every horizon trains the same actor seeds, so seed 0 at 5 steps is compared with seed 0 at 30
#   steps, and what a seed brings to both cancels; a one-sample t-test, for "differs from zero"). The
#   difference must exceed `k` standard errors, where the
#   standard error comes from the spread across actor seeds and `k` is Student's t at the test's
#   degrees of freedom: if nothing had changed, a difference that large would turn up in about one
#   sweep in 20. Each verdict prints `|t|` (the difference in standard errors) beside `k`.
# * **large enough to matter**: at least `MIN_REWARD_EFFECT` reward per step, the reward of holding
#   the block the 2 cm success tolerance nearer the target on every step (for a block distance, the
#   2 cm tolerance itself).
#
# A difference that passes the first and fails the second is "detected, but smaller than the minimum
# effect that matters", not a change. Here is the function that judges the gap:

# %%
display(Code(inspect.getsource(nb05.gap_change), language="python"))
terms = {t: by(f"gap_{t}_eval_horizon") for t in nb05.TERMS}          # the gap's three terms (below)
reconcile("ex2", *nb05.ex2_reconciliation(M, n_eval, cfg.eval_horizon,      # python -m pusht.exercise ex2
                                          predicted=getattr(prediction("ex2"), "choice", None)))

# %% [markdown] nbgrader={"grade": false, "grade_id": "ex2_order", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": true}
# **Completion point (Exercise 2).** Earned from the receipts in your cell outputs: the prediction
# receipt must come before the experiment receipt. There is nothing to write here; just keep
# the outputs when you save and hand in the notebook.
#
# Only the receipt printed by the prediction cell and the one printed by the experiment cell count, in that order (execution counts and times). Being honest here is on you: restarting, deleting `.pusht_predictions.json` and re-running everything in order would leave a record the grader cannot tell from an honest one, and the point is worth far less than the prediction itself.

# %%
ask(SELF_CHECKS["negative_gap"], "")

# %% [markdown]
# ## Where the change comes from
#
# Notebook 04 split the gap into three terms that add up to it exactly (`pusht/analysis.py`):
# **drift**, the dream's error with a pusher that never moves; **motion**, what the untrained actor's
# actions add; **training**, what training the actor adds in the dream beyond what it adds in
# reality. Here is that split for every run of the sweep, over the whole evaluation, and then the gap
# split the other way: into the reward's position half (where the block is) and yaw half (how it is
# turned).
#
# Before you look at the numbers, answer this one:

# %%
ask(SELF_CHECKS["drift_same"], "")

# %%
fig = nb05.fig_gap_terms(terms, gaps)
show(fig, "05_gap_terms.png")
m0 = next(iter(M.values()))                     # zero actions: the same rollouts in every run
display(Markdown(nb05.rule_text(len(EX2_ACTOR_SEEDS)) + "\n\n"
                 + nb05.terms_sentence(terms, imagined, by("untrained_actor_dream_return_per_step"))
                 + "\n\n" + nb05.halves_sentence(by("imagination_gap_position_eval_horizon"),
                                                 by("imagination_gap_yaw_eval_horizon"),
                                                 by("gap_drift_position_eval_horizon"),
                                                 by("gap_drift_yaw_eval_horizon"),
                                                 (m0["zero_dream_final_yaw_err_deg"], m0["zero_real_final_yaw_err_deg"]))
                 + "\n\n" + nb05.own_horizon_sentence(by("imagination_gap_train_horizon"))))

# %% [markdown]
# Step by step: the mean distance of the block from the target over the evaluation, in the dream
# (solid) and in reality (dashed), for each horizon. The dotted lines mark where each horizon's
# training dreams ended. The black lines are the control: a pusher that never moves, from the same
# starts. Whatever the dream does to that block, it does without any pushing.

# %%
curves = {h: {w: np.stack([nb05.mean_block_distance(sweep[h, a].rollouts[w]) for a in EX2_ACTOR_SEEDS])
              for w in ("dream", "real")} for h in EX2_HORIZONS}
run0 = next(iter(sweep.values()))               # zero actions: the same rollouts in every run
zero = {w: nb05.mean_block_distance(run0.rollouts[f"{w}_zero"]) for w in ("dream", "real")}
fig = nb05.fig_block_over_time(curves, zero=zero)
show(fig, "05_block_over_time.png")
spawn = float(np.mean([m["spawn_tee_dist"] for m in M.values()]))
text = nb05.block_sentence(by("imagined_final_tee_dist"), by("real_final_tee_dist"), spawn, curves,
                           zero_final=m0["zero_action_dream_final_tee_dist"])
if PAGE.get("horizon_sweep_5_vs_30"):
    text += (f"\n\nFor comparison, the chapter page summarises its own 5-versus-30 sweep as: "
             f"*{PAGE['horizon_sweep_5_vs_30']}*. The numbers above are what this run measured.")
display(Markdown(text))

# %% [markdown]
# ## The conclusion, from this run

# %%
display(Markdown(nb05.conclusion(gaps, real, terms)))

# %%
ask(SELF_CHECKS["spread"], "")

# %% [markdown]
# ## What a real Dreamer does about model error
#
# This chapter trained its world model once, on expert data, and froze it. Dreamer never does that.
# Its world model keeps learning from what the current policy really does:
#
# * **DreamerV1** (`danijar/dreamer`, `dreamer.py`): the dataset starts with 5,000 steps of random
#   actions (`prefill`). From then on the agent acts in the real environment with its current
#   policy plus Gaussian exploration noise (`expl_amount = 0.3`), every episode it plays is saved to
#   the dataset, and every 1,000 environment steps (`train_every`) it makes 100 training steps
#   (`train_steps`). Each training step updates the world model on sequences drawn from everything
#   collected so far, the agent's own episodes included, and the actor and the value network on
#   dreams that start from those sequences' states.
# * **DreamerV3** (`danijar/dreamerv3`, `embodied/run/train.py`): the same loop, run continuously.
#   Every environment step the policy takes goes into a replay buffer, and the agent trains on
#   replayed sequences at a fixed ratio to the steps it collects (`train_ratio: 32` in
#   `dreamerv3/configs.yaml`); one update (`Agent.loss` in `dreamerv3/agent.py`) trains the world
#   model and, from states of those same replayed sequences, the actor-critic in imagination.
#
# So when a policy heads for states the model gets wrong, those states soon appear in the replay
# data, with what really happened there, and the model is trained on them. Both versions imagine 15
# steps per update by default (`horizon = 15` in DreamerV1, `imag_length: 15` in DreamerV3), the
# same as this chapter's default. Notebooks 01-05 do not run that loop; notebook 06 does, round by
# round, and measures in both worlds what it buys on PushT.

# %% [markdown]
# ## What we cut
#
# This chapter is small on purpose. Here is what a real Dreamer has and we do not, and what each
# omission costs.
#
# * **The real-data loop** (above). Here we trained the model on the expert's data once. Nothing in
#   that data was chosen by our own policy, so the model was never corrected on the states the
#   policy seeks out. Notebook 06 adds the loop and measures it.
# * **Learned reward and continue heads.** Dreamer predicts the reward, and whether the episode
#   goes on, from its latent state, because from pixels it has no other way to know. We read the
#   reward straight off the decoded block pose and always dream a fixed number of steps. That is
#   fair here (PushT's reward is a known function of the pose) and it keeps the failure in plain
#   sight. A learned head reads the same imagined state, so it inherits the model's picture of the
#   block, wrong or right.
# * **A stochastic latent, with KL balancing.** Our latent is deterministic, so the dream cannot say
#   "I am not sure where the block is": it always commits to one answer, and the actor can optimise
#   against that answer as if it were true. DreamerV3's latent is stochastic (categorical), trained
#   with a balanced KL loss and free bits. World Models (below) reported that policies trained in a
#   noisier version of their dream (a higher sampling temperature) transferred to the real game far
#   better than policies trained in a nearly deterministic one.
# * **How good the model would need to be.** Notebook 01 measured what our model learned and what it
#   did not; this notebook measures how the same model's rating of a policy depends on how that policy
#   was trained. Whether a bigger model, or more data of some other kind, would close the gap
#   is not something these notebooks measure.
#

# %%
display(Markdown(nb05.takeaway(gaps)))

# %% [markdown]
# ## Read next
#
# Each of these takes on the problem this chapter measured: a learned model rates a policy by its own
# errors, not by what reality pays, and a policy trained inside it can be led by those errors, or
# learn to exploit them.
#
# * **World Models**, Ha & Schmidhuber (2018). A controller trained entirely inside a learned dream;
#   it shows a policy exploiting a near-deterministic dream, and a noisier dream resisting it.
# * **PETS**: Chua et al. (2018), *Deep Reinforcement Learning in a Handful of Trials using
#   Probabilistic Dynamics Models*. An ensemble of probabilistic models and planning that re-plans
#   every step, so the model's uncertainty enters every decision.
# * **MBPO**: Janner et al. (2019), *When to Trust Your Model: Model-Based Policy Optimization*.
#   Model error compounds with rollout length; so it uses short model rollouts branched from real
#   states: the horizon question of this notebook, answered with a bound.
# * **DreamerV1**: Hafner et al. (2020), *Dream to Control: Learning Behaviors by Latent
#   Imagination*. The actor-critic of this chapter: lambda-returns in imagination, the actor's
#   gradient through the model, and the real-data loop that keeps the model honest.
# * **DreamerV2**: Hafner et al. (2021), *Mastering Atari with Discrete World Models*. Categorical
#   latents and KL balancing: the stochastic latent this chapter cut.
# * **DreamerV3**: Hafner et al. (2023), *Mastering Diverse Domains through World Models*. The
#   real-data loop and one set of hyperparameters across many domains; its code (`imag_loss` in
#   `dreamerv3/agent.py`) trains the actor by REINFORCE instead of backpropagating through the model.
# * **MOPO**: Yu et al. (2020), *Model-based Offline Policy Optimization*. Our setting is offline
#   (a fixed dataset, a frozen model): MOPO subtracts an estimate of the model's uncertainty, read
#   from an ensemble of models, from the reward, so the policy is paid less where the model is unsure.
# * **MOReL**: Kidambi et al. (2020), *Model-Based Offline Reinforcement Learning*. Also offline: a
#   pessimistic model that ends the episode with a penalty wherever the ensemble disagrees, so the
#   policy cannot profit from states the data never covered.
