"""PushT on real pymunk physics, in SI units, with the target T at the origin.

This is the public PushT (real-stanford/diffusion_policy, huggingface/gym-pusht) rescaled to
metres (1 px = 0.002 m) and re-centred so the target pose is (0, 0, yaw 0). What makes it PushT is
kept: 100 Hz physics under 10 Hz control, a frictionless T whose velocity is wiped every substep
(it moves only while pushed: quasi-static pushing), and a disc pusher. Two changes make it safe to
hand to a policy that will try anything:

* the pusher is force-limited (a kinematic control body drags a dynamic disc through a pivot joint
  with a maximum force), so it stalls against a wall instead of squeezing the T through it;
* start states never overlap, and the pusher is clamped inside the arena.

Observation (metres, radians folded into sin/cos)::

    [agent_x, agent_y, tee_x, tee_y, sin(tee_yaw), cos(tee_yaw)]

``tee_xy`` is the T's centre of gravity. Actions are pusher velocity commands in ``[-1, 1]^2``,
scaled by ``MAX_SPEED``; out-of-range values are clipped, NaN/inf or a wrong shape raise
``ValueError``. The reward is the chapter's shaped one, ``-0.5 * (pos_err / 0.5 + ang_err / pi)``,
and ``info["success"]`` is True once the T is within ``SUCCESS_POS`` metres and ``SUCCESS_ANG``
radians of the target, which also ends the episode.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

# --- geometry (metres) -----------------------------------------------------------------------
PX = 0.002                      # metres per pixel of the public PushT
ARENA_HALF = 0.5                # walls at x, y = +-0.5 m (the public 512 px arena, re-centred)
WALL_RADIUS = 0.004
PUSHER_RADIUS = 0.03            # 15 px
# The T in its body frame, origin at the centre of gravity (45 px below the bar's outer edge, as in
# the public PushT), yaw 0 = bar on top. Each part is an axis-aligned box (xmin, ymin, xmax, ymax).
TEE_BAR = (-0.12, 0.03, 0.12, 0.09)    # 120 x 30 px
TEE_STEM = (-0.03, -0.15, 0.03, 0.03)  # 30 x 90 px
TEE_BOXES = np.array([TEE_BAR, TEE_STEM])
TEE_MASS = 1.0                  # kg
TEE_MOMENT = 3000 * PX**2       # 0.012 kg m^2 (the public PushT's value, rescaled)

# --- dynamics ----------------------------------------------------------------------------------
PHYSICS_DT = 0.01               # 100 Hz physics
SUBSTEPS = 10                   # -> 10 Hz control
CONTROL_DT = PHYSICS_DT * SUBSTEPS
MAX_SPEED = 0.5                 # m/s for an action of norm 1 per axis
PUSHER_MASS = 0.1               # kg
PUSHER_MAX_FORCE = 300.0        # N: enough to push the T at full speed, not to crush it into a wall

# --- task --------------------------------------------------------------------------------------
MAX_STEPS = 300                 # 30 s episodes, as the public PushT
SUCCESS_POS = 0.02              # m
SUCCESS_ANG = math.pi / 18      # 10 degrees
POS_SCALE, ANG_SCALE = 0.5, math.pi
# Reset boxes. The public PushT spawns the T's position uniformly in a 300 px box (+-0.3 m here),
# a mean 0.23 m from the target; the chapter page's block spawns ~0.17 m away on average, so the T
# box is shrunk to +-0.22 m (mean distance 0.7652 * 0.22 = 0.168 m). The pusher box is the public
# one (+-0.4 m); the yaw is uniform.
TEE_RESET_HALF = 0.22
PUSHER_RESET_HALF = 0.4
RESET_CLEARANCE = 0.01          # m of free space between pusher and T at the start

OBS_DIM, ACT_DIM = 6, 2
OBS_NAMES = ("agent_x", "agent_y", "tee_x", "tee_y", "sin(tee_yaw)", "cos(tee_yaw)")


def wrap_angle(a):
    """Wrap radians into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def shaped_reward(tee_xy, tee_yaw):
    """The chapter's reward for a T pose (numpy, any leading shape): (reward, pos_err m, ang_err rad)."""
    pos_err = np.linalg.norm(np.asarray(tee_xy, dtype=float), axis=-1)
    ang_err = np.abs(wrap_angle(tee_yaw))
    return -0.5 * (pos_err / POS_SCALE + ang_err / ANG_SCALE), pos_err, ang_err


def distance_to_tee(points, tee_pose):
    """Distance (m) from world points (..., 2) to the T's outline at ``tee_pose`` (x, y, yaw).

    Negative inside the T. Used for non-overlapping resets and for "did the pusher touch the T?".
    ``tee_pose`` may carry the same leading shape as ``points``.
    """
    points = np.asarray(points, dtype=float)
    pose = np.asarray(tee_pose, dtype=float)
    c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    dx, dy = points[..., 0] - pose[..., 0], points[..., 1] - pose[..., 1]
    local = np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)[..., None, :]  # (..., 1, 2)
    lo, hi = TEE_BOXES[:, :2], TEE_BOXES[:, 2:]                                   # (2, 2)
    outside = np.maximum(np.maximum(lo - local, local - hi), 0.0)                 # (..., 2, 2)
    out_d = np.linalg.norm(outside, axis=-1)
    in_d = np.minimum(local - lo, hi - local).min(axis=-1)                        # >0 inside a box
    per_box = np.where(out_d > 0, out_d, -in_d)
    return per_box.min(axis=-1)


def tee_outline(tee_pose):
    """World-frame corner lists of the T's two boxes at ``tee_pose``, for drawing."""
    x, y, yaw = tee_pose
    c, s = math.cos(yaw), math.sin(yaw)
    outlines = []
    for x0, y0, x1, y1 in TEE_BOXES:
        corners = np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
        outlines.append(corners @ np.array([[c, s], [-s, c]]) + (x, y))
    return outlines


class PushTEnv:
    """The PushT task on pymunk. ``obs = env.reset(seed)``; ``obs, reward, done, info = env.step(a)``.

    The same seed gives the same trajectory bit for bit (pymunk is deterministic and the reset
    draws from its own ``numpy`` generator).
    """

    def __init__(self, max_steps: int = MAX_STEPS):
        self.max_steps = int(max_steps)
        self.space = None
        self.steps = 0
        self.done = True

    # --- construction ------------------------------------------------------------------------
    def _build(self, pusher_xy, tee_pose):
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 0.0                       # velocities wiped every substep: quasi-static
        space.collision_slop = 0.1 * PX           # pymunk's default 0.1 was meant for pixels
        h = ARENA_HALF
        corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
        for a, b in zip(corners, corners[1:] + corners[:1]):
            wall = pymunk.Segment(space.static_body, a, b, WALL_RADIUS)
            space.add(wall)

        tee = pymunk.Body(TEE_MASS, TEE_MOMENT)
        tee.position = (float(tee_pose[0]), float(tee_pose[1]))
        tee.angle = float(tee_pose[2])
        space.add(tee, *[pymunk.Poly(tee, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
                         for x0, y0, x1, y1 in TEE_BOXES])

        # The pusher: a dynamic disc that cannot spin, dragged by a kinematic control body. With
        # max_bias 0 the pivot is a pure velocity constraint, capped at PUSHER_MAX_FORCE.
        disc = pymunk.Body(PUSHER_MASS, float("inf"))
        disc.position = (float(pusher_xy[0]), float(pusher_xy[1]))
        space.add(disc, pymunk.Circle(disc, PUSHER_RADIUS))
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position = disc.position
        pivot = pymunk.PivotJoint(control, disc, (0, 0), (0, 0))
        pivot.max_bias = 0.0
        pivot.max_force = PUSHER_MAX_FORCE
        space.add(control, pivot)

        self.space, self.tee, self.disc, self.control = space, tee, disc, control

    def reset(self, seed: int | None = None, state=None) -> np.ndarray:
        """Start an episode and return the first observation.

        ``seed`` draws a random non-overlapping start (pusher in a +-0.4 m box, T in a +-0.22 m box,
        yaw uniform). ``state=(pusher_x, pusher_y, tee_x, tee_y, tee_yaw)`` places them exactly
        instead (it must not overlap).
        """
        if state is not None:
            state = np.asarray(state, dtype=float)
            if state.shape != (5,) or not np.all(np.isfinite(state)):
                raise ValueError(f"state must be 5 finite numbers (pusher_x, pusher_y, tee_x, tee_y, "
                                 f"tee_yaw); got {state!r}")
            pusher_xy, tee_pose = state[:2], state[2:]
            if distance_to_tee(pusher_xy, tee_pose) < PUSHER_RADIUS:
                raise ValueError("state places the pusher inside the T; move it clear of the block")
        else:
            pusher_xy, tee_pose = sample_start(np.random.default_rng(seed))
        self._build(pusher_xy, tee_pose)
        self.steps = 0
        self.done = False
        return self._obs()

    # --- stepping ------------------------------------------------------------------------------
    def step(self, action):
        """Apply one 0.1 s velocity command. Returns ``(obs, reward, done, info)``."""
        if self.done:
            raise RuntimeError("the episode is over (success or max_steps); call env.reset() first")
        a = np.asarray(action, dtype=float)
        if a.shape != (ACT_DIM,):
            raise ValueError(f"action must have shape ({ACT_DIM},) (pusher vx, vy in [-1, 1]); "
                             f"got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite numbers in [-1, 1]; got {a.tolist()}")
        a = np.clip(a, -1.0, 1.0)
        disc, control, space = self.disc, self.control, self.space
        control.position = disc.position
        control.velocity = (float(a[0]) * MAX_SPEED, float(a[1]) * MAX_SPEED)
        for _ in range(SUBSTEPS):
            space.step(PHYSICS_DT)
        # A safety net under the walls: the disc never leaves the arena.
        lim = ARENA_HALF - WALL_RADIUS - PUSHER_RADIUS
        x, y = disc.position
        if abs(x) > lim or abs(y) > lim:
            disc.position = (min(max(x, -lim), lim), min(max(y, -lim), lim))
        self.steps += 1
        obs = self._obs()
        reward, pos_err, ang_err = shaped_reward(obs[2:4], self.tee.angle)
        success = bool(pos_err < SUCCESS_POS and ang_err < SUCCESS_ANG)
        self.done = success or self.steps >= self.max_steps
        info = {"success": success, "pos_err": float(pos_err), "ang_err": float(ang_err),
                "steps": self.steps}
        return obs, float(reward), self.done, info

    # --- state ---------------------------------------------------------------------------------
    def _obs(self) -> np.ndarray:
        px, py = self.disc.position
        tx, ty = self.tee.position
        yaw = self.tee.angle
        return np.array([px, py, tx, ty, math.sin(yaw), math.cos(yaw)])

    @property
    def tee_pose(self) -> np.ndarray:
        """(x, y, yaw) of the T, metres and radians (yaw wrapped to [-pi, pi))."""
        return np.array([*self.tee.position, float(wrap_angle(self.tee.angle))])

    @property
    def pusher_xy(self) -> np.ndarray:
        return np.array(self.disc.position)


def sample_start(rng: np.random.Generator):
    """A random start: pusher xy and T pose (x, y, yaw) with at least RESET_CLEARANCE between them."""
    tee_pose = np.array([*rng.uniform(-TEE_RESET_HALF, TEE_RESET_HALF, 2), rng.uniform(-np.pi, np.pi)])
    while True:   # rejection sampling: about 7% of pusher draws overlap the T
        pusher_xy = rng.uniform(-PUSHER_RESET_HALF, PUSHER_RESET_HALF, 2)
        if distance_to_tee(pusher_xy, tee_pose) > PUSHER_RADIUS + RESET_CLEARANCE:
            return pusher_xy, tee_pose


def obs_to_pose(obs):
    """Split observations (..., 6) into pusher xy (..., 2) and T pose (x, y, yaw) (..., 3)."""
    obs = np.asarray(obs)
    yaw = np.arctan2(obs[..., 4], obs[..., 5])
    return obs[..., :2], np.concatenate([obs[..., 2:4], yaw[..., None]], axis=-1)
