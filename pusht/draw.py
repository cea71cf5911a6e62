"""Drawing PushT states with matplotlib: one frame, a path, or the two worlds side by side."""

from __future__ import annotations

import numpy as np

from .env import ARENA_HALF, PUSHER_RADIUS, obs_to_pose, tee_outline
from .palette import TARGET

TARGET_COLOR, TEE_COLOR, PUSHER_COLOR = TARGET, "#7f7f7f", "#1f77b4"


def setup_arena(ax, title: str | None = None):
    """Square axes showing the whole arena, in metres."""
    ax.set_xlim(-ARENA_HALF, ARENA_HALF)
    ax.set_ylim(-ARENA_HALF, ARENA_HALF)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
    return ax


def draw_state(ax, obs, target: bool = True, alpha: float = 1.0, tee_color=TEE_COLOR,
               pusher_color=PUSHER_COLOR, label: str | None = None):
    """Draw one observation ``[agent_x, agent_y, tee_x, tee_y, sin, cos]``: the T-block, the
    pusher and (dashed) the target. Returns the artists, so an animation can update them."""
    from matplotlib.patches import Circle, Polygon

    pusher, tee = obs_to_pose(np.asarray(obs, dtype=float))
    artists = []
    if target:
        for i, box in enumerate(tee_outline((0.0, 0.0, 0.0))):
            ax.add_patch(Polygon(box, closed=True, fill=False, ls="--", lw=1.2, ec=TARGET_COLOR,
                                 label="target" if i == 0 else None))
    for i, box in enumerate(tee_outline(tee)):
        artists.append(ax.add_patch(Polygon(box, closed=True, fc=tee_color, ec="k", lw=0.8,
                                            alpha=alpha, label=(label or "T-block") if i == 0 else None)))
    artists.append(ax.add_patch(Circle(pusher, PUSHER_RADIUS, fc=pusher_color, ec="k", lw=0.8,
                                       alpha=alpha, label="pusher" if label is None else None)))
    return artists


def _update(artists, obs):
    pusher, tee = obs_to_pose(np.asarray(obs, dtype=float))
    for patch, box in zip(artists[:2], tee_outline(tee)):
        patch.set_xy(box)
    artists[2].center = tuple(pusher)


def animate_two_worlds(dream_obs, real_obs, every: int = 2, titles=("in the dream", "in the real sim"),
                       dt: float = 0.1, dpi: int = 100):
    """Side-by-side animation of one start: the dream (left) and the real sim (right).

    ``dream_obs`` and ``real_obs`` are (T+1, 6) trajectories in metres. Returns a matplotlib
    ``FuncAnimation``; in a notebook show it with ``IPython.display.HTML(anim.to_jshtml())``.
    Every embedded frame is a PNG of the figure at ``dpi``, so ``every`` and ``dpi`` set the size
    of the page (a lower ``dpi`` keeps a saved notebook small).
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation

    fig, axes = plt.subplots(1, 2, figsize=(8, 4.2), dpi=dpi)
    worlds = (np.asarray(dream_obs), np.asarray(real_obs))
    all_artists, texts = [], []
    for ax, traj, title in zip(axes, worlds, titles):
        setup_arena(ax, title)
        all_artists.append(draw_state(ax, traj[0]))
        texts.append(ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9))
    axes[0].legend(loc="lower left", fontsize=8)
    frames = list(range(0, len(worlds[0]), every))

    def update(t):
        for artists, traj, text in zip(all_artists, worlds, texts):
            _update(artists, traj[min(t, len(traj) - 1)])
            _, tee = obs_to_pose(traj[min(t, len(traj) - 1)])
            text.set_text(f"t = {t * dt:.1f} s   block-to-target {np.hypot(*tee[:2]):.3f} m")
        return [a for arts in all_artists for a in arts] + texts

    fig.tight_layout()
    anim = FuncAnimation(fig, update, frames=frames, interval=100 * every, blit=False)
    plt.close(fig)
    return anim
