"""The iteration scrubber's data: the chapter's seed-0 policy at every stage of its training.

``make chapter`` calls :func:`export` after the notebooks have run. It trains seed 0's actor again
in the world model the notebooks cached, exactly as the notebooks did (the same seeds; only the
real-floor monitor looks more often, and the monitor never touches training), keeps a copy of the
actor at every monitor point, and runs each copy through **the headline's own evaluation**: the
same held-out starts (``cfg.eval_episodes`` of them, ``cfg.eval_horizon`` steps) in the dream and
in the real simulator, with the calls ``evaluate.two_world_eval`` makes. The last copy must equal
the policy the notebooks trained and evaluated, bit for bit: :func:`export` checks that against
the cached agent and refuses to write otherwise; so the last kept iteration's evaluation is the
chapter's headline evaluation, and the first (iteration 0, before any update) is its untrained
control.

The file it writes (``<out>/site/scrubber.json``) holds, per kept iteration, that evaluation (the
mean and each start's reward per step in both worlds, real success) and, for the first held-out
start, both worlds' block and pusher positions at every control step, in millimetres and degrees,
with what the scrubber points at (how far the block moved from its spawn pose, how near the pusher
came to it, the share of steps the pusher spent pinned against a wall); plus the training curves
(the training dreams and the monitor's real floor, kept for the record: the landing page draws the
evaluation instead).
"""

from __future__ import annotations

import copy
import json
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import torch

from . import provenance

FRAMES = 21            # kept iterations: 0, then every imag_iters/20, the last included
CURVE_POINTS = 80      # the landing page's curves keep at most this many points each

def _thin(values, points: int = CURVE_POINTS) -> dict:
    """``values`` (one per step) as at most ``points`` means of consecutive blocks, with the step
    at each block's centre: a curve that keeps its shape at a fraction of the size."""
    v = np.asarray(values, dtype=float)
    if len(v) == 0:
        return {"x": [], "y": []}
    edges = np.linspace(0, len(v), min(points, len(v)) + 1).astype(int)
    xs = [float((a + b - 1) / 2) for a, b in zip(edges[:-1], edges[1:])]
    ys = [float(v[a:b].mean()) for a, b in zip(edges[:-1], edges[1:])]
    return {"x": [round(x, 1) for x in xs], "y": [round(y, 5) for y in ys]}


def _world(rollout, i: int = 0) -> dict:
    """Start ``i``'s trajectory in one world: mean reward per step, pusher (x, y) and block
    (x, y, yaw) at every step, in mm and degrees; and what the scrubber points at, in metres: how
    far the block ended from its spawn pose and how much nearer the target, how near the pusher's
    rim ever came to the T, and the share of steps the pusher spent pinned against a wall."""
    from pusht.analysis import at_wall
    from pusht.env import obs_to_pose
    from pusht.evaluate import pusher_gap

    pusher, tee = obs_to_pose(rollout.obs[:, i])          # (T+1, 2), (T+1, 3)
    alive = ~np.isnan(rollout.rewards[:, i])              # steps the episode lasted
    return {"reward_per_step": round(float(rollout.return_per_step[i]), 5),
            "final_block_to_target_m": round(float(rollout.final_tee_dist[i]), 4),
            "block_moved_m": round(float(np.linalg.norm(tee[-1, :2] - tee[0, :2])), 4),
            "block_nearer_target_m": round(float(np.linalg.norm(tee[0, :2]) - np.linalg.norm(tee[-1, :2])), 4),
            "pusher_min_gap_m": round(float(np.nanmin(pusher_gap(rollout)[:, i])), 4),
            "pusher_at_wall_share": round(float(at_wall(rollout.obs[1:, i])[alive].mean()), 4),
            "pusher_mm": np.rint(pusher * 1000).astype(int).tolist(),
            "block_mm_deg": np.column_stack([np.rint(tee[:, :2] * 1000), np.rint(np.degrees(tee[:, 2]))])
            .astype(int).tolist()}


def _evaluation(dream, real) -> dict:
    """The headline's numbers for one kept iteration, as ``two_world_eval`` computes them, plus
    each start's reward per step (the page tests changes start by start)."""
    imagined, real_r = float(dream.return_per_step.mean()), float(real.return_per_step.mean())
    return {"imagined_return_per_step": round(imagined, 6), "real_return_per_step": round(real_r, 6),
            "imagination_gap": round(imagined - real_r, 6),
            "real_success_rate": round(float(real.success.mean()), 4),
            "imagined_per_start": [round(float(v), 5) for v in dream.return_per_step],
            "real_per_start": [round(float(v), 5) for v in real.return_per_step]}


def _same_weights(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def export(out: Path, smoke: bool, seed: int = 0, log=print) -> Path:
    """Write ``out/site/scrubber.json`` for the chapter run in ``out`` (its model cache is
    ``out/cache``, as the notebooks' is ``OUT/cache``). Returns the path."""
    from pusht.analysis import at_wall
    from pusht.config import make_config
    from pusht.data import EVAL_SEED_BASE, start_seeds
    from pusht.dreamer import agent_stage, world_model_stage
    from pusht.env import CONTROL_DT, SUCCESS_POS
    from pusht.evaluate import TOUCH_TOL
    from pusht.evaluate import dream_rollout, policy_of, real_rollout

    out = Path(out)
    cache = out / "cache"
    cfg = make_config(smoke=smoke, seed=seed, out=out)
    ws = world_model_stage(cfg, cache_dir=cache, model_cache=cache, log=None)
    chapter = agent_stage(cfg, ws, model_cache=cache, log=None)       # the notebooks' own agent
    watched = cfg.replace(monitor_every=max(cfg.imag_iters // (FRAMES - 1), 1))
    copies: list[tuple[dict, float]] = []
    stage = agent_stage(watched, ws, log=None,
                        watch=lambda agent, floor: copies.append((copy.deepcopy(agent.state_dict()), floor)))
    if not _same_weights(copies[-1][0], chapter.agent.state_dict()):
        raise RuntimeError("the scrubber's retrained actor differs from the one the notebooks trained: "
                           "training is not deterministic here, so the scrubber would show another policy")

    T = ws.data.torch(cfg.device)
    mean, std = T["mean"], T["std"]
    seeds = [int(s) for s in start_seeds(EVAL_SEED_BASE, seed, cfg.eval_episodes)]   # the headline's starts
    start = seeds[0]                                                                # the scrubber's one
    agent = copy.deepcopy(stage.agent)
    agent.eval()
    frames = []
    iters = [int(i) for i in stage.history["monitor_iters"]]
    imag = stage.history["imag_reward"]
    for it, (weights, floor) in zip(iters, copies):
        agent.load_state_dict(weights)
        # two_world_eval's own two calls: reality first, then the dream from reality's start frames
        real = real_rollout(ws.wm, policy_of(agent), seeds, cfg.eval_horizon, mean, std)
        dream = dream_rollout(ws.wm, policy_of(agent), real.obs[0], cfg.eval_horizon, mean, std)
        frames.append({"iteration": it,
                       "imagined_reward_train": round(float(imag[min(it, len(imag) - 1)]), 5),
                       "real_floor": round(floor, 5),
                       "eval": _evaluation(dream, real),
                       "dream": _world(dream), "real": _world(real)})
    data = {
        "written_by": "chapter_site/scrubber.py (make chapter)",
        "measured_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "commit": provenance.commit(), "host": provenance.host(),
        "seed": seed, "config": "smoke" if smoke else "default",
        "start_seed": start, "horizon": cfg.eval_horizon, "control_dt_s": CONTROL_DT,
        "eval_starts": len(seeds), "imag_iters": cfg.imag_iters, "imag_horizon": cfg.imag_horizon,
        "monitor_starts": cfg.monitor_episodes,
        # what the scrubber's readout compares with: the expert data's own share of steps with the
        # pusher against a wall, a touch (m) and the block's "moved" (m, the success tolerance)
        "expert_pusher_at_wall_share": round(float(at_wall(ws.data.train_obs).mean()), 4),
        "touch_tol_m": TOUCH_TOL, "moved_tol_m": SUCCESS_POS,
        "same_as_chapter_agent": True,
        "frames": frames,
        "curves": {"imagined_reward": _thin(stage.history["imag_reward"]),
                   "real_floor": {"x": iters, "y": [f["real_floor"] for f in frames]},
                   "wm_recon": _thin(ws.history["recon"]), "wm_dyn": _thin(ws.history["dyn"])},
    }
    path = out / "site" / "scrubber.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, separators=(",", ":")) + "\n")
    if log:
        log(f"scrubber: {len(frames)} iterations of seed {seed}'s actor, each on the {len(seeds)} held-out starts, "
            f"{path.stat().st_size / 1024:.0f} KB -> {path}")
    return path
