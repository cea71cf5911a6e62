"""An optional Rerun recording of one run: both worlds step by step, and the training curves.

    python -m pusht.dreamer --seed 0 --rerun      # also writes runs/seed0/dreamer.rrd
    rerun runs/seed0/dreamer.rrd                 # opens it in the Rerun viewer

Each of the first few evaluation starts gets a 2D view in which the SAME policy is drawn twice from
the same start: the T-block as the world model dreams it (orange) and as the real sim moves it
(grey), each with its pusher, over the dashed target. Scrub the ``step`` timeline to watch the two
worlds part. Beside them: the block's distance to the target in each world, the imagined and the
real reward during training (timeline ``imag_iter``), the world model's losses (``wm_update``) and
the run's imagination-gap report.

Rerun draws 2D views with y pointing down; positions are logged with y negated so the pictures
match the notebooks' figures (y up). Every timeline is a step or iteration count; there is no
wall-clock timeline.

Rerun (``rerun-sdk``) is an optional extra: ``pip install rerun-sdk`` or ``pip install -e '.[rerun]'``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .env import ARENA_HALF, PUSHER_RADIUS, obs_to_pose, tee_outline
from .palette import DREAM, REAL, TARGET, rgb

RERUN_MISSING = ("--rerun needs the optional package rerun-sdk, which is not installed here. "
                 "Install it with `pip install rerun-sdk` (or `pip install -e '.[rerun]'`), or leave "
                 "out --rerun.")

# the worlds' colours are the notebooks' and the site's (pusht.palette)
COLORS = {"dream": rgb(DREAM), "real": rgb(REAL), "target": rgb(TARGET),
          "pusher": (31, 119, 180), "arena": (0, 0, 0)}


def rerun_available() -> bool:
    """True if ``rerun-sdk`` can be imported."""
    try:
        import rerun  # noqa: F401
    except ImportError:
        return False
    return True


def _require_rerun():
    try:
        import rerun as rr
    except ImportError as e:
        raise ImportError(RERUN_MISSING) from e
    return rr


def _flip(xy: np.ndarray) -> np.ndarray:
    """World (y up) to Rerun's 2D view (y down)."""
    return np.asarray(xy, dtype=np.float64) * (1.0, -1.0)


def _tee_strips(tee_pose) -> list[np.ndarray]:
    """The T's two boxes as closed line strips."""
    return [_flip(np.vstack([box, box[:1]])) for box in tee_outline(tee_pose)]


def record_rerun(result, path, episodes: int = 4) -> Path:
    """Write ``result`` (a ``dreamer.RunResult``) to the Rerun file ``path``; return the path.

    ``episodes``: how many of the evaluation starts get a view of their own (both worlds each).
    Raises ``ImportError`` with the install command if rerun-sdk is missing.
    """
    rr = _require_rerun()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = rr.RecordingStream("pusht_dreamer", recording_id=f"seed{result.cfg.seed}")
    rec.set_log_time_enabled(False)      # no wall-clock timeline: same run, same contents
    rec.set_log_tick_enabled(False)
    rec.save(path)

    real, dream = result.rollouts["real"], result.rollouts["dream"]
    n = min(episodes, real.obs.shape[1])
    h = ARENA_HALF
    arena = _flip(np.array([(-h, -h), (h, -h), (h, h), (-h, h), (-h, -h)]))
    for ep in range(n):
        root = f"episode_{ep:02d}"
        rec.log(f"{root}/arena", rr.LineStrips2D([arena], colors=COLORS["arena"]), static=True)
        rec.log(f"{root}/target", rr.LineStrips2D(_tee_strips((0.0, 0.0, 0.0)), colors=COLORS["target"],
                                                  radii=0.002), static=True)
        for t in range(real.obs.shape[0]):
            rec.set_time("step", sequence=t)
            for world, roll in (("real", real), ("dream", dream)):
                pusher, tee = obs_to_pose(roll.obs[t, ep])
                rec.log(f"{root}/{world}/tee", rr.LineStrips2D(_tee_strips(tee), colors=COLORS[world],
                                                                radii=0.003, labels=world))
                rec.log(f"{root}/{world}/pusher", rr.Points2D(_flip(pusher[None]), radii=PUSHER_RADIUS,
                                                               colors=COLORS["pusher"]))
        steps = np.arange(real.obs.shape[0])
        for world, roll in (("real", real), ("dream", dream)):
            dist = np.linalg.norm(obs_to_pose(roll.obs[:, ep])[1][:, :2], axis=-1)
            rec.send_columns(f"tee_distance_m/{root}/{world}", indexes=[rr.TimeColumn("step", sequence=steps)],
                             columns=rr.Scalars.columns(scalars=dist))

    hist = result.history
    curves = [("training/imagined_reward_per_step", "imag_iter", hist["imag_reward"]),
              ("training/critic_loss", "imag_iter", hist["critic_loss"]),
              ("world_model/recon_loss", "wm_update", hist["wm_recon"]),
              ("world_model/dyn_loss", "wm_update", hist["wm_dyn"])]
    for entity, timeline, values in curves:
        rec.send_columns(entity, indexes=[rr.TimeColumn(timeline, sequence=np.arange(len(values)))],
                         columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)))
    rec.send_columns("training/real_reward_per_step",
                     indexes=[rr.TimeColumn("imag_iter", sequence=np.asarray(hist["monitor_iters"]))],
                     columns=rr.Scalars.columns(scalars=np.asarray(hist["monitor_real_reward"], float)))

    m = result.metrics
    rec.log("report", rr.TextDocument(_report_markdown(m), media_type="text/markdown"), static=True)
    rec.flush()
    return path


def _report_markdown(m: dict) -> str:
    return "\n".join([
        f"# The imagination gap (seed {m['seed']})",
        f"{m['eval_episodes']} held-out starts, {m['eval_horizon']}-step rollouts, the same policy in both worlds.",
        "",
        "| | dream | real |",
        "|---|---|---|",
        f"| reward per step | {m['imagined_return_per_step']:+.4f} | {m['real_return_per_step']:+.4f} |",
        (f"| final block-to-target distance (m) | {m['imagined_final_tee_dist']:.3f} | "
         f"{m['real_final_tee_dist']:.3f} |"),
        "",
        (f"Gap (dream minus real): **{m['imagination_gap']:+.4f}** per step. Real success rate: "
         f"{m['real_success_rate']:.2f}. The block spawned {m['spawn_tee_dist']:.3f} m from the target "
         f"on average and really moved {m['real_block_displacement']:.3f} m."),
    ])
