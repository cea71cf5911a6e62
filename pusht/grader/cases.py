"""The hidden tests' generated cases: every input a hidden case hands the function, drawn from the run's nonce.

``autograde/checks.py`` names each case by a generator here and the few numbers its property fixes;
``pusht.grader.probes`` expands the spec (``expand``) into the inputs, in the probe process and in the
grader's own process alike, and runs it. One generator per kind of case, grouped by the exercise it
tests: the reward (notebook 02), the lambda-return and the losses (03), the dream (04), the ensemble's
disagreement (06) and CEM's refit (07).
"""

from __future__ import annotations

import math


def _torch():
    import torch
    return torch


# --- generated cases: every hidden input drawn from the run's nonce ---------------------------------
# A hidden case is public (``autograde/checks.py`` ships with the package), so none of its inputs may be
# fixed: code that recognises a fixed input could answer it from memory. A generated case is a spec
# ``{"kind", "gen": name, "seed": s, ...}``: the generator ``name`` draws every input from
# ``torch.Generator().manual_seed(fresh * CASE_SEEDS + s)``, the run's nonce ``fresh`` included, and
# keeps the property the case tests (a T on the target, members that agree, all-zero rewards, lam = 0).
# The spec's other keys are exactly what that property fixes (``"lam": 0.0``, ``"K": 1``); everything
# else (shapes, scalars, normalisations, seeds of the agents and models) is drawn. The probe process and
# the grader run the same generator on the same nonce, so both see bit-identical inputs.
CASE_SEEDS = 1 << 12                  # a case's seed is below this: each (nonce, seed) its own stream
GENERATORS: dict = {}
_RUN_KEYS = ("kind", "of", "row", "module_grads")       # how a case is run: kept as given
_SPEC_KEYS = ("gen", "seed", "helpers")                 # what names the generator and the helpers


def generator(name: str):
    """Register a case generator: ``fn(draw, **fixed) -> {"args": [...]}`` (or a dream's fields)."""
    def register(fn):
        GENERATORS[name] = fn
        return fn
    return register


def expand(case: dict, fresh: int) -> dict:
    """The concrete case of a generated spec (``"gen"``): its run keys and the inputs its generator
    drew from the nonce ``fresh``. Any other case is returned as it is (``probes.build_arg`` builds it)."""
    if not isinstance(case, dict) or "gen" not in case:
        return case
    seed = int(case.get("seed", 0))
    if not 0 <= seed < CASE_SEEDS:
        raise ValueError(f"a generated case's seed must lie in [0, {CASE_SEEDS}), got {seed}")
    fixed = {k: v for k, v in case.items() if k not in _RUN_KEYS + _SPEC_KEYS}
    out = {k: case[k] for k in _RUN_KEYS if k in case}
    out.update(GENERATORS[case["gen"]](Draw(int(fresh) * CASE_SEEDS + seed), **fixed))
    return out


class Draw:
    """The draws of one generated case, all from one seeded ``torch.Generator``, in a fixed order."""

    def __init__(self, seed: int):
        self.torch = _torch()
        self.g = self.torch.Generator().manual_seed(seed)

    def int(self, lo: int, hi: int) -> int:
        """An integer in [lo, hi]."""
        return int(self.torch.randint(lo, hi + 1, (1,), generator=self.g))

    def uniform(self, lo: float, hi: float) -> float:
        """A Python float in [lo, hi)."""
        return lo + (hi - lo) * float(self.torch.rand((), generator=self.g))

    def seed(self) -> int:
        return int(self.torch.randint(0, 2 ** 31 - 1, (1,), generator=self.g))

    def randn(self, *shape):
        return self.torch.randn(*shape, generator=self.g)

    def rand(self, *shape, lo=0.0, hi=1.0):
        return lo + (hi - lo) * self.torch.rand(*shape, generator=self.g)

    def dyadic(self, *shape, lo: int, hi: int, denom: int):
        """Integers in [lo, hi] over ``denom`` (a power of two): exact in float32, and so are their sums
        and differences with other such numbers, and their products with powers of two."""
        return self.torch.randint(lo, hi + 1, shape, generator=self.g).float() / denom

    def dims(self, rank: int, lo: int, hi: int) -> tuple:
        return tuple(self.int(lo, hi) for _ in range(rank))

    def sign(self, *shape):
        return self.torch.randint(0, 2, shape, generator=self.g).float() * 2 - 1


def _grad(x, on: bool):
    return x.requires_grad_(True) if on else x


# -- reward_from_obs(norm_obs, mean, std) -------------------------------------------------------------
def _normalisation(d: Draw, kind: str):
    """(mean, std) of shape (6,). ``dyadic``: mean k/8 in [-1, 1], std a power of two in [1/4, 2], so that
    the round trip of a dyadic observation through (obs - mean) / std and back is exact (a T put on the
    target stays exactly on it); ``data``: the kind the chapter's data has; ``odd``: far from it."""
    torch = d.torch
    if kind == "dyadic":
        mean = d.dyadic(6, lo=-8, hi=8, denom=8)
        std = 2.0 ** torch.randint(-2, 2, (6,), generator=d.g).float()
        return mean, std
    if kind == "data":
        return d.rand(6, lo=-0.05, hi=0.05), d.rand(6, lo=0.1, hi=0.8)
    return d.rand(6, lo=-0.5, hi=0.5), d.rand(6, lo=0.2, hi=1.2)


def _normalised(obs, mean, std, grad=False):
    return _grad(((obs - mean) / std).contiguous(), grad)


def _pushers(d: Draw, n: int):
    """n pusher positions (n, 2), dyadic, anywhere within +-0.75 m."""
    return d.dyadic(n, 2, lo=-48, hi=48, denom=64)


def _poses(d: Draw, xy, yaw_sin, yaw_cos):
    n = xy.shape[0]
    return d.torch.cat([_pushers(d, n), xy, yaw_sin[:, None], yaw_cos[:, None]], -1)


@generator("reward_on_target")
def _reward_on_target(d: Draw):
    """n T's exactly on the target (centre 0, yaw 0) with the decoded (sin, cos) = (0, c), c in [1/4, 2],
    random pushers and a random dyadic normalisation: each scores exactly 0."""
    torch = d.torch
    n = d.int(2, 8)
    obs = _poses(d, torch.zeros(n, 2), torch.zeros(n), d.dyadic(n, lo=16, hi=128, denom=64))
    mean, std = _normalisation(d, "dyadic")
    return {"args": [_normalised(obs, mean, std), mean, std]}


@generator("reward_known_poses")
def _reward_known_poses(d: Draw):
    """Poses whose reward is known in closed form: a square T r m from the target (-r), a T turned by
    theta on the target (-|theta| / (2 pi)), and both at once; random r, theta, lengths of (sin, cos),
    pushers and a random dyadic normalisation (a square T stays exactly square)."""
    torch = d.torch
    r, phi = d.rand(3, lo=0.05, hi=0.6), d.rand(3, lo=-math.pi, hi=math.pi)
    theta, scale = d.rand(3, lo=-3.1, hi=3.1), d.rand(3, lo=0.5, hi=1.5)
    xy = torch.stack([r * phi.cos(), r * phi.sin()], -1)
    xy[1] = 0.0                                              # row 1: turned only
    s, c = scale * theta.sin(), scale * theta.cos()
    s[0], c[0] = 0.0, float(d.dyadic(1, lo=32, hi=96, denom=64))   # row 0: moved only, square
    obs = _poses(d, xy, s, c)
    mean, std = _normalisation(d, "dyadic")
    return {"args": [_normalised(obs, mean, std), mean, std]}


@generator("reward_yaw")
def _reward_yaw(d: Draw):
    """T's on the target's centre turned by an angle in each quadrant and past +-pi (which wraps), each
    at three lengths of (sin, cos) in [0.3, 2]; random pushers and normalisation."""
    torch = d.torch
    spans = [(0.05, math.pi / 2), (math.pi / 2, math.pi - 0.05), (-math.pi + 0.05, -math.pi / 2),
             (-math.pi / 2, -0.05), (math.pi + 0.05, 2 * math.pi - 0.05), (-2 * math.pi + 0.05, -math.pi - 0.05)]
    yaw = torch.tensor([d.uniform(lo, hi) for lo, hi in spans]).repeat_interleave(3)
    scale = d.rand(yaw.shape[0], lo=0.3, hi=2.0)
    obs = _poses(d, torch.zeros(yaw.shape[0], 2), scale * yaw.sin(), scale * yaw.cos())
    mean, std = _normalisation(d, "dyadic")
    return {"args": [_normalised(obs, mean, std), mean, std]}


@generator("reward_half_turn")
def _reward_half_turn(d: Draw):
    """Half turns on the target, (sin, cos) = (0, -s) at a random length s (each scores -0.5), and
    square T's off the target whose decoded cos is above 1; rows shuffled, random pushers and
    normalisation (dyadic: sin stays exactly 0)."""
    torch = d.torch
    n_half, n_over = d.int(1, 3), d.int(1, 3)
    cos = torch.cat([-d.dyadic(n_half, lo=16, hi=128, denom=64), 1 + d.dyadic(n_over, lo=4, hi=48, denom=64)])
    xy = torch.cat([torch.zeros(n_half, 2), d.dyadic(n_over, 2, lo=-24, hi=24, denom=64)])
    order = torch.randperm(n_half + n_over, generator=d.g)
    obs = _poses(d, xy[order], torch.zeros(n_half + n_over), cos[order])
    mean, std = _normalisation(d, "dyadic")
    return {"args": [_normalised(obs, mean, std), mean, std]}


@generator("reward_pusher_only")
def _reward_pusher_only(d: Draw):
    """n rows with one random T pose and n different pushers: every row must score the same."""
    torch = d.torch
    n = d.int(3, 6)
    yaw, scale = d.uniform(-math.pi, math.pi), d.uniform(0.5, 1.5)
    pose = torch.cat([d.rand(2, lo=-0.4, hi=0.4), torch.tensor([scale * math.sin(yaw), scale * math.cos(yaw)])])
    obs = torch.cat([d.rand(n, 2, lo=-1.0, hi=1.0), pose.expand(n, 4)], -1)
    mean, std = _normalisation(d, "odd")
    return {"args": [_normalised(obs, mean, std), mean, std]}


@generator("reward_random")
def _reward_random(d: Draw, lead: str = "batch", norm: str = "odd", grad: bool = False):
    """Standard-normal normalised observations of a random leading shape: ``batch`` (A, B), ``rows``
    (n,), ``single`` () or ``any`` (3 or 4 dims of 2 to 6), under a random normalisation of kind ``norm``."""
    shape = {"batch": lambda: d.dims(2, 2, 7), "rows": lambda: d.dims(1, 3, 9), "single": lambda: (),
             "any": lambda: d.dims(d.int(3, 4), 2, 6)}[lead]()
    norm_obs = _grad(d.randn(*shape, 6), grad)
    mean, std = _normalisation(d, norm)
    return {"args": [norm_obs, mean, std]}


# -- lambda_return(rewards, values, gamma, lam) ---------------------------------------------------------
@generator("lambda_small")
def _lambda_small(d: Draw):
    """A case small enough to work by hand: H in 2..4, B in 1..3, rewards and values multiples of 1/4,
    gamma and lam multiples of 1/8."""
    H, B = d.int(2, 4), d.int(1, 3)
    rewards, values = d.dyadic(H, B, lo=-8, hi=8, denom=4), d.dyadic(H + 1, B, lo=-80, hi=80, denom=4)
    return {"args": [rewards, values, d.int(2, 7) / 8, d.int(1, 7) / 8]}


@generator("lambda_return")
def _lambda_return(d: Draw, H: int | None = None, B: int | None = None, gamma: float | None = None,
                   lam: float | None = None, values: str = "randn", grad: str | None = None):
    """Standard-normal rewards (H, B) and values (H+1, B), H in 3..12 and B in 2..8 unless fixed, gamma in
    [0.5, 0.98) and lam in [0.05, 0.9) unless fixed. ``values``: ``v0_big`` puts values of +-100 in row 0
    (which no return may use); ``vh_only`` makes every reward and every value but V_H zero (V_H of
    magnitude 0.5 to 2). ``grad``: which of ``rewards``/``values`` requires grad."""
    H = d.int(3, 12) if H is None else H
    B = d.int(2, 8) if B is None else B
    gamma = d.uniform(0.5, 0.98) if gamma is None else gamma
    lam = d.uniform(0.05, 0.9) if lam is None else lam
    r, v = d.randn(H, B), d.randn(H + 1, B)
    if values == "v0_big":
        v[0] = d.rand(B, lo=-100.0, hi=100.0)
    elif values == "vh_only":
        r.zero_()
        v.zero_()
        v[-1] = d.sign(B) * d.rand(B, lo=0.5, hi=2.0)
    return {"args": [_grad(r, grad == "rewards"), _grad(v, grad == "values"), gamma, lam]}


# -- actor_critic_losses(agent, states, rewards, entropy, gamma, lam, ent_coef, return_fn) ---------------
@generator("losses")
def _losses(d: Draw, H: int | None = None, B: int | None = None, S: int | None = None,
            hidden: int | None = None, gamma: float | None = None, lam: float | None = None,
            ent: float | None = None, grad=()):
    """A seeded agent (state S, hidden units), dreamed states (H+1, B, S), rewards (H, B) in [-1, 0], an
    entropy in [0.5, 2), gamma, lam, ent_coef and the chapter's lambda-return; whatever is not fixed is
    drawn (H 2..8, B 2..6, S 4..10, hidden 4..12, gamma [0.5, 0.98), lam [0.05, 0.95), ent_coef
    [0.005, 0.2)). ``grad``: which of ``states``/``rewards``/``entropy`` require grad."""
    torch = d.torch
    H = d.int(2, 8) if H is None else H
    B = d.int(2, 6) if B is None else B
    S = d.int(4, 10) if S is None else S
    hidden = d.int(4, 12) if hidden is None else hidden
    gamma = d.uniform(0.5, 0.98) if gamma is None else gamma
    lam = d.uniform(0.05, 0.95) if lam is None else lam
    ent = d.uniform(0.005, 0.2) if ent is None else ent
    agent = {"agent": {"seed": d.seed(), "state": S, "hidden": hidden}}
    states = _grad(d.randn(H + 1, B, S), "states" in grad)
    rewards = _grad(d.rand(H, B, lo=-1.0, hi=0.0), "rewards" in grad)
    entropy = _grad(torch.tensor(d.uniform(0.5, 2.0)), "entropy" in grad)
    return {"args": [agent, states, rewards, entropy, gamma, lam, ent, {"fn": "lambda_return"}]}


# -- dream(wm, policy, norm_obs0, horizon) ----------------------------------------------------------------
@generator("dream")
def _dream(d: Draw, policy: str = "mlp", batch: int | None = None, horizon: int | None = None,
           mode: str = "no_grad"):
    """A seeded world model of random sizes (latent 2..5, hidden 5..10, embed 3..6), a policy (``mlp``: a
    seeded actor of 4..10 hidden units; ``recording``; ``zero``), start frames (batch, 6) and a horizon
    (batch 2..5, horizon 2..8 unless fixed)."""
    model = {"latent": d.int(2, 5), "hidden": d.int(5, 10), "embed": d.int(3, 6), "seed": d.seed()}
    pol = d.int(4, 10) if policy == "mlp" else policy
    batch = d.int(2, 5) if batch is None else batch
    horizon = d.int(2, 8) if horizon is None else horizon
    return {"model": model, "policy": pol, "obs0": d.randn(batch, 6), "horizon": horizon, "mode": mode}


# -- block_disagreement(frames, std) ------------------------------------------------------------------------
def _disagree_std(d: Draw, kind: str):
    """std (6,): ``data`` the data's kind; ``odd`` far from it; ``wild`` the data's kind on the block
    (dims 2:4) and anything from 0.001 to 10 elsewhere; ``dyadic`` multiples of 1/8 on the block (so a
    block that members share stays exactly shared in metres) and anything elsewhere."""
    if kind == "data":
        return d.rand(6, lo=0.1, hi=0.8)
    if kind == "wild":
        std = 10.0 ** d.rand(6, lo=-3.0, hi=1.0)
        std[2:4] = d.rand(2, lo=0.1, hi=0.8)
        return std
    if kind == "dyadic":
        std = d.rand(6, lo=0.1, hi=1.2)
        std[2:4] = d.dyadic(2, lo=1, hi=12, denom=8)
        return std
    return d.rand(6, lo=0.2, hi=1.2)


def _lead(d: Draw, lead):
    if isinstance(lead, (list, tuple)):
        return tuple(lead)
    return {"none": lambda: (), "rows": lambda: d.dims(1, 2, 32), "any": lambda: d.dims(d.int(3, 4), 2, 6)}[lead]()


@generator("disagree")
def _disagree(d: Draw, K: int | None = None, K_min: int = 2, K_max: int = 5, lead="rows", std: str = "odd",
              grad: bool = False):
    """Standard-normal frames (K, *lead, 6) of K members (K_min..K_max unless fixed) and a std of kind
    ``std``; ``lead``: a fixed shape, ``none`` (one state), ``rows`` (n,), n in 2..32, or ``any`` (3 or 4
    dims of 2 to 6)."""
    K = d.int(K_min, K_max) if K is None else K
    shape = _lead(d, lead)
    frames = _grad(d.randn(K, *shape, 6), grad)
    return {"args": [frames, _disagree_std(d, std)]}


@generator("disagree_pair")
def _disagree_pair(d: Draw):
    """Two members whose block centres are a random distance dist apart (0.05 to 1 m, any direction) in
    each of n states, and alike on everything else (pusher, yaw); a std of 1 on the block (normalised
    units are metres there, as in the hand-worked case) and anything elsewhere: each state's
    disagreement is dist / 2, whatever the std of the other dims."""
    torch = d.torch
    n = d.int(1, 6)
    std = d.rand(6, lo=0.1, hi=1.2)
    std[2:4] = 1.0
    a = d.rand(n, 2, lo=-0.4, hi=0.4)
    dist, phi = d.rand(n, lo=0.05, hi=1.0), d.rand(n, lo=-math.pi, hi=math.pi)
    frames = d.randn(n, 6).expand(2, n, 6).clone()
    frames[0, :, 2:4] = a
    frames[1, :, 2:4] = a + dist[:, None] * torch.stack([phi.cos(), phi.sin()], -1)
    return {"args": [frames, std]}


@generator("disagree_agree")
def _disagree_agree(d: Draw, grad: bool = False):
    """K members (2..5) that put the block in exactly the same place in each of n states (multiples of
    1/64, with a std of multiples of 1/8 on the block: exact in metres, so the population variance is
    exactly 0) while they differ on the pusher and the yaw."""
    K, n = d.int(2, 5), d.int(2, 8)
    frames = d.randn(K, n, 6)
    frames[:, :, 2:4] = d.dyadic(n, 2, lo=-48, hi=48, denom=64)
    return {"args": [_grad(frames, grad), _disagree_std(d, "dyadic")]}


# -- cem_update(samples, scores, elites, min_std) -------------------------------------------------------------
def _cem_scores(d: Draw, B: int, S: int, apart: bool = False):
    """(B, S) scores, distinct within each start by construction (no ties, so the elites are one set
    whatever the sort): each start's ranks, a random permutation of 0..S-1, times a step of 0.05 to 1, plus
    an offset. ``apart``: the starts' offsets far apart in a random order (every score of one start above
    every score of another), so that elites picked across starts are not any start's own."""
    torch = d.torch
    ranks = torch.stack([torch.randperm(S, generator=d.g) for _ in range(B)]).float()
    step = d.rand(B, 1, lo=0.05, hi=1.0)
    if apart:
        offset = torch.randperm(B, generator=d.g).float()[:, None] * (S + 10) + d.rand(B, 1, lo=-3.0, hi=3.0)
    else:
        offset = d.rand(B, 1, lo=-3.0, hi=3.0)
    return ranks * step + offset


def _cem_trail(d: Draw, trail) -> tuple:
    if isinstance(trail, (list, tuple)):
        return tuple(trail)
    return {"none": lambda: (), "one": lambda: (d.int(1, 4),), "plan": lambda: (d.int(2, 5), 2),
            "any": lambda: d.dims(d.int(2, 3), 1, 4)}[trail]()


@generator("cem")
def _cem(d: Draw, B: int | None = None, S: int | None = None, elites=None, trail="one", min_std=None,
         apart: bool = False, agree: bool = False):
    """Samples (B, S, *trail), each start's around a centre of its own with a spread of its own, distinct
    scores (B, S) (``_cem_scores``), ``elites`` and ``min_std``. Unless fixed: B 2..5, S 6..16 (8..16 for
    ``agree``), elites
    2..S-1 (``"all"``: S), trail ``one`` (D,), ``none`` (), ``plan`` (K, 2) or ``any`` (2 or 3 dims of 1
    to 4), min_std in [0.01, 0.05) (``"default"``: not passed, the function's default 0.0 holds).
    ``agree``: the floor's case: min_std in [0.1, 0.5), elites 3..S-1, and a third of the elements each
    where all of a start's samples agree exactly (spread 0), lie within 0.4 min_std of their centre
    (spread below the floor) or spread 5 to 10 min_std (above it); with ``"default"``, the same spreads
    in a unit of [0.1, 0.5), and the elements that agree must give exactly 0."""
    torch = d.torch
    B = d.int(2, 5) if B is None else B
    S = (d.int(8, 16) if agree else d.int(6, 16)) if S is None else S
    if elites is None:
        elites = d.int(3 if agree else 2, S - 1)
    elif elites == "all":
        elites = S
    shape = _cem_trail(d, trail)
    if min_std is None:
        min_std = d.uniform(0.1, 0.5) if agree else d.uniform(0.01, 0.05)
    centre = d.rand(B, 1, *shape, lo=-0.5, hi=0.5)
    if agree:                   # the spreads are measured in min_std (in [0.1, 0.5) where it is not passed)
        unit = d.uniform(0.1, 0.5) if min_std == "default" else min_std
        n = B * math.prod(shape)
        kind = (torch.randperm(n, generator=d.g) % 3).reshape(B, 1, *shape)
        small = d.rand(B, S, *shape, lo=-0.4 * unit, hi=0.4 * unit)
        large = d.randn(B, S, *shape) * d.rand(B, 1, *shape, lo=5.0, hi=10.0) * unit
        samples = centre + torch.where(kind == 0, 0.0, torch.where(kind == 1, small, large))
    else:
        spread = d.rand(B, 1, *([1] * len(shape)), lo=0.2, hi=1.0)
        samples = centre + spread * d.randn(B, S, *shape)
    scores = _cem_scores(d, B, S, apart)
    args = [samples.contiguous(), scores, elites]
    return {"args": args if min_std == "default" else args + [min_std]}
