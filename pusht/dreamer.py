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

import argparse
import contextlib
import copy
import gc
import hashlib
import json
import os
import sys
import time
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import torch

from .agent import ActorCritic
from .analysis import shift_metrics
from .config import Config, field_docs, make_config
from .data import EVAL_SEED_BASE, MONITOR_SEED_BASE, cached_file, load_expert_data, start_seeds
from .ensemble import EnsembleWorldModel, disagreement_metrics, ensemble_history
from .env import ACT_DIM, OBS_DIM, OBS_NAMES
from .evaluate import policy_of, real_rollout, two_world_eval
from .imagination import WIRINGS, freeze, lambda_return, train_in_imagination
from .record import RERUN_MISSING, record_rerun, rerun_available
from .reward import reward_from_obs
from .world_model import PREDICTS, WorldModel, prediction_error_vs_copy_last, train_world_model

# Metric keys the chapter page records, in its order.
PAGE_KEYS = ["eval_episodes", "eval_horizon", "final_imagined_reward_per_step_train", "gamma",
             "hidden_dim", "imag_horizon", "imag_iters", "imagination_gap", "imagined_final_tee_dist",
             "imagined_return_per_step", "latent_dim", "real_final_tee_dist", "real_return_per_step",
             "real_success_rate", "seed", "smoke"]
PUSHER_DIMS, BLOCK_DIMS = (0, 1), (2, 3, 4, 5)


@dataclass
class WorldModelStage:
    """Step 1's products: the data, the frozen world model, its training curves and its error."""

    data: object           # data.ExpertData
    wm: WorldModel
    history: dict          # per-update "recon" and "dyn" losses
    error: dict            # prediction_error_vs_copy_last on held-out sequences
    seconds: float         # wall-clock of the whole stage
    data_seconds: float    # ... of which collecting (or loading) the expert data


@dataclass
class AgentStage:
    """Step 2's products: the trained agent, a copy of it before training, and its curves."""

    agent: ActorCritic
    init_agent: ActorCritic
    history: dict          # imagination curves and the real-sim monitor points
    seconds: float


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


# Which config fields each stage depends on: the key of its on-disk cache.
WM_FIELDS = ("seed", "device", "threads", "n_episodes", "seq_len", "n_val_episodes", "latent_dim",
             "hidden_dim", "embed_dim", "wm_epochs", "wm_lr", "batch_size", "context", "wm_predicts",
             "ensemble_size")
AGENT_FIELDS = WM_FIELDS + ("actor_seed", "imag_iters", "imag_batch", "imag_horizon", "actor_lr", "gamma", "lam",
                            "ent_coef", "critic_wiring", "monitor_every", "monitor_episodes", "eval_horizon",
                            "disagreement_penalty")


# ... and which modules: editing one of these invalidates the stage's cache, editing others does not.
WM_MODULES = ("env.py", "expert.py", "data.py", "world_model.py", "ensemble.py", "config.py", "dreamer.py")
AGENT_MODULES = WM_MODULES + ("agent.py", "imagination.py", "reward.py", "evaluate.py")


def _cache_path(model_cache, kind: str, cfg: Config, names, modules) -> Path | None:
    if model_cache is None:
        return None
    here = Path(__file__).parent
    h = hashlib.sha256(json.dumps({n: str(getattr(cfg, n)) for n in names}, sort_keys=True).encode())
    for name in modules:
        h.update((here / name).read_bytes())
    return Path(model_cache) / f"{kind}_{h.hexdigest()[:16]}.pt"


def _cached(path, build):
    found = None if path is None else cached_file(path)
    if found is not None:
        return torch.load(found, weights_only=False)
    stage = build()
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")   # its own: run_many's workers share a cache
        torch.save(stage, tmp)
        os.replace(tmp, path)
    return stage


@contextlib.contextmanager
def gc_paused():
    """Pause Python's cyclic garbage collector for the length of a training loop.

    Every tensor an operation returns is a Python object, so a loop of thousands of small
    operations keeps triggering the collector, and each full pass re-walks every live object
    (after importing this package, torch included, there are about 170,000). Measured with
    ``gc.callbacks`` at the default config, that cost 0.4 s of a run. The loops create no
    reference cycles (autograd graphs are freed by reference counting), so nothing piles up while
    it is paused; it is switched back on afterwards. It changes no number: garbage collection
    never touches a float.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


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
        data = load_expert_data(cfg.seed, cfg.n_episodes, cfg.n_val_episodes, cfg.seq_len, cache_dir)
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
                                         progress=_wrap(progress, "world model"), log=log)
            members.append(wm)
            hists.append(hist)
        if cfg.ensemble_size > 1:
            wm, hist = EnsembleWorldModel(members), ensemble_history(hists)
        wm.eval()
        error = prediction_error_vs_copy_last(wm.cpu(), T["val_obs"].cpu(), T["val_act"].cpu(),
                                              T["std"].cpu(), cfg.context)
        return WorldModelStage(data, freeze(wm.to(cfg.device)), hist, error, time.perf_counter() - t0,
                               data_seconds)

    return _cached(_cache_path(model_cache, "wm", cfg, WM_FIELDS, WM_MODULES), build)


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
                                        monitor=monitor, progress=_wrap(progress, "imagination"),
                                        log=log, reward_fn=reward_fn, return_fn=return_fn,
                                        loss_fn=loss_fn)
        return AgentStage(agent, init_agent, hist, time.perf_counter() - t0)

    custom = (reward_fn is not reward_from_obs or return_fn is not lambda_return or loss_fn is not None
              or watch is not None)
    return _cached(None if custom else _cache_path(model_cache, "agent", cfg, AGENT_FIELDS, AGENT_MODULES), build)


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
            metrics[f"wm_{kind}_ratio_{name}"] = float(ratio[d])
    return {k: _round(v) for k, v in metrics.items()}


# MKL's conditional-numerical-reproducibility branches (mkl_cbwr_get's return codes).
_MKL_BRANCHES = {1: "AUTO", 2: "AUTO", 3: "COMPATIBLE", 4: "SSE2", 6: "SSSE3", 7: "SSE4_1",
                 8: "SSE4_2", 9: "AVX", 10: "AVX2", 11: "AVX512_MIC", 12: "AVX512",
                 13: "AVX512_MIC_E1", 14: "AVX512_E1"}

# The fingerprint keys that decide the floats of a run: where all of them match meta.yaml's, a run
# must reproduce it bit for bit; where one differs, only within the recorded tolerance bands.
FLOAT_KEYS = ("machine", "cpu_vendor", "cpu_model", "torch", "cpu_capability", "mkl", "mkl_path",
              "numpy", "pymunk")


def _mkl() -> tuple[str, str]:
    """(MKL version, the code path MKL takes here), read from the MKL linked into torch.

    The path is MKL's CNR branch: the one MKL_CBWR forces, else the one MKL picks for this CPU
    itself (on Intel CPUs an ISA such as AVX512; elsewhere "AUTO", plus "+zen" where MKL uses its
    AMD Zen kernels). Two hosts with the same torch and cpu_capability can differ here (issue 9).
    """
    import ctypes

    if not torch.backends.mkl.is_available():
        return "none", "none"
    try:
        lib = ctypes.CDLL(str(Path(torch.__file__).parent / "lib" / "libtorch_cpu.so"))
        buf = ctypes.create_string_buffer(256)
        lib.MKL_Get_Version_String(buf, len(buf))
        version = buf.value.decode().split(" for ")[0].replace("Intel(R) oneAPI Math Kernel Library ", "MKL ")
        branch = lib.mkl_serv_cbwr_get(1)                        # MKL_CBWR_BRANCH
        if branch in (1, 2):                                     # not forced: what MKL picks itself
            branch = lib.mkl_serv_cbwr_get_auto_branch()
        path = _MKL_BRANCHES.get(branch & 0xFFFF, str(branch))
        if branch & 0x10000:
            path += ",STRICT"
        if lib.mkl_serv_cpuiszen():
            path += "+zen"
        return version, path
    except (OSError, AttributeError):                          # no such library or symbol here
        return "unknown", "unknown"


def platform_fingerprint() -> dict:
    """What the floats of a run depend on, recorded beside its numbers (see FLOAT_KEYS).

    Cheap: reads /proc/cpuinfo and asks the MKL already loaded with torch, no computation.
    """
    import platform

    from .host import cpu_info, cpu_model

    info = cpu_info()
    model = cpu_model(family=True)
    mkl, mkl_path = _mkl()
    try:
        from importlib.metadata import version
        pymunk_version = version("pymunk")
    except Exception:                                           # not installed as a distribution
        pymunk_version = "unknown"
    return {"torch": str(torch.__version__), "cpu_capability": torch.backends.cpu.get_cpu_capability(),
            "machine": platform.machine(), "python": platform.python_version(),
            "numpy": str(np.__version__), "pymunk": pymunk_version,
            "cpu_vendor": info.get("vendor_id", "unknown"), "cpu_model": model,
            "mkl": mkl, "mkl_path": mkl_path, "mkl_cbwr": os.environ.get("MKL_CBWR"),
            "aten_cpu_capability": os.environ.get("ATEN_CPU_CAPABILITY")}


def _round(v):
    return round(v, 6) if isinstance(v, float) else v


def _wrap(progress, desc):
    return (lambda it: progress(it, desc=desc, leave=False)) if progress else None


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


# --- command line ------------------------------------------------------------------------------
CHOICES = {"critic_wiring": WIRINGS, "wm_predicts": PREDICTS, "loop_wm": ("continue", "retrain"),
           "loop_actor": ("continue", "retrain")}


def build_parser(prog: str = "python -m pusht.dreamer") -> argparse.ArgumentParser:
    docs = field_docs()
    # Each config flag's help states its real default; argparse's own would print "None", the
    # marker for "not given" that lets --smoke fill in only what the user left alone.
    p = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n\n")[0])
    defaults = Config()
    for f in fields(Config):
        default = getattr(defaults, f.name)
        if f.name == "smoke":
            p.add_argument("--smoke", action="store_true", help=docs.get("smoke"))
            continue
        kind = {bool: None, int: int, float: float, str: str}.get(type(default), Path)
        # default=None marks "not given", so --smoke can fill in only what the user left alone.
        p.add_argument(f"--{f.name}", type=kind, default=None, help=f"{docs.get(f.name, '')} "
                       f"(default: {default})", choices=CHOICES.get(f.name))
    p.add_argument("--cache", type=Path, default=None,
                   help="folder for cached expert data (default: $PUSHT_CACHE or ~/.cache/pusht-dreamer)")
    p.add_argument("--no-cache", action="store_true", help="always collect expert data afresh")
    p.add_argument("--quiet", action="store_true", help="print only the final report")
    p.add_argument("--rerun", action="store_true",
                   help="also write <out>/dreamer.rrd, a Rerun recording of both worlds and the training "
                        "curves (needs the optional rerun-sdk package)")
    return p


def parse_config(argv=None, prog: str = "python -m pusht.dreamer"):
    parser = build_parser(prog)
    args = parser.parse_args(argv)
    given = {f.name: getattr(args, f.name) for f in fields(Config)
             if f.name != "smoke" and getattr(args, f.name) is not None}
    if "out" not in given and "seed" in given:
        given["out"] = Path(f"runs/seed{given['seed']}")      # each seed gets its own folder
    try:
        cfg = make_config(smoke=args.smoke, **given)
    except ValueError as e:
        parser.error(str(e).splitlines()[0])
    if args.rerun and not rerun_available():     # say so now, not after the whole run
        parser.error(RERUN_MISSING)
    try:
        torch.empty(0, device=cfg.device)       # fail here, with usage, if the device is unusable
    except Exception as e:                      # torch raises RuntimeError or AssertionError here
        parser.error(f"--device {cfg.device} is not usable here ({str(e).splitlines()[0]}); "
                     f"use --device cpu")
    return cfg, args


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
