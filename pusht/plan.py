"""Planning in the learned model: CEM model-predictive control in the frozen world model.

    python -m pusht.plan --seed 0            # the recipe below, 30 held-out starts (4-8 min on one core)
    python -m pusht.plan --seed 0 --smoke    # a few seconds
    python -m pusht.plan --seed 0 --serial 5 # also plan 5 starts one at a time: batching's speed-up

No actor. At every real step, for every start still running:

1. **filter**: the model's state ``(h, z)`` given the true observations so far (as the real
   evaluation does: ``z = posterior(h, encoder(o_t))``, ``h`` carried by the GRU under the actions
   taken);
2. **plan** by the cross-entropy method: sample ``samples`` action sequences of ``horizon`` steps,
   each piecewise constant over ``knots`` equal pieces (``knots`` x 2 numbers per plan), from a
   Gaussian per knot, clipped to [-1, 1]; dream each from ``(h, z)`` with the prior; score it;
   refit the Gaussian to the ``elites`` best; ``iters`` times;
3. **act**: the first step of the final mean, in the real sim; then filter the new frame and plan
   again (the next plan starts from this one's mean, its spread reset).

**The objective** (``--objective``) is read off the dreamed frames and averaged over the plan's steps:
the analytic PushT reward (``reward.reward_from_obs``, the env's shaped reward, the number the
evaluation averages over the real steps), or, with ``tolerance``, minus the block's distance and
angle error each in units of the success test's tolerance (2 cm, 10 degrees), which weighs the angle
more (1 cm as 5 degrees, where the reward weighs 1 cm as 3.6). Nothing is learned about either; the
dream supplies the states.

Every start plans in the same model calls: one batched dream of ``starts x samples`` sequences per
CEM iteration (``batched=False`` plans one start at a time, for the benchmark of the speed-up).
Randomness comes from one ``torch.Generator`` per start, seeded by the start's own ``env.reset``
seed (itself derived from the config's seed), so the same seed gives the same actions, and a start
draws the same numbers whether it plans alone or with the others.

The world model is the recipe's (``RECIPE``): ``predicts="delta"``, ``hidden_dim`` 128, and the
richer data (``data.DataMix``: noisy-expert, pause and random-walk sequences beside the expert's).
Every config flag of ``pusht.dreamer`` is accepted and overrides it.
"""

from __future__ import annotations

import dataclasses
import gc
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from .config import Config
from .data import EVAL_SEED_BASE, start_seeds
from .env import ACT_DIM, SUCCESS_ANG, SUCCESS_POS, PushTEnv
from .evaluate import Rollout, expert_rollout, real_rollout, zero_policy
from .gate import as_row, gate, gate_line
from .stats import MIN_REWARD_EFFECT, beyond, k_for, wilson
from .reference import reference
from .reward import reward_from_obs
from .runtime import labelled
from .split import se
from .wm_stage import world_model_stage

# The world model and data the planner is measured with (on top of the chapter's defaults): a delta
# model twice the chapter's width, trained twice as long on 2,600 sequences where the chapter has 300:
# the expert's (600), the noisy expert's (600, noise 0.5), pauses (200), random walks (600) and pokes
# (600). Chosen on seed 0's first 10 held-out starts among five mixes; on 30 starts of seeds 0-1
# (benchmarks/plan_search.csv) the first try, 100 each of noisy, pause and random, did worse than zero
# actions, and the recipe without its pokes solved 7 and 4 where the recipe solved 7 and 5.
RECIPE = dict(wm_predicts="delta", hidden_dim=128, wm_epochs=60, n_episodes=600, data_noisy_episodes=600,
              data_noise=0.5, data_pause_episodes=200, data_random_episodes=600, data_poke_episodes=600)
SMOKE_RECIPE = dict(wm_predicts="delta", hidden_dim=32, data_noisy_episodes=10, data_pause_episodes=10,
                    data_random_episodes=10, data_poke_episodes=10)


OBJECTIVES = ("reward", "tolerance")


@dataclass(frozen=True)
class PlanSettings:
    """The planner's settings (``python -m pusht.plan --help`` prints these lines)."""

    horizon: int = 16
    """Steps of each dreamed plan (1.6 s)."""
    knots: int = 4
    """Pieces of a plan: its action is constant over each of horizon/knots steps."""
    samples: int = 256
    """Plans sampled per CEM iteration, per start."""
    iters: int = 4
    """CEM iterations per real step."""
    elites: int = 25
    """Best plans the Gaussian is refitted to."""
    init_std: float = 0.5
    """Spread of the first Gaussian of every real step (actions live in [-1, 1])."""
    min_std: float = 0.05
    """Floor of the refitted spread, so the search never collapses to a point."""
    warm: bool = True
    """Start each real step's search from the previous step's final mean (else from zero actions)."""
    window: int = 0
    """Real steps the model's state is filtered over before each plan: 0, all of them since the start;
    w, only the last w (from h = 0, as the model's training clips begin), the rest forgotten."""
    starts: int = 30
    """Held-out evaluation starts (the first of the chapter's, env.reset seeds from data.EVAL_SEED_BASE)."""
    objective: str = "reward"
    """What a plan is scored by, averaged over its dreamed steps: reward, the analytic PushT reward (1 cm of
    the block's distance weighs as much as 3.6 degrees of its angle); tolerance, minus the distance and the
    angle error each in units of the success test's tolerance (2 cm, 10 degrees: 1 cm weighs as 5 degrees)."""

    def validate(self) -> None:
        if not isinstance(self.window, int) or self.window < 0:
            raise ValueError(f"window must be a whole number, 0 or more, got {self.window!r}")
        for name in ("horizon", "knots", "samples", "iters", "elites", "starts"):
            v = getattr(self, name)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} must be a whole number, at least 1, got {v!r}")
        if self.knots > self.horizon:
            raise ValueError(f"knots ({self.knots}) must be at most horizon ({self.horizon}): a piece lasts a step or more")
        if self.elites > self.samples:
            raise ValueError(f"elites ({self.elites}) must be at most samples ({self.samples})")
        if self.elites < 2:
            raise ValueError(f"elites must be at least 2 to refit a spread, got {self.elites}")
        if not 0 < self.init_std <= 2:
            raise ValueError(f"init_std must be in (0, 2], got {self.init_std}")
        if not 0 <= self.min_std <= self.init_std:
            raise ValueError(f"min_std must be in [0, init_std], got {self.min_std}")
        if self.objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {self.objective!r}")


SMOKE_PLAN = dict(horizon=8, knots=2, samples=32, iters=2, elites=4, starts=3)
# Notebook 07's planner, for a learner's free two-core machine: a quarter of the recipe's samples
# (benchmarks/plan_sensitivity.csv: 64 samples and 8 elites solved as many starts as 256 on seeds 0-1, in a
# quarter of the planning time) and 8 knots, chosen on seeds 0-1 among one-at-a-time changes of horizon,
# knots and iterations (18 of 60 solved, against 10 at 4 knots) and confirmed on seeds 2-5
# (benchmarks/plan_confirm.csv: 40 of 120 against 24; per start, 26 solved by 8 knots alone, 10 by 4 knots
# alone, sign test p = 0.011), for about a sixth more planning time. benchmarks/plan_summary.md has them all.
NOTEBOOK_PLAN = dict(samples=64, elites=8, knots=8)


def ladder(smoke: bool = False) -> dict[str, dict]:
    """The world models of notebook 07, from the chapter's to the recipe's, one change at a time:
    ``{name: config overrides}``. ``"data"`` is the recipe's data (and its training length) with the
    chapter's model; ``"data+delta"`` and ``"data+size"`` add one of the recipe's two model changes
    each (predicting changes; ``hidden_dim``), ``"recipe"`` both: the 2x2 that separates their shares."""
    recipe = SMOKE_RECIPE if smoke else RECIPE
    data = {k: v for k, v in recipe.items() if k not in ("wm_predicts", "hidden_dim")}
    return {"chapter": {}, "data": data, "data+delta": {**data, "wm_predicts": recipe["wm_predicts"]},
            "data+size": {**data, "hidden_dim": recipe["hidden_dim"]}, "recipe": dict(recipe)}


# --- the pieces ------------------------------------------------------------------------------------
def knot_index(horizon: int, knots: int) -> torch.Tensor:
    """(horizon,) the knot each step of a plan uses: ``floor(t * knots / horizon)``."""
    return torch.arange(horizon) * knots // horizon


def dream_scores(wm, h, z, obs0, actions, mean, std, objective: str = "reward") -> torch.Tensor:
    """The objective of each plan, averaged over its dreamed steps: the analytic reward of its dreamed
    frames (``"reward"``), or minus the block's distance and angle error in units of the success
    tolerances (``"tolerance"``, ``PlanSettings.objective``).

    ``h`` (N, H), ``z`` (N, Z): the filtered states the plans start from; ``obs0`` (N, D) the normalised
    real frames they were filtered on (a ``"delta"`` model adds its changes to them); ``actions``
    (N, T, A). One model call per step for all N rows. Returns (N,)."""
    outs = []
    for t in range(actions.shape[1]):
        h, z = wm.img_step(h, z, actions[:, t])
        outs.append(wm.decode(h, z))
    frames = wm.accumulate(torch.stack(outs), obs0)                       # (T, N, D) normalised
    reward, pos, ang = reward_from_obs(frames, mean, std)
    if objective == "tolerance":
        return -(pos / SUCCESS_POS + ang / SUCCESS_ANG).mean(0)
    return reward.mean(0)


@reference("07_planning: cem_update")
def cem_update(samples: torch.Tensor, scores: torch.Tensor, elites: int, min_std: float = 0.0):
    """The cross-entropy method's refit: the Gaussian of the ``elites`` best samples.

    ``samples`` (B, S, ...), ``scores`` (B, S), higher is better. Returns ``(mean, std)`` of shape
    (B, ...): the elites' mean and (population) standard deviation, floored at ``min_std``."""
    idx = scores.topk(elites, dim=1).indices                                # (B, E)
    shape = idx.shape + samples.shape[2:]
    best = samples.gather(1, idx.reshape(*idx.shape, *([1] * (samples.dim() - 2))).expand(shape))
    return best.mean(1), best.std(1, correction=0).clamp_min(min_std)


def cem_plan(wm, h, z, obs0, init_mean, gens, s: PlanSettings, mean, std, update=None) -> torch.Tensor:
    """CEM for B starts at once: ``h``, ``z``, ``obs0`` (B, .), ``init_mean`` (B, K, A), ``gens`` B
    generators (start i draws its noise from ``gens[i]`` alone). Each iteration dreams all B x S plans
    in one batched call. ``update``: the refit (default :func:`cem_update`; notebook 07 passes the
    learner's). Returns the final mean (B, K, A)."""
    update = cem_update if update is None else update      # the learner's refit, even a falsy one
    B, S = h.shape[0], s.samples
    idx = knot_index(s.horizon, s.knots)
    rows = [x.repeat_interleave(S, 0) for x in (h, z, obs0)]
    m, sd = init_mean, torch.full_like(init_mean, s.init_std)
    for _ in range(s.iters):
        eps = torch.stack([torch.randn((S, s.knots, ACT_DIM), generator=g) for g in gens])   # (B, S, K, A)
        plans = (m[:, None] + sd[:, None] * eps).clamp(-1.0, 1.0)
        scores = dream_scores(wm, *rows, plans[:, :, idx].reshape(B * S, s.horizon, ACT_DIM), mean, std, s.objective)
        m, sd = update(plans, scores.view(B, S), s.elites, s.min_std)
        if tuple(m.shape) != tuple(init_mean.shape) or tuple(sd.shape) != tuple(init_mean.shape):
            raise ValueError(f"the refit must return a mean and a spread of shape {tuple(init_mean.shape)} "
                             f"(starts, knots, action), got {tuple(m.shape)} and {tuple(sd.shape)}")
    return m


def plan_generators(seeds) -> list[torch.Generator]:
    """One generator per start, seeded by its ``env.reset`` seed."""
    return [torch.Generator().manual_seed(int(seed)) for seed in seeds]


@torch.inference_mode()
def plan_rollout(wm, seeds, horizon: int, mean, std, s: PlanSettings, batched: bool = True,
                 progress=None, update=None, record: list | None = None) -> Rollout:
    """The planner in the real sim from ``env.reset(seed)`` for each seed, all in lockstep, replanning
    at every step from the state filtered on the true frames. ``batched=False`` plans the starts one
    at a time (the same numbers drawn, the same model; for timing). Scored like every rollout.
    ``update``: the CEM refit (default :func:`cem_update`). ``record``: a list that receives, at every
    real step, the dream of each start's chosen plan, ``(B, horizon + 1, 6)`` in metres from the
    filtered frame on (NaN rows for starts already done): what the planner expected to happen."""
    envs = [PushTEnv() for _ in seeds]
    B, K = len(envs), s.knots
    obs = np.zeros((horizon + 1, B, 6))
    obs[0] = [env.reset(seed) for env, seed in zip(envs, seeds)]
    actions = np.zeros((horizon, B, ACT_DIM))
    alive = np.ones((horizon, B), dtype=bool)
    success = np.zeros(B, dtype=bool)
    live = np.ones(B, dtype=bool)
    mean_np, std_np = mean.cpu().numpy().astype(np.float64), std.cpu().numpy().astype(np.float64)
    gens = plan_generators(seeds)
    h, _ = wm._init(B)
    plan_mean = h.new_zeros(B, K, ACT_DIM)
    steps = range(horizon)
    for t in (labelled(progress, "planning" if batched else "planning, one start at a time") or iter)(steps):
        norm = torch.as_tensor((obs[t] - mean_np) / std_np, dtype=torch.float32, device=mean.device)
        if s.window and t > s.window:       # re-filter from h = 0 over the last `window` real steps only
            lo = t - s.window
            ctx = torch.as_tensor((obs[lo:t + 1] - mean_np) / std_np, dtype=torch.float32).transpose(0, 1)
            h, _ = wm.filter(ctx, torch.as_tensor(actions[lo:t], dtype=torch.float32).transpose(0, 1))
            h = h[:, -1]
        z = wm.filter_step(h, norm)
        ids = np.flatnonzero(live)
        tid = torch.as_tensor(ids)
        args = (h[tid], z[tid], norm[tid], plan_mean[tid] if s.warm else torch.zeros_like(plan_mean[tid]))
        if batched:
            best = cem_plan(wm, *args, [gens[i] for i in ids], s, mean, std, update)
        else:
            best = torch.cat([cem_plan(wm, *(x[j:j + 1] for x in args), [gens[i]], s, mean, std, update)
                              for j, i in enumerate(ids)])
        plan_mean[tid] = best
        if record is not None:
            record.append(_expected(wm, args[:3], best, ids, B, s, mean, std))
        a = h.new_zeros(B, ACT_DIM)
        a[tid] = best[:, 0]
        actions[t] = a.cpu().numpy()
        obs[t + 1] = obs[t]
        alive[t] = live
        for i in ids:
            obs[t + 1, i], _, done, info = envs[i].step(actions[t, i])
            success[i] = info["success"]
            live[i] = not done
        h = wm.gru(torch.cat([z, a], dim=-1), h)
        if not live.any():
            alive[t + 1:] = False
            obs[t + 2:] = obs[t + 1]
            break
    norm_next = torch.as_tensor((obs[1:] - mean_np) / std_np, dtype=torch.float32, device=mean.device)
    r, pos, _ = reward_from_obs(norm_next, mean, std)
    r, pos = r.cpu().numpy().astype(np.float64), pos.cpu().numpy().astype(np.float64)
    r[~alive], pos[~alive] = np.nan, np.nan
    return Rollout(obs=obs, actions=actions, rewards=r, pos_err=pos, success=success)


def _expected(wm, start, best, ids, B: int, s: PlanSettings, mean, std) -> np.ndarray:
    """(B, horizon + 1, 6) metres: the dream of each live start's chosen plan (``best``), NaN elsewhere."""
    h, z, obs0 = start
    plan = best[:, knot_index(s.horizon, s.knots)]                          # (b, T, A)
    outs = []
    for t in range(s.horizon):
        h, z = wm.img_step(h, z, plan[:, t])
        outs.append(wm.decode(h, z))
    frames = torch.cat([obs0[None], wm.accumulate(torch.stack(outs), obs0)])   # (T+1, b, D) normalised
    out = np.full((B, s.horizon + 1, frames.shape[-1]), np.nan)
    out[ids] = (frames * std + mean).transpose(0, 1).cpu().numpy()
    return out


# --- the measurement -------------------------------------------------------------------------------
def summarize(rollouts: dict) -> dict:
    """Success k/n with its Wilson 95% interval, reward per step with standard errors, the planner's
    paired difference from zero actions and from the expert (with the verdict of ``stats.beyond``:
    beyond k standard errors and at least the minimum effect), final distance and yaw error; for
    ``rollouts`` ``{"plan", "zero", "expert"}`` on the same starts."""

    n = len(rollouts["plan"].success)
    out = {"n_starts": n}
    per = {name: r.return_per_step for name, r in rollouts.items()}
    for name, r in rollouts.items():
        k = int(r.success.sum())
        lo, hi = wilson(k, n)
        out.update({f"{name}_successes": k, f"{name}_success_rate": k / n, f"{name}_success_low": lo,
                    f"{name}_success_high": hi,
                    f"{name}_reward_per_step": float(per[name].mean()), f"{name}_reward_per_step_se": se(per[name]),
                    f"{name}_final_dist": float(r.final_tee_dist.mean()),
                    f"{name}_final_yaw_err_deg": float(r.final_yaw_err.mean())})
    for other in ("zero", "expert"):
        d = per["plan"] - per[other]
        out[f"plan_minus_{other}"], out[f"plan_minus_{other}_se"] = float(d.mean()), se(d)
    out["k"] = k_for(n) if n > 1 else float("nan")
    out["plan_beats_zero"] = bool(beyond(out["plan_minus_zero"], out["plan_minus_zero_se"], out["k"],
                                         MIN_REWARD_EFFECT, sign=+1))
    return out


def per_start(rollouts: dict, seeds) -> list[dict]:
    """One row per start: its seed, and each policy's success, reward per step, final distance and yaw error."""
    rows = []
    for i, seed in enumerate(seeds):
        row = {"start_seed": int(seed)}
        for name, r in rollouts.items():
            row.update({f"{name}_success": bool(r.success[i]), f"{name}_reward_per_step": float(r.return_per_step[i]),
                        f"{name}_final_dist": float(r.final_tee_dist[i]),
                        f"{name}_final_yaw_err_deg": float(r.final_yaw_err[i])})
        rows.append(row)
    return rows


def speedup(wm, seeds, steps: int, mean, std, s: PlanSettings) -> dict:
    """Batched against one start at a time, on the same starts and steps, side by side: the wall time
    of each, their ratio, and the largest difference between their actions (float rounding only:
    the same random numbers, the same model, rows computed in batches of different sizes)."""
    out = {"starts": len(seeds), "steps": steps}
    acts = {}
    for mode, batched in (("batched", True), ("serial", False)):
        t0 = time.perf_counter()
        acts[mode] = plan_rollout(wm, seeds, steps, mean, std, s, batched=batched).actions
        out[f"{mode}_s"] = time.perf_counter() - t0
    out["speedup"] = out["serial_s"] / out["batched_s"]
    out["max_action_diff"] = float(np.abs(acts["batched"] - acts["serial"]).max())
    return out


def run(cfg: Config, s: PlanSettings, cache_dir=None, model_cache=None, log=print, progress=None,
        serial: int = 0, serial_steps: int = 10, chapter_gate: bool = False) -> dict:
    """The recipe measured on one seed: the world model stage of ``cfg``, the gate, the planner on
    ``s.starts`` held-out starts beside zero actions and the expert, with the wall time of each stage.
    ``serial`` > 0: also the speed-up of batching on that many starts (``serial_steps`` steps).
    ``chapter_gate``: also the gate of the chapter's default world model (trained, or from the cache)."""
    cfg.validate()
    s.validate()
    torch.set_num_threads(cfg.threads)
    timing = {}
    t0 = time.perf_counter()
    ws = world_model_stage(cfg, cache_dir, model_cache, log, progress)
    timing["world_model_s"] = time.perf_counter() - t0
    T = ws.data.torch(cfg.device)
    mean, std = T["mean"], T["std"]
    seeds = start_seeds(EVAL_SEED_BASE, cfg.seed, s.starts)
    out = {"config": cfg.to_dict(), "settings": dataclasses.asdict(s),
           "world_model": {"built_s": ws.seconds, "data_s": ws.data_seconds}}   # as built, cached or not
    t0 = time.perf_counter()
    gates = {"plan_horizon": gate(ws.wm, seeds, s.horizon, mean, std),
             "eval_horizon": gate(ws.wm, seeds, cfg.eval_horizon, mean, std)}
    timing["gate_s"] = time.perf_counter() - t0
    if chapter_gate:
        chapter = Config(seed=cfg.seed, threads=cfg.threads, device=cfg.device)
        t0 = time.perf_counter()
        cws = world_model_stage(chapter, cache_dir, model_cache, log, progress)
        C = cws.data.torch(cfg.device)
        out["chapter_world_model"] = {"built_s": cws.seconds, "data_s": cws.data_seconds}
        for span, steps in (("plan_horizon", s.horizon), ("eval_horizon", cfg.eval_horizon)):
            gates[f"chapter_{span}"] = gate(cws.wm, seeds, steps, C["mean"], C["std"])
        timing["chapter_gate_s"] = time.perf_counter() - t0
    out["gate"] = {k: as_row(g) for k, g in gates.items()}
    if log:
        for name, g in gates.items():
            log(f"[{name}] {gate_line(g)}")
    t0 = time.perf_counter()
    rollouts = {"plan": plan_rollout(ws.wm, seeds, cfg.eval_horizon, mean, std, s, progress=progress)}
    timing["plan_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rollouts["zero"] = real_rollout(ws.wm, zero_policy, seeds, cfg.eval_horizon, mean, std)
    rollouts["expert"] = expert_rollout(seeds, cfg.eval_horizon, mean, std)
    timing["baselines_s"] = time.perf_counter() - t0
    out["summary"] = summarize(rollouts)
    out["per_start"] = per_start(rollouts, seeds)
    if serial:
        out["speedup"] = speedup(ws.wm, seeds[:serial], serial_steps, mean, std, s)
    out["timing"] = timing
    out["data_kinds"] = np.bincount(ws.data.train_kind, minlength=4).tolist() if ws.data.train_kind is not None else None
    return out


def report(res: dict, log=print) -> None:
    """The short table of one seed's measurement."""
    m, cfg = res["summary"], res["config"]
    n = m["n_starts"]
    log(f"\n=== planning in the learned model: seed {cfg['seed']}, {n} held-out starts, "
        f"{cfg['eval_horizon']} real steps ===")
    log(f"{'':18}{'success':>10}{'95% interval':>16}{'reward/step':>20}{'final dist':>12}{'final yaw':>11}")
    for name, label in (("plan", "planner (CEM)"), ("zero", "zero actions"), ("expert", "scripted expert")):
        log(f"{label:18}{m[name + '_successes']:>5d}/{n:<4d}{100 * m[name + '_success_low']:>8.0f}-"
            f"{100 * m[name + '_success_high']:.0f}%{m[name + '_reward_per_step']:>+13.3f} ± "
            f"{m[name + '_reward_per_step_se']:.3f}{100 * m[name + '_final_dist']:>9.1f} cm"
            f"{m[name + '_final_yaw_err_deg']:>9.1f}°")
    verdict = "beyond the noise" if m["plan_beats_zero"] else "NOT beyond the noise"
    log(f"planner minus zero actions: {m['plan_minus_zero']:+.3f} ± {m['plan_minus_zero_se']:.3f} per step "
        f"({verdict}: k = {m['k']:.2f}); minus the expert: {m['plan_minus_expert']:+.3f} ± "
        f"{m['plan_minus_expert_se']:.3f}")
    for name, g in res["gate"].items():
        log(f"[{name}] {gate_line(g)}")
    if "speedup" in res:
        sp = res["speedup"]
        log(f"batched vs one start at a time ({sp['starts']} starts, {sp['steps']} steps): "
            f"{sp['batched_s']:.1f} s vs {sp['serial_s']:.1f} s, {sp['speedup']:.1f}x "
            f"(largest action difference {sp['max_action_diff']:.1e})")
    log("wall time: " + ", ".join(f"{k[:-2]} {v:.1f} s" for k, v in res["timing"].items()))


# --- the command line ------------------------------------------------------------------------------
def settings_docs() -> dict[str, str]:
    import ast
    import inspect

    body = ast.parse(inspect.getsource(PlanSettings)).body[0].body
    return {a.target.id: " ".join(str(b.value.value).split()) for a, b in zip(body, body[1:])
            if isinstance(a, ast.AnnAssign) and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)}


def build_plan_parser():
    from .cli import build_parser

    p = build_parser("python -m pusht.plan", __doc__.split("\n\n")[0])
    for action in p._actions:          # say which defaults the recipe changes
        if action.dest in RECIPE and action.help:
            action.help = action.help.rsplit(" (default:", 1)[0] + f" (default here: {RECIPE[action.dest]})"
    g = p.add_argument_group("the planner (CEM in the frozen world model)")
    docs, defaults = settings_docs(), PlanSettings()
    for f in dataclasses.fields(PlanSettings):
        default = getattr(defaults, f.name)
        if isinstance(default, bool):
            g.add_argument(f"--no_{f.name}", dest=f.name, action="store_false", default=None,
                           help=f"{docs[f.name]} (default: on; this flag turns it off)")
        else:
            g.add_argument(f"--{f.name}", type=type(default), default=None, help=f"{docs[f.name]} (default: {default})")
    g.add_argument("--serial", type=int, default=0, metavar="N",
                   help="also plan the first N starts one at a time and batched, side by side (the speed-up)")
    g.add_argument("--serial_steps", type=int, default=10, help="real steps of that comparison (default: 10)")
    g.add_argument("--chapter_gate", action="store_true", help="also read the gate of the chapter's default world model")
    g.add_argument("--model_cache", type=Path, default=None, help="folder caching the trained world models")
    return p


def main(argv=None) -> int:
    from tqdm.auto import tqdm

    from .cli import parse_config
    from .data import default_cache_dir

    parser = build_plan_parser()
    cfg, args = parse_config(argv, parser=parser, base=lambda smoke: SMOKE_RECIPE if smoke else RECIPE)
    given = {f.name: getattr(args, f.name) for f in dataclasses.fields(PlanSettings)
             if getattr(args, f.name) is not None}
    try:
        s = PlanSettings(**{**(SMOKE_PLAN if cfg.smoke else {}), **given})
        s.validate()
    except ValueError as e:
        parser.error(str(e))
    if args.rerun:
        parser.error("--rerun records the actor's run (python -m pusht.dreamer); the planner has no recording")
    if args.out is None:
        cfg = cfg.replace(out=Path(f"runs/plan-seed{cfg.seed}"))
    cache = None if args.no_cache else (args.cache or default_cache_dir())
    log = None if args.quiet else print
    res = run(cfg, s, cache, args.model_cache, log, None if args.quiet else tqdm, args.serial,
              args.serial_steps, args.chapter_gate)
    cfg.out.mkdir(parents=True, exist_ok=True)
    (cfg.out / "plan.json").write_text(json.dumps(res, indent=1, default=str) + "\n")
    report(res)
    print(f"\nresults: {cfg.out / 'plan.json'}")
    return 0


if __name__ == "__main__":
    code = main()
    gc.freeze()
    sys.exit(code)
