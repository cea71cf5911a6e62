"""The chapter's whole pipeline in one command.

    python -m pusht.dreamer --seed 0 --out runs/seed0

1. collect scripted-expert sequences (3.1's data);
2. train the world model on them, measure it against copy-last, freeze it;
3. train an actor-critic purely inside the frozen model (``imagination.py``);
4. deploy the same policy in the dream and in the real sim (``evaluate.py``);
5. write ``metrics.json`` (the chapter's keys plus the controls), ``history.npz`` (curves) and
   ``timing.json`` (wall-clock per phase, kept apart so metrics stay bit-reproducible).
"""

from __future__ import annotations

import gc
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .agent import ActorCritic
from .agent_stage import AgentStage, agent_stage
from .analysis import shift_metrics
from .cli import parse_config
from .config import Config
from .data import EVAL_SEED_BASE, start_seeds
from .ensemble import EnsembleWorldModel, disagreement_metrics
from .env import OBS_NAMES
from .evaluate import two_world_eval
from .metric_keys import WM_RATIO, key
from .record import record_rerun
from .wm_stage import WorldModelStage, world_model_stage
from .world_model import WorldModel

# What the notebooks and the command line take from here: the two stages and the run that chains them.
__all__ = ["PAGE_KEYS", "RunResult", "agent_stage", "main", "parse_config", "report", "round_metrics", "run",
           "save", "summarize", "world_model_stage"]

# Metric keys the chapter page records, in its order.
PAGE_KEYS = ["eval_episodes", "eval_horizon", "final_imagined_reward_per_step_train", "gamma",
             "hidden_dim", "imag_horizon", "imag_iters", "imagination_gap", "imagined_final_tee_dist",
             "imagined_return_per_step", "latent_dim", "real_final_tee_dist", "real_return_per_step",
             "real_success_rate", "seed", "smoke"]


@dataclass
class RunResult:
    """Everything a notebook needs from one run."""

    cfg: Config
    metrics: dict
    history: dict          # wm losses, imagination curves, monitor points
    wm_error: dict         # prediction_error_vs_copy_last on held-out sequences
    rollouts: dict         # evaluate.Rollout per world
    wm: WorldModel
    agent: ActorCritic
    init_agent: ActorCritic
    data: object           # data.ExpertData
    timing: dict


def run(cfg: Config, cache_dir=None, model_cache=None, log=print, progress=None) -> RunResult:
    """Run the whole chapter for one config and return everything it produced.

    ``cache_dir`` caches expert data; ``model_cache`` caches the trained stages (None: no cache).
    ``log`` receives the progress lines (``None`` silences them); ``progress`` wraps the long loops
    (pass ``tqdm.auto.tqdm`` in a notebook).
    """
    cfg.validate()
    t0 = time.perf_counter()
    ws = world_model_stage(cfg, cache_dir, model_cache, log, progress)
    ag = agent_stage(cfg, ws, model_cache, log, progress)
    t3 = time.perf_counter()
    T = ws.data.torch(cfg.device)
    eval_seeds = start_seeds(EVAL_SEED_BASE, cfg.seed, cfg.eval_episodes)
    ev, rollouts = two_world_eval(ws.wm, ag.agent, ag.init_agent, eval_seeds, cfg.eval_horizon,
                                  T["mean"], T["std"], train_horizon=cfg.imag_horizon)
    ev.update(shift_metrics(ws.wm, rollouts, ws.data, T["mean"], T["std"], cfg.imag_horizon,
                            cfg.seq_len))
    if isinstance(ws.wm, EnsembleWorldModel):  # how far apart its members dream the evaluation
        ev.update(disagreement_metrics(ws.wm, rollouts, T["mean"], T["std"], cfg.imag_horizon))
    timing = {"data_s": ws.data_seconds, "world_model_s": ws.seconds - ws.data_seconds,
              "imagination_s": ag.seconds,
              "eval_s": time.perf_counter() - t3, "total_s": time.perf_counter() - t0}
    return RunResult(cfg, summarize(cfg, ev, ws, ag), {**{f"wm_{k}": v for k, v in ws.history.items()},
                                                       **ag.history},
                     ws.error, rollouts, ws.wm, ag.agent, ag.init_agent, ws.data, timing)


def summarize(cfg: Config, ev: dict, ws: WorldModelStage, ag: AgentStage) -> dict:
    """metrics.json: the chapter page's keys, the controls, and the world model's error ratios."""
    imag_hist, wm_hist, wm_error = ag.history, ws.history, ws.error
    k = min(20, len(imag_hist["imag_reward"]))
    metrics = {
        "eval_episodes": cfg.eval_episodes, "eval_horizon": cfg.eval_horizon,
        "final_imagined_reward_per_step_train": float(imag_hist["imag_reward"][-1]),
        "gamma": cfg.gamma, "hidden_dim": cfg.hidden_dim, "imag_horizon": cfg.imag_horizon,
        "imag_iters": cfg.imag_iters, "latent_dim": cfg.latent_dim, "seed": cfg.seed,
        "smoke": bool(cfg.smoke),
        **ev,
        "imagined_reward_first20_train": float(imag_hist["imag_reward"][:k].mean()),
        "imagined_reward_last20_train": float(imag_hist["imag_reward"][-k:].mean()),
        # the noise of last20 - first20: each iteration's reward is a mean over one random batch of
        # dreams, so the two 20-iteration means carry a standard error read off their own spread
        "imagined_reward_rise_se": float(np.sqrt(imag_hist["imag_reward"][:k].var(ddof=1) / k
                                                 + imag_hist["imag_reward"][-k:].var(ddof=1) / k))
        if k > 1 else float("nan"),
        "imagined_return_first20_train": float(imag_hist["imag_return"][:k].mean()),
        "imagined_return_last20_train": float(imag_hist["imag_return"][-k:].mean()),
        "real_reward_monitor_first": float(imag_hist["monitor_real_reward"][0]),
        "real_reward_monitor_last": float(imag_hist["monitor_real_reward"][-1]),
        "wm_final_recon_loss": float(wm_hist["recon"][-1]),
        "wm_final_dyn_loss": float(wm_hist["dyn"][-1]),
    }
    for kind in ("one_step", "open_loop"):
        ratio = wm_error[f"{kind}_model"] / np.maximum(wm_error[f"{kind}_copy"], 1e-12)
        for d, name in enumerate(OBS_NAMES):
            metrics[key(WM_RATIO, kind=kind, dim=name)] = float(ratio[d])
    return round_metrics(metrics)


def round_metrics(metrics: dict) -> dict:
    """``metrics`` with every float rounded to six decimals, as metrics.json keeps them."""
    return {k: round(v, 6) if isinstance(v, float) else v for k, v in metrics.items()}


def save(result: RunResult, out: Path) -> None:
    """Write metrics.json, config.json, history.npz and timing.json into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(json.dumps(result.metrics, indent=2, sort_keys=True) + "\n")
    (out / "config.json").write_text(json.dumps(result.cfg.to_dict(), indent=2) + "\n")
    (out / "timing.json").write_text(json.dumps({k: round(v, 3) for k, v in result.timing.items()},
                                                indent=2) + "\n")
    np.savez(out / "history.npz", **result.history)


def report(m: dict, log=print) -> None:
    """Print the imagination-gap block, as the chapter shows it."""
    log(f"\n=== the imagination gap ({m['eval_episodes']} held-out starts, "
        f"{m['eval_horizon']}-step rollouts) ===")
    log(f"IMAGINED return/step (in the dream) : {m['imagined_return_per_step']:+.4f}   "
        f"final tee-dist {m['imagined_final_tee_dist']:.3f} m")
    log(f"REAL     return/step (true PushT)   : {m['real_return_per_step']:+.4f}   "
        f"final tee-dist {m['real_final_tee_dist']:.3f} m  (spawned {m['spawn_tee_dist']:.3f} m away)")
    verdict = ("<- the dream is rosier than reality" if m["imagination_gap"] > 0.02
               else "<- imagined and real roughly agree")
    log(f"gap (imagined - real)               : {m['imagination_gap']:+.4f}   {verdict}")
    log(f"real task success rate              : {m['real_success_rate']:.2f}")
    log("controls, same dream, same starts   : "
        f"zero actions {m['zero_action_dream_return_per_step']:+.4f} "
        f"({m['zero_action_dream_final_tee_dist']:.3f} m),  untrained actor "
        f"{m['untrained_actor_dream_return_per_step']:+.4f} "
        f"({m['untrained_actor_dream_final_tee_dist']:.3f} m)")
    log(f"what the real policy did            : block moved {m['real_block_displacement']:.3f} m "
        f"on average; pusher touched the block in {m['real_episodes_touching_block']}"
        f"/{m['eval_episodes']} episodes")


def main(argv=None) -> int:
    cfg, args = parse_config(argv)
    from .data import default_cache_dir
    cache = None if args.no_cache else (args.cache or default_cache_dir())
    log = None if args.quiet else print
    result = run(cfg, cache_dir=cache, log=log)
    save(result, cfg.out)
    report(result.metrics)
    print(f"\nmetrics: {cfg.out / 'metrics.json'}  (imagination gap "
          f"{result.metrics['imagination_gap']:+.4f} return/step; real success "
          f"{result.metrics['real_success_rate']:.2f}; {result.timing['total_s']:.1f} s)")
    if args.rerun:
        path = record_rerun(result, cfg.out / "dreamer.rrd")
        print(f"rerun recording: {path}  (open it with: rerun {path})")
    return 0


if __name__ == "__main__":
    code = main()
    # The process ends here. Freezing every live object first spares the interpreter's last
    # garbage collection at shutdown from re-walking all of torch (measured: 0.55 s -> 0.13 s).
    gc.freeze()
    sys.exit(code)
