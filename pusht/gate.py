"""The gate: can this dream be trusted to act in? Read it before anything is trained.

The scripted expert solves the real task. Replay its real actions, open loop, in the dream from the
same starts, beside zero actions in both worlds: reality pays the expert's pushes more than standing
still; a dream that can be planned in must rank them the same way. The quantity is the package's
expert signal (``split.expert_signal``: the expert minus zero actions, reward per step, each start's
difference averaged, with its standard error over the starts), in the dream and in reality.

The verdict uses the notebooks' one test (``pusht.stats.beyond``): the dream's signal passes when
it is positive beyond ``k`` standard errors (Student's t at the starts' degrees of freedom, 95%) AND
at least the minimum effect that matters (``MIN_REWARD_EFFECT``, 0.02 per step: the block 2 cm
nearer the target on every step). Nothing is trained; a gate costs one expert rollout, two real
zero-action rollouts' worth of physics and two batched dreams (about a second for 30 starts).
"""

from __future__ import annotations

import numpy as np

from .evaluate import dream_rollout, expert_rollout, real_rollout, replay_rollout, zero_policy
from .metric_keys import EXPERT_SIGNAL, key
from .stats import MIN_REWARD_EFFECT, beyond, k_for
from .split import expert_signal


def gate_rollouts(wm, seeds, horizon: int, mean, std) -> dict:
    """The four rollouts the gate reads, keyed as ``split.expert_signal`` wants them: the expert in
    reality and its actions replayed in the dream, zero actions in both, all from ``env.reset(seed)``."""
    real_expert = expert_rollout(seeds, horizon, mean, std)
    return {"real_expert": real_expert,
            "dream_expert": replay_rollout(wm, real_expert, mean, std),
            "real_zero": real_rollout(wm, zero_policy, seeds, horizon, mean, std),
            "dream_zero": dream_rollout(wm, zero_policy, real_expert.obs[0], horizon, mean, std)}


def verdict(signal: dict, n_starts: int) -> dict:
    """Pass/fail of each world's expert signal (keys of ``split.expert_signal``), with the threshold."""
    k = k_for(n_starts)
    out = {"k": k, "min_effect": MIN_REWARD_EFFECT}
    for world in ("dream", "real"):
        d, se = signal[key(EXPERT_SIGNAL, world=world)], signal[key(EXPERT_SIGNAL, world=world, se=True)]
        out[f"{world}_ranks_expert_first"] = bool(beyond(d, se, k, MIN_REWARD_EFFECT, sign=+1))
    out["passed"] = out["dream_ranks_expert_first"]
    return out


def gate(wm, seeds, horizon: int, mean, std) -> dict:
    """Does the dream of ``wm`` rank the expert's real pushes above zero actions, as reality does?

    ``seeds``: the starts (``env.reset`` seeds; use held-out ones); ``horizon``: steps of each
    rollout; ``mean``/``std``: the data's normalisation (tensors). Returns a flat dict:
    ``expert_signal_dream``/``_real`` and their ``_se`` (reward per step, expert minus zero actions),
    the same for the reward's ``_position``/``_yaw`` terms, ``zero_dream_block_moved`` (m: how far
    the dream moves a block nobody touches; past a few cm, zero actions are not standing still in the
    dream), ``expert_gap``, ``k``, ``min_effect``, ``dream_ranks_expert_first``,
    ``real_ranks_expert_first`` and the verdict ``passed`` (the dream's ranking), plus ``n_starts``
    and ``horizon``.
    """
    seeds = list(seeds)
    if len(seeds) < 2:
        raise ValueError(f"the gate needs at least 2 starts for a standard error, got {len(seeds)}")
    return read(gate_rollouts(wm, seeds, horizon, mean, std))


def read(rollouts: dict) -> dict:
    """The gate's reading of rollouts already made (:func:`gate_rollouts`), as :func:`gate` returns it."""
    n, horizon = rollouts["real_expert"].success.shape[0], rollouts["real_expert"].actions.shape[0]
    signal = expert_signal(rollouts, None)
    return {**signal, **verdict(signal, n), "n_starts": int(n), "horizon": int(horizon)}


def gate_line(g: dict) -> str:
    """One line for a terminal: both worlds' signals with their standard errors, and the verdict."""
    def pm(world):
        return f"{g[key(EXPERT_SIGNAL, world=world)]:+.3f} ± {g[key(EXPERT_SIGNAL, world=world, se=True)]:.3f}"
    word = "PASSES" if g["passed"] else "FAILS"
    return (f"gate ({g['n_starts']} starts, {g['horizon']} steps): expert minus zero actions, reward/step: "
            f"dream {pm('dream')}, reality {pm('real')}; untouched block moved "
            f"{100 * g['zero_dream_block_moved']:.1f} cm in the dream -> {word} "
            f"(needs > {g['k']:.2f} se and >= {g['min_effect']:.2f})")


def as_row(g: dict) -> dict:
    """The gate's numbers as plain floats and bools (for JSON and CSV)."""
    return {k: (bool(v) if isinstance(v, (bool, np.bool_)) else float(v) if isinstance(v, (float, np.floating))
                else v) for k, v in g.items()}
