"""The chapter's second stage: an actor-critic learns purely inside the frozen world model.

    from pusht.agent_stage import agent_stage      # also from pusht.dreamer, as the notebooks do

Cached on disk (``stage_cache``) like the world model's stage: keyed by ``AGENT_FIELDS`` and the
source of every module this one can run. A stage given a learner's own reward, return or loss,
or watched, is never cached.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import torch

from .agent import ActorCritic
from .config import Config
from .data import MONITOR_SEED_BASE, start_seeds
from .env import ACT_DIM
from .evaluate import policy_of, real_rollout
from .imagination import lambda_return, train_in_imagination
from .reward import reward_from_obs
from .runtime import gc_paused, labelled
from .stage_cache import cached, stage_path
from .wm_stage import WM_FIELDS, WorldModelStage

# The config fields the stage reads (the world model's too): with the source, its cache file's key.
AGENT_FIELDS = WM_FIELDS + ("actor_seed", "imag_iters", "imag_batch", "imag_horizon", "actor_lr", "gamma", "lam",
                            "ent_coef", "critic_wiring", "monitor_every", "monitor_episodes", "eval_horizon",
                            "disagreement_penalty")


@dataclass
class AgentStage:
    """Step 2's products: the trained agent, a copy of it before training, and its curves."""

    agent: ActorCritic
    init_agent: ActorCritic
    history: dict          # imagination curves and the real-sim monitor points
    seconds: float


def agent_stage(cfg: Config, stage: WorldModelStage, model_cache=None, log=print, progress=None,
                reward_fn=reward_from_obs, return_fn=lambda_return, loss_fn=None, watch=None) -> AgentStage:
    """Step 2: an actor-critic learns purely inside the frozen world model of ``stage``.

    Reseeded on its own, so a cached world model gives the same agent as a fresh one.
    ``reward_fn``, ``return_fn`` and ``loss_fn`` let a learner's own implementations drive the
    training (``loss_fn=None``: the losses of ``cfg.critic_wiring``). ``watch(agent, real_floor)``,
    if given, is called at every monitor point with the agent as it is then (the site's iteration
    scrubber keeps copies); it only watches, and a watched stage is never cached.
    """
    def build():
        t0 = time.perf_counter()
        torch.set_num_threads(cfg.threads)
        T = stage.data.torch(cfg.device)
        mean, std = T["mean"], T["std"]
        agent_seed = cfg.seed + 1 + 7919 * cfg.actor_seed     # actor_seed 0: the chapter's seed + 1
        torch.manual_seed(agent_seed)
        gen = torch.Generator().manual_seed(agent_seed)
        # the model's own state size: K*(H+Z) for an ensemble of K (ensemble.py)
        agent = ActorCritic(stage.wm.hidden_dim + stage.wm.latent_dim, ACT_DIM, cfg.hidden_dim).to(cfg.device)
        init_agent = copy.deepcopy(agent)
        monitor_seeds = start_seeds(MONITOR_SEED_BASE, cfg.seed, cfg.monitor_episodes)

        def monitor(a):   # the "real floor": the current policy in the real sim, never trained on
            roll = real_rollout(stage.wm, policy_of(a), monitor_seeds, cfg.eval_horizon, mean, std)
            floor = float(roll.return_per_step.mean())
            if watch is not None:
                watch(a, floor)
            return floor

        with gc_paused():
            hist = train_in_imagination(stage.wm, agent, T["train_obs"][:, : cfg.context + 1],
                                        T["train_act"][:, : cfg.context], mean, std, cfg, gen,
                                        monitor=monitor, progress=labelled(progress, "imagination"),
                                        log=log, reward_fn=reward_fn, return_fn=return_fn,
                                        loss_fn=loss_fn)
        return AgentStage(agent, init_agent, hist, time.perf_counter() - t0)

    custom = (reward_fn is not reward_from_obs or return_fn is not lambda_return or loss_fn is not None
              or watch is not None)
    return cached(None if custom else stage_path(model_cache, "agent", cfg, AGENT_FIELDS, __name__), build)
