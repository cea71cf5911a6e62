"""The chapter's first stage: collect expert data, train the world model, measure it, freeze it.

    from pusht.wm_stage import world_model_stage      # also from pusht.dreamer, as the notebooks do

Cached on disk (``stage_cache``): the file is named by the config fields in ``WM_FIELDS`` and the
source of every module this one can run, so a later notebook, or every student's kernel while
grading, reuses it only where nothing it was computed from has changed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import torch

from .config import Config
from .data import DataMix, load_expert_data
from .ensemble import EnsembleWorldModel, ensemble_history
from .env import ACT_DIM, OBS_DIM
from .imagination import freeze
from .runtime import gc_paused, labelled
from .stage_cache import cached, stage_path
from .world_model import WorldModel, prediction_error_vs_copy_last, train_world_model

# The config fields the stage reads: with this module's source, the key of its cache file.
WM_FIELDS = ("seed", "device", "threads", "n_episodes", "seq_len", "n_val_episodes", "latent_dim",
             "hidden_dim", "embed_dim", "wm_epochs", "wm_lr", "batch_size", "context", "wm_predicts",
             "ensemble_size", "data_noisy_episodes", "data_pause_episodes", "data_random_episodes",
             "data_noise", "data_poke_episodes")


@dataclass
class WorldModelStage:
    """Step 1's products: the data, the frozen world model, its training curves and its error."""

    data: object           # data.ExpertData
    wm: WorldModel
    history: dict          # per-update "recon" and "dyn" losses
    error: dict            # prediction_error_vs_copy_last on held-out sequences
    seconds: float         # wall-clock of the whole stage
    data_seconds: float    # ... of which collecting (or loading) the expert data


def new_world_model(cfg: Config, train_obs: torch.Tensor) -> WorldModel:
    """An untrained world model of ``cfg``'s sizes and kind; a ``"delta"`` model gets the changes'
    own std from the normalised training sequences ``train_obs``. Seed torch first."""
    wm = WorldModel(OBS_DIM, ACT_DIM, cfg.latent_dim, cfg.hidden_dim, cfg.embed_dim,
                    predicts=cfg.wm_predicts).to(cfg.device)
    if cfg.wm_predicts == "delta":
        wm.set_delta_scale(train_obs)
    return wm


def world_model_stage(cfg: Config, cache_dir=None, model_cache=None, log=print,
                      progress=None) -> WorldModelStage:
    """Step 1: collect expert data, train 3.1's world model, measure it against copy-last, freeze.

    ``cache_dir`` caches the expert data, ``model_cache`` the whole stage (keyed by the config
    fields it depends on and the package source), so a later notebook can reuse it.
    """
    def build():
        t0 = time.perf_counter()
        torch.set_num_threads(cfg.threads)
        data = load_expert_data(cfg.seed, cfg.n_episodes, cfg.n_val_episodes, cfg.seq_len, cache_dir,
                                DataMix.of(cfg))
        T = data.torch(cfg.device)
        data_seconds = time.perf_counter() - t0
        members, hists = [], []
        for k in range(cfg.ensemble_size):    # ensemble.py: member 0 is the chapter's single model
            member_seed = cfg.seed + 1000 * k
            if k == 0 and cfg.ensemble_size > 1:   # the single model's own stage: from the cache if there
                single = world_model_stage(cfg.replace(ensemble_size=1, disagreement_penalty=0.0), cache_dir,
                                           model_cache, log, progress)
                members.append(single.wm)
                hists.append(single.history)
                continue
            if log and cfg.ensemble_size > 1:
                log(f"[wm] ensemble member {k + 1}/{cfg.ensemble_size} (seed {member_seed})")
            torch.manual_seed(member_seed)    # model init reproducible, independent of data collection
            gen = torch.Generator().manual_seed(member_seed)
            wm = new_world_model(cfg, T["train_obs"])
            with gc_paused():
                hist = train_world_model(wm, T["train_obs"], T["train_act"], cfg, gen,
                                         progress=labelled(progress, "world model"), log=log)
            members.append(wm)
            hists.append(hist)
        if cfg.ensemble_size > 1:
            wm, hist = EnsembleWorldModel(members), ensemble_history(hists)
        wm.eval()
        error = prediction_error_vs_copy_last(wm.cpu(), T["val_obs"].cpu(), T["val_act"].cpu(),
                                              T["std"].cpu(), cfg.context)
        return WorldModelStage(data, freeze(wm.to(cfg.device)), hist, error, time.perf_counter() - t0,
                               data_seconds)

    return cached(stage_path(model_cache, "wm", cfg, WM_FIELDS, __name__), build)
