"""Dreamer's real-data loop: act in the real world, learn the model from everything seen, dream again.

    python -m pusht.loop --seed 0 --loop_rounds 3 --out runs/loop0

Notebooks 01-05 are offline: one batch of expert data, one frozen world model, one actor. Real
Dreamer alternates three steps, and this module runs them round by round:

1. **collect**: run the current policy in the REAL sim from fresh starts, with exploration noise
   added to its actions (``loop_noise``), ``loop_episodes`` episodes of ``loop_episode_len`` steps;
   cut them into clips of ``seq_len`` steps and add them to the data;
2. **model**: continue training the world model on everything seen so far, expert and policy
   data alike (``loop_wm="continue"``, ``loop_wm_epochs`` passes), or train a fresh one on it
   (``"retrain"``, ``wm_epochs`` passes);
3. **behave**: continue training the actor-critic in the new model (``loop_actor="continue"``,
   ``loop_imag_iters`` updates) or train a fresh one (``"retrain"``), its dreams starting from the
   start states of every clip, the policy's own included.

Round 0 is the chapter's offline run (``dreamer.run``, cached). After every round both worlds are
measured on the chapter's held-out evaluation starts, exactly as ``metrics.json`` is, plus the
world model's error against copy-last on the *policy's* data (clips of the round's real evaluation
rollouts, never trained on) beside its error on held-out expert data. The normalisation (mean and
std of the expert frames) is kept fixed, so the networks' inputs mean the same in every round.
Each round's collection starts come from their own seed range (``data.LOOP_SEED_BASE``), disjoint
from training, validation, monitoring and evaluation starts.
"""

from __future__ import annotations

import copy
import gc
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from .agent import ActorCritic
from .agent_stage import AGENT_FIELDS
from .analysis import shift_metrics
from .config import Config
from .data import EVAL_SEED_BASE, LOOP_SEED_BASE, start_seeds
from .dreamer import round_metrics, run
from .env import ACT_DIM, OBS_NAMES
from .evaluate import Rollout, policy_of, real_rollout, two_world_eval
from .imagination import freeze, train_in_imagination
from .metric_keys import WM_COPY_ERR, WM_ERR, WM_RATIO, key
from .runtime import gc_paused, labelled
from .stage_cache import cached, stage_path
from .wm_stage import new_world_model
from .world_model import prediction_error_vs_copy_last, train_world_model

LOOP_FIELDS = ("loop_rounds", "loop_episodes", "loop_episode_len", "loop_noise", "loop_wm", "loop_wm_epochs",
               "loop_actor", "loop_imag_iters")
MODES = ("continue", "retrain")


@dataclass
class LoopResult:
    """Every round's metrics and evaluation rollouts, and the last round's model and agent."""

    cfg: Config
    rounds: list           # one flat metrics dict per round, round 0 = the offline chapter run
    rollouts: list         # one two_world_eval rollouts dict per round
    wm: object             # the last round's world model (frozen)
    agent: ActorCritic     # the last round's agent
    timing: list           # seconds per round, by phase


# --- the three steps ----------------------------------------------------------------------------
@torch.inference_mode()
def collect_episodes(wm, agent, seeds, steps: int, mean, std, noise: float, gen: torch.Generator) -> Rollout:
    """Run ``agent``'s deterministic policy plus Gaussian noise of std ``noise`` (clipped to the
    action box) in the real sim from each start in ``seeds``, ``steps`` steps, all in lockstep.
    The recorded actions are the ones the sim received."""
    act = policy_of(agent)

    def explore(state):
        a = act(state)
        if noise > 0:
            a = (a + noise * torch.randn(a.shape, generator=gen).to(a.device)).clamp(-1.0, 1.0)
        return a

    return real_rollout(wm, explore, seeds, steps, mean, std)


def rollout_clips(roll: Rollout, seq_len: int) -> tuple[np.ndarray, np.ndarray]:
    """Cut every episode of ``roll`` into non-overlapping clips of ``seq_len`` steps, keeping
    only clips during which the episode was still running. Returns obs (N, seq_len+1, 6) in
    metres and actions (N, seq_len, 2), the layout of the expert data."""
    obs, act = np.swapaxes(roll.obs, 0, 1), np.swapaxes(roll.actions, 0, 1)       # (B, T+1, D), (B, T, A)
    alive = ~np.isnan(roll.rewards.T)                                              # (B, T)
    clip_obs, clip_act = [], []
    for s in range(0, act.shape[1] - seq_len + 1, seq_len):
        ok = alive[:, s: s + seq_len].all(axis=1)
        clip_obs.append(obs[ok, s: s + seq_len + 1])
        clip_act.append(act[ok, s: s + seq_len])
    if not clip_obs:
        raise ValueError(f"episodes of {act.shape[1]} steps are shorter than one clip of {seq_len} steps; "
                         f"raise loop_episode_len")
    return np.concatenate(clip_obs), np.concatenate(clip_act)


def policy_data_error(wm, roll: Rollout, mean, std, seq_len: int, context: int) -> dict:
    """``prediction_error_vs_copy_last`` on clips of real rollouts ``roll`` (the policy's data)."""
    obs, act = rollout_clips(roll, seq_len)
    m, s = mean.cpu().numpy().astype(np.float64), std.cpu().numpy().astype(np.float64)
    norm = torch.as_tensor((obs - m) / s, dtype=torch.float32)
    return prediction_error_vs_copy_last(wm.cpu(), norm, torch.as_tensor(act, dtype=torch.float32),
                                         std.cpu(), context)


def _members(wm) -> list:
    return list(wm.members) if hasattr(wm, "members") else [wm]


def train_model_round(wm, cfg: Config, obs, act, rnd: int, log=None, progress=None):
    """Step 2 of round ``rnd``: a trained copy of ``wm`` (``loop_wm="continue"``) or a fresh model
    of the same kind (``"retrain"``) on the normalised tensors ``obs``/``act``. Returns it frozen."""
    from .ensemble import EnsembleWorldModel

    members = []
    for k, old in enumerate(_members(wm)):
        seed = cfg.seed + 1000 * k + 100_000 * rnd           # each member and round its own stream
        torch.manual_seed(seed)
        gen = torch.Generator().manual_seed(seed)
        if cfg.loop_wm == "continue":
            member, epochs = copy.deepcopy(old), cfg.loop_wm_epochs
        else:
            member, epochs = new_world_model(cfg, obs), cfg.wm_epochs
        member.requires_grad_(True)
        member.train()
        with gc_paused():
            train_world_model(member, obs, act, cfg.replace(wm_epochs=epochs), gen,
                              progress=labelled(progress, f"round {rnd}: world model"), log=log)
        member.eval()
        members.append(member)
    new = EnsembleWorldModel(members) if len(members) > 1 else members[0]
    return freeze(new)


def train_agent_round(wm, agent, cfg: Config, starts_obs, starts_act, mean, std, rnd: int, log=None,
                      progress=None) -> tuple[ActorCritic, dict]:
    """Step 3 of round ``rnd``: the actor-critic trained further (``loop_actor="continue"``) or
    afresh (``"retrain"``) in the frozen ``wm``, dreams starting from ``starts_obs``."""
    seed = cfg.seed + 1 + 7919 * cfg.actor_seed + 100_000 * rnd
    torch.manual_seed(seed)
    gen = torch.Generator().manual_seed(seed)
    if cfg.loop_actor == "continue":
        new, iters = copy.deepcopy(agent), cfg.loop_imag_iters
    else:
        new, iters = ActorCritic(wm.hidden_dim + wm.latent_dim, ACT_DIM, cfg.hidden_dim).to(cfg.device), cfg.imag_iters
    with gc_paused():
        hist = train_in_imagination(wm, new, starts_obs, starts_act, mean, std, cfg.replace(imag_iters=iters), gen,
                                    progress=labelled(progress, f"round {rnd}: imagination"), log=log)
    return new, hist


# --- one round's measurement ----------------------------------------------------------------------
def _error_metrics(data: str, err: dict) -> dict:
    out = {}
    for kind in ("one_step", "open_loop"):
        # copy-last is exact where nothing moved (the block, under a policy that never touches it):
        # there the ratio is undefined, and NaN says so; the errors in metres below stay defined
        ratio = np.where(err[f"{kind}_copy"] > 1e-6, err[f"{kind}_model"] / np.maximum(err[f"{kind}_copy"], 1e-6),
                         np.nan)
        for d, name in enumerate(OBS_NAMES):
            out[key(WM_RATIO, data=data, kind=kind, dim=name)] = float(ratio[d])
        for part, dims in (("pusher", (0, 1)), ("block", (2, 3))):
            model = float(np.sqrt(np.mean(err[f"{kind}_model"][list(dims)] ** 2)))
            copy_last = float(np.sqrt(np.mean(err[f"{kind}_copy"][list(dims)] ** 2)))
            out[key(WM_ERR, data=data, kind=kind, body=part)] = model               # metres, RMSE over x and y
            out[key(WM_COPY_ERR, data=data, kind=kind, body=part)] = copy_last
    return out


def measure_round(cfg: Config, rnd: int, wm, agent, init_agent, data, T, hist: dict, n_clips: int,
                  n_episodes: int) -> tuple[dict, dict]:
    """Both worlds on the chapter's evaluation starts, and the model's error on expert and policy data."""
    eval_seeds = start_seeds(EVAL_SEED_BASE, cfg.seed, cfg.eval_episodes)
    ev, rollouts = two_world_eval(wm, agent, init_agent, eval_seeds, cfg.eval_horizon, T["mean"], T["std"],
                                  train_horizon=cfg.imag_horizon)
    ev.update(shift_metrics(wm, rollouts, data, T["mean"], T["std"], cfg.imag_horizon, cfg.seq_len))
    expert = prediction_error_vs_copy_last(wm.cpu(), T["val_obs"].cpu(), T["val_act"].cpu(), T["std"].cpu(),
                                           cfg.context)
    policy = policy_data_error(wm, rollouts["real_trained"], T["mean"], T["std"], cfg.seq_len, cfg.context)
    k = min(20, len(hist["imag_reward"]))
    metrics = {"round": rnd, "seed": cfg.seed, "eval_episodes": cfg.eval_episodes, "eval_horizon": cfg.eval_horizon,
               "train_clips": int(n_clips), "policy_episodes": int(n_episodes),
               **ev, **_error_metrics("expert", expert), **_error_metrics("policy", policy),
               "real_block_toward_target": ev["spawn_tee_dist"] - ev["real_final_tee_dist"],
               "imagined_reward_first20_train": float(np.mean(hist["imag_reward"][:k])),
               "imagined_reward_last20_train": float(np.mean(hist["imag_reward"][-k:]))}
    return round_metrics(metrics), rollouts


# --- the loop -------------------------------------------------------------------------------------
def run_loop(cfg: Config, cache_dir=None, model_cache=None, log=print, progress=None,
             on_round=None) -> LoopResult:
    """Round 0 (the offline chapter run) and ``cfg.loop_rounds`` rounds of collect, model, behave.

    ``progress`` wraps the loops (a bar over the rounds, and each round's training); ``on_round(
    metrics)`` is called after each round is measured (the CLI prints a line). ``model_cache``
    caches round 0's stages (shared with the notebooks) and the whole loop's result.
    """
    cfg.validate()

    def build():
        base = run(cfg, cache_dir, model_cache, log=log, progress=progress)
        data, T = base.data, base.data.torch(cfg.device)
        mean, std = T["mean"], T["std"]
        wm, agent = base.wm, base.agent
        obs, act = T["train_obs"], T["train_act"]
        m0, r0 = measure_round(cfg, 0, wm, agent, base.init_agent, data, T, base.history,
                               len(obs), 0)
        rounds, rolls, timing = [m0], [r0], [{"round": 0, **base.timing}]
        if on_round:
            on_round(m0)
        seeds = start_seeds(LOOP_SEED_BASE, cfg.seed, cfg.loop_rounds * cfg.loop_episodes)
        gen = torch.Generator().manual_seed(cfg.seed + 31337)
        n_episodes = 0
        rng = range(1, cfg.loop_rounds + 1)
        for rnd in (progress(rng, desc="rounds") if progress else rng):
            t0 = time.perf_counter()
            batch = seeds[(rnd - 1) * cfg.loop_episodes: rnd * cfg.loop_episodes]
            roll = collect_episodes(wm, agent, batch, cfg.loop_episode_len, mean, std, cfg.loop_noise, gen)
            new_obs, new_act = rollout_clips(roll, cfg.seq_len)
            m, s = mean.cpu().numpy().astype(np.float64), std.cpu().numpy().astype(np.float64)
            obs = torch.cat([obs, torch.as_tensor((new_obs - m) / s, dtype=torch.float32, device=cfg.device)])
            act = torch.cat([act, torch.as_tensor(new_act, dtype=torch.float32, device=cfg.device)])
            n_episodes += len(batch)
            t1 = time.perf_counter()
            wm = train_model_round(wm, cfg, obs, act, rnd, log=log, progress=progress)
            t2 = time.perf_counter()
            agent, hist = train_agent_round(wm, agent, cfg, obs[:, : cfg.context + 1], act[:, : cfg.context],
                                            mean, std, rnd, log=log, progress=progress)
            t3 = time.perf_counter()
            metrics, rollouts = measure_round(cfg, rnd, wm, agent, base.init_agent, data, T, hist, len(obs),
                                              n_episodes)
            rounds.append(metrics)
            rolls.append(rollouts)
            timing.append({"round": rnd, "collect_s": t1 - t0, "world_model_s": t2 - t1, "imagination_s": t3 - t2,
                           "eval_s": time.perf_counter() - t3, "total_s": time.perf_counter() - t0})
            if on_round:
                on_round(metrics)
        return LoopResult(cfg, rounds, rolls, wm, agent, timing)

    return cached(stage_path(model_cache, "loop", cfg, AGENT_FIELDS + LOOP_FIELDS, __name__), build)


def save_loop(result: LoopResult, out: Path) -> None:
    """``out/loop.json`` (every round's metrics, in order), ``out/round<r>.json`` and ``timing.json``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "loop.json").write_text(json.dumps(result.rounds, indent=2, sort_keys=True) + "\n")
    for m in result.rounds:
        (out / f"round{m['round']}.json").write_text(json.dumps(m, indent=2, sort_keys=True) + "\n")
    (out / "config.json").write_text(json.dumps(result.cfg.to_dict(), indent=2) + "\n")
    (out / "timing.json").write_text(json.dumps([{k: round(v, 3) for k, v in t.items()} for t in result.timing],
                                                indent=2) + "\n")


def round_line(m: dict) -> str:
    """One round in one line, as the CLI prints it: rewards per step over the whole evaluation
    (``..._eval_horizon``, each start's mean over the steps it lasted, averaged over the starts: the
    same numbers as ``imagination_gap``), as notebook 06's table reads them."""
    return (f"round {m['round']}: gap {m['imagination_gap_eval_horizon']:+.3f} (training horizon "
            f"{m['imagination_gap_train_horizon']:+.3f}), dream {m['trained_dream_return_per_step_eval_horizon']:+.3f}, "
            f"real {m['trained_real_return_per_step_eval_horizon']:+.3f}, success {m['real_success_rate']:.0%}, touching "
            f"{m['real_episodes_touching_block']}/{m['eval_episodes']}, block moved "
            f"{m['real_block_displacement']:.3f} m; model on the policy's data, open-loop block "
            f"{m['wm_policy_open_loop_block_err']:.3f} m (copy-last {m['wm_policy_open_loop_block_copy_err']:.3f} m)")


def main(argv=None) -> int:
    from tqdm.auto import tqdm

    from .cli import parse_config
    from .data import default_cache_dir

    argv = sys.argv[1:] if argv is None else list(argv)
    if not any(a == "--out" or a.startswith("--out=") for a in argv):
        seed = next((argv[i + 1] for i, a in enumerate(argv[:-1]) if a == "--seed"), "0")
        argv += ["--out", f"runs/loop{seed}"]
    cfg, args = parse_config(argv, prog="python -m pusht.loop")
    cache = None if args.no_cache else (args.cache or default_cache_dir())
    result = run_loop(cfg, cache_dir=cache, model_cache=None if args.no_cache else Path(cache) / "stages",
                      log=None, progress=None if args.quiet else tqdm,
                      on_round=lambda m: tqdm.write(round_line(m)))
    save_loop(result, cfg.out)
    print(f"\nper-round metrics: {cfg.out / 'loop.json'}")
    return 0


if __name__ == "__main__":
    code = main()
    gc.freeze()
    sys.exit(code)
