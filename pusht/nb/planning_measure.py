"""What notebook 07 measures: the ladder of world models and each one's gate, the data's zero actions,
the planner and the actor in the real sim on the same starts, and the comparisons between them.

Everything here returns plain numbers (and the rollouts they came from); the words are in
``planning_words``, the claims that guard them in ``planning_claims``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pusht.data import EVAL_SEED_BASE, KINDS, start_seeds
from pusht.env import SUCCESS_ANG, SUCCESS_POS, obs_to_pose
from pusht.evaluate import Rollout, dream_rollout, zero_policy
from pusht.gate import gate_rollouts, read
from pusht.plan import NOTEBOOK_PLAN, SMOKE_PLAN, PlanSettings, ladder, plan_rollout
from pusht.split import per_start, se
from pusht.stats import MIN_REWARD_EFFECT, beyond, k_for, wilson

# The ladder's rungs as the notebook's tables name them, in order, and as its sentences do.
LABELS = {"chapter": "the chapter's model", "data": "+ richer data", "data+delta": "+ richer data + changes",
          "data+size": "+ richer data + width", "recipe": "+ richer data + changes + width (the recipe)"}
SAY = {"chapter": "the chapter's model", "data": "the chapter's model on the richer data",
       "data+delta": "the model predicting changes, on the richer data",
       "data+size": "the twice-as-wide model, on the richer data", "recipe": "the recipe's model"}


def settings(cfg) -> PlanSettings:
    """The notebook's planner: ``plan.NOTEBOOK_PLAN`` (``SMOKE_PLAN`` for a smoke config)."""
    return PlanSettings(**(SMOKE_PLAN if cfg.smoke else NOTEBOOK_PLAN))


def starts(cfg, s: PlanSettings) -> list[int]:
    """The held-out starts every measurement of the notebook uses: the first ``s.starts`` of the
    chapter's evaluation starts (the actor's evaluation begins with the same ones)."""
    return start_seeds(EVAL_SEED_BASE, cfg.seed, s.starts)


def configs(cfg) -> dict:
    """``{rung: Config}`` of the ladder (``plan.ladder``) on top of the notebook's config."""
    return {name: cfg.replace(**over) for name, over in ladder(cfg.smoke).items()}


# --- the gate, per model ---------------------------------------------------------------------------
@dataclass
class Rung:
    """One world model of the ladder and what its gate read, at the planner's horizon."""

    name: str
    stage: object                      # wm_stage.WorldModelStage
    gate: dict                         # gate.read at the planner's horizon
    signal: np.ndarray                 # (B,) the dream's expert signal per start (reward/step)
    moved: np.ndarray                  # (B,) how far the zero-action dream moved the untouched block (m, largest)
    toward: np.ndarray                 # (B,) how much nearer the target that block ends in the dream (m)
    drift_curve: np.ndarray = field(repr=False, default=None)   # (T+1,) mean block displacement, eval horizon
    seconds: float = float("nan")      # wall time of training (or loading) it and reading its gate

    @property
    def label(self) -> str:
        return LABELS.get(self.name, self.name)

    @property
    def say(self) -> str:
        return SAY.get(self.name, self.name)


def read_rung(name: str, stage, seeds, s: PlanSettings, eval_horizon: int, device: str = "cpu") -> Rung:
    """The gate of one trained world model (``stage``) on ``seeds``: at the planner's horizon (the
    verdict), and the zero-action dream's drift over the whole evaluation (the picture)."""
    T = stage.data.torch(device)
    mean, std = T["mean"], T["std"]
    ro = gate_rollouts(stage.wm, seeds, s.horizon, mean, std)
    g = read(ro)
    signal = per_start(ro["dream_expert"], None) - per_start(ro["dream_zero"], None)
    obs = ro["dream_zero"].obs
    moved = np.linalg.norm(obs[:, :, 2:4] - obs[:1, :, 2:4], axis=-1).max(0)
    _, tee = obs_to_pose(obs)
    dist = np.linalg.norm(tee[..., :2], axis=-1)                       # (T+1, B) block to target, m
    long = dream_rollout(stage.wm, zero_policy, ro["real_expert"].obs[0], eval_horizon, mean, std)
    curve = np.linalg.norm(long.obs[:, :, 2:4] - long.obs[:1, :, 2:4], axis=-1).mean(1)
    return Rung(name, stage, g, signal, moved, dist[0] - dist[-1], curve)


def paired(a: np.ndarray, b: np.ndarray) -> dict:
    """``a - b`` per start, averaged, with its standard error, k (Student's t over the starts) and the
    verdict both ways (beyond k standard errors and at least the minimum effect). The one-sample test
    of ``stats.sign_test`` on the differences, as the notebook's claims read it: a dict of plain
    numbers, NaN starts (an episode with no steps) dropped, the standard error never snapped to 0."""
    d = np.asarray(a, float) - np.asarray(b, float)
    d = d[~np.isnan(d)]
    k = k_for(len(d))
    diff, s = float(d.mean()), se(d)
    return {"diff": diff, "se": s, "k": k, "min_effect": MIN_REWARD_EFFECT,
            "up": beyond(diff, s, k, MIN_REWARD_EFFECT, +1), "down": beyond(diff, s, k, MIN_REWARD_EFFECT, -1)}


def shares(rungs: dict) -> dict:
    """The 2x2 on the richer data: each model change's effect on the dream's expert signal, with the
    other change absent and present (paired over the same starts)."""
    r = rungs
    return {"delta_alone": paired(r["data+delta"].signal, r["data"].signal),
            "delta_with_size": paired(r["recipe"].signal, r["data+size"].signal),
            "size_alone": paired(r["data+size"].signal, r["data"].signal),
            "size_with_delta": paired(r["recipe"].signal, r["data+delta"].signal),
            "data": paired(r["data"].signal, r["chapter"].signal)}


# --- the data's zero actions -----------------------------------------------------------------------
def on_target(obs: np.ndarray) -> np.ndarray:
    """Whether the block is within the success tolerance of the target (position and angle)."""
    _, tee = obs_to_pose(obs)
    return (np.linalg.norm(tee[..., :2], axis=-1) < SUCCESS_POS) & (np.abs(tee[..., 2]) < SUCCESS_ANG)


def zero_census(data) -> dict:
    """Where a zero action (both components exactly 0) appears in the training data: how many
    steps, and of those, how many with the block on the target (the padding after an early
    success) and how many with the block off it; per kind of sequence (``data.KINDS``)."""
    act, obs = data.train_act, data.train_obs
    zero = np.all(act == 0.0, axis=-1)                                   # (N, T)
    done = on_target(obs[:, :-1])                                        # the block before the step
    kinds = data.train_kind if data.train_kind is not None else np.zeros(len(act), dtype=np.int8)
    out = {"steps": int(zero.size), "zero": int(zero.sum()), "zero_on_target": int((zero & done).sum()),
           "zero_off_target": int((zero & ~done).sum()), "sequences": int(len(act))}
    out["zero_share"] = out["zero"] / out["steps"]
    out["by_kind"] = {KINDS[k]: {"sequences": int((kinds == k).sum()), "zero": int(zero[kinds == k].sum()),
                                 "zero_off_target": int((zero & ~done)[kinds == k].sum())}
                      for k in np.unique(kinds)}
    return out


# --- the planner and the actor in the real sim -----------------------------------------------------
def outcome(rollout, zero, n: int | None = None) -> dict:
    """A policy's real result on the starts of ``zero`` (the zero-action control, same starts):
    success k/n with its Wilson interval, reward per step with its standard error, its paired
    difference from zero actions (and the verdict), final distance (m) and yaw error (degrees)."""
    n = n or len(rollout.success)
    sl = slice(0, n)
    r, z = rollout.return_per_step[sl], zero.return_per_step[sl]
    k = int(rollout.success[sl].sum())
    lo, hi = wilson(k, n)
    vs = paired(r, z)
    _, tee = obs_to_pose(rollout.obs[-1, sl])
    return {"successes": k, "n": n, "rate": k / n, "low": lo, "high": hi,
            "reward": float(np.nanmean(r)), "reward_se": se(r[~np.isnan(r)]),
            "minus_zero": vs["diff"], "minus_zero_se": vs["se"], "k": vs["k"], "min_effect": vs["min_effect"],
            "beats_zero": vs["up"], "below_zero": vs["down"],
            "final_dist": float(np.linalg.norm(tee[:, :2], axis=-1).mean()),
            "final_yaw_deg": float(np.degrees(np.abs(tee[:, 2])).mean())}


def succeeds(o: dict) -> bool:
    """The exercise's "succeeds in reality": solves at least one held-out start AND earns more per
    step than zero actions from the same starts, beyond the noise and by the minimum effect."""
    return o["successes"] >= 1 and o["beats_zero"]


@dataclass
class Ex4Result:
    """Exercise 4's experiment: the actor and the planner in the recipe's model, the planner in the
    chapter's model, and the two controls, all on the same held-out starts."""

    outcomes: dict                     # {"planner", "planner_chapter", "actor", "zero", "expert"}: outcome()
    rollouts: dict                     # the same keys: real-sim Rollouts (the actor's cut to the starts)
    actor_dream: object                # the actor's dream of the same starts (Rollout)
    dream_zero: object                 # zero actions in the same dream (Rollout): the actor's dream's control
    planned: list                      # plan_rollout's record for the recipe's planner
    actor_metrics: dict                # the actor run's metrics.json
    gates: dict                        # {"planner": gate, "planner_chapter": gate} the models' gates
    seconds: dict = field(default_factory=dict)


def plan_in(stage, seeds, horizon: int, s: PlanSettings, device="cpu", progress=None, update=None, record=None):
    T = stage.data.torch(device)
    return plan_rollout(stage.wm, seeds, horizon, T["mean"], T["std"], s, progress=progress, update=update,
                        record=record)


def cut(rollout, n: int):
    """The first ``n`` starts of a rollout."""
    return Rollout(obs=rollout.obs[:, :n], actions=rollout.actions[:, :n], rewards=rollout.rewards[:, :n],
                   pos_err=rollout.pos_err[:, :n], success=rollout.success[:n])


def actor_readings(res: Ex4Result, train_horizon: int) -> dict:
    """The actor against its controls, paired over the starts: its dream's rating minus the same dream's
    zero actions (``dream_vs_zero``), and its dream minus reality over the whole evaluation
    (``gap_eval``) and over the first ``train_horizon`` steps, those it learns from (``gap_train``)."""
    dream, real = res.actor_dream, res.rollouts["actor"]
    return {"dream": float(dream.return_per_step.mean()), "dream_zero": float(res.dream_zero.return_per_step.mean()),
            "dream_vs_zero": paired(dream.return_per_step, res.dream_zero.return_per_step),
            "gap_eval": paired(dream.return_per_step, real.return_per_step),
            "gap_train": paired(per_start(dream, train_horizon), per_start(real, train_horizon))}
