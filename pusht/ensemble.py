"""An ensemble of world models and its disagreement, MOPO's penalty for dreaming off the data.

K world models are trained on the same expert sequences, each from its own initial weights and in
its own batch order (member k is seeded ``seed + 1000 k``, so member 0 is the chapter's single
model). Where the data pinned the dynamics down they agree; where the actor steers the dream away
from the data each extrapolates in its own way and they drift apart. MOPO (Yu et al. 2020) turns
that spread into a penalty: the actor is trained on ``reward - lambda * disagreement``, so a dream
only pays where the models agree.

:class:`EnsembleWorldModel` wraps the members behind the interface the rest of the package uses
(``_init``, ``filter_step``, ``img_step``, ``gru``, ``prior``, ``decode``, ``decoder``,
``decode_dream``, ``warm``, ``filter``, ``step``, ...). Its state is the members' states side by
side: ``h`` is ``[h_1, ..., h_K]`` (B, K*H) and ``z`` is ``[z_1, ..., z_K]`` (B, K*Z), so every
rollout function (``imagine``, ``dream``, ``real_rollout``) runs unchanged, each member rolls its
own latent trajectory under the same actions, and the actor reads all K states (K*(H+Z) inputs).
Decoding gives the members' MEAN observation.

No bootstrap: every member trains on all the sequences. Member 0 must be the single model of the
same config (which sees all of them), the data are few (300 sequences: a bootstrap resample leaves
each member about 63% of them), and random initialisation plus batch order is what deep ensembles
rely on for their spread (Lakshminarayanan et al. 2017).

Members run one after the other in a plain loop (``torch.func.vmap`` has no batching rule for
``nn.GRUCell``): an ensemble of K costs about K times one model.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from .reference import reference

BLOCK_XY = slice(2, 4)     # the block centre's (x, y) in an observation


@reference("06_closing_the_gap: block_disagreement")
def block_disagreement(frames: torch.Tensor, std: torch.Tensor | None = None) -> torch.Tensor:
    """How far apart K members put the block: frames (K, ..., D) -> (...).

    ``frames`` are the members' decoded normalised frames, stacked on dim 0. The result is the
    root-mean-square distance of the members' block centres (dims 2:4) from their mean, i.e.
    ``sqrt(var_x + var_y)`` with population variances across the K members (the members are the
    whole ensemble, not a sample of it). Metres when ``std`` (D,) is given (only ``std[2:4]``
    enters); normalised units when it is None. Zero where all members agree (K = 1 in
    particular), and differentiable in ``frames`` with a zero, not NaN, gradient there.
    """
    block = frames[..., BLOCK_XY]
    if std is not None:
        block = block * std[BLOCK_XY]
    var = block.var(dim=0, correction=0).sum(-1)                           # (...)
    # sqrt has an infinite slope at 0: take it only where the variance is positive
    positive = var > 0
    return torch.where(positive, torch.where(positive, var, 1.0).sqrt(), 0.0)


class EnsembleWorldModel(nn.Module):
    """K ``WorldModel`` members behind one world model's interface (see the module doc)."""

    def __init__(self, members: list):
        super().__init__()
        if len(members) < 1:
            raise ValueError("an ensemble needs at least one member")
        first = members[0]
        for k, m in enumerate(members):
            if (m.hidden_dim, m.latent_dim) != (first.hidden_dim, first.latent_dim):
                raise ValueError(f"member {k} has (hidden, latent) = {(m.hidden_dim, m.latent_dim)}, "
                                 f"member 0 {(first.hidden_dim, first.latent_dim)}: all must match")
            if getattr(m, "predicts", "state") != getattr(first, "predicts", "state"):
                raise ValueError(f"member {k} predicts {m.predicts!r}, member 0 {first.predicts!r}")
            if getattr(first, "delta_std", None) is not None and not torch.equal(m.delta_std, first.delta_std):
                raise ValueError(f"member {k} has another delta_std than member 0 (set both from the same data)")
        self.members = nn.ModuleList(members)
        self.member_hidden, self.member_latent = first.hidden_dim, first.latent_dim
        # What the rest of the package reads: the sizes of the concatenated state.
        self.hidden_dim, self.latent_dim = len(members) * first.hidden_dim, len(members) * first.latent_dim
        self.predicts = getattr(first, "predicts", "state")

    def __len__(self) -> int:
        return len(self.members)

    @property
    def delta_std(self):
        """The members' (shared) scale of decoded changes; None for a ``"state"`` model."""
        return getattr(self.members[0], "delta_std", None)

    # --- splitting and joining the concatenated state ------------------------------------------
    def _hs(self, h):
        return h.split(self.member_hidden, dim=-1)

    def _zs(self, z):
        return z.split(self.member_latent, dim=-1)

    @staticmethod
    def _join(parts):
        return torch.cat(list(parts), dim=-1)

    # --- the world model's interface -----------------------------------------------------------
    def _init(self, batch: int):
        """Zero state: h (B, K*H), z (B, K*Z)."""
        inits = [m._init(batch) for m in self.members]
        return self._join(h for h, _ in inits), self._join(z for _, z in inits)

    def filter_step(self, h, norm_obs):
        """Each member's posterior latent of the same real frame given its own memory: (B, K*Z)."""
        return self._join(m.filter_step(hk, norm_obs) for m, hk in zip(self.members, self._hs(h)))

    def gru(self, x, h):
        """``wm.gru(torch.cat([z, a], -1), h)`` as for one model: each member steps its own memory
        on its own latent and the shared action."""
        z, action = x.split([self.latent_dim, x.shape[-1] - self.latent_dim], dim=-1)
        return self._join(m.gru(torch.cat([zk, action], dim=-1), hk)
                          for m, zk, hk in zip(self.members, self._zs(z), self._hs(h)))

    def prior(self, h):
        """Each member's prior latent from its own memory: (..., K*H) -> (..., K*Z)."""
        return self._join(m.prior(hk) for m, hk in zip(self.members, self._hs(h)))

    def img_step(self, h, z, action):
        """One dreamed step of every member under the same action: (h, z, a) -> (h', z')."""
        steps = [m.img_step(hk, zk, action) for m, hk, zk in zip(self.members, self._hs(h), self._zs(z))]
        return self._join(s[0] for s in steps), self._join(s[1] for s in steps)

    def member_outputs(self, h, z):
        """Each member's decoder output of its own state: (K, ..., D)."""
        return torch.stack([m.decode(hk, zk) for m, hk, zk in zip(self.members, self._hs(h), self._zs(z))])

    def decode(self, h, z):
        """The members' mean decoder output; any leading shape."""
        return self.member_outputs(h, z).mean(0)

    def decoder(self, states):
        """``decode`` of concatenated states [h, z] (..., K*(H+Z)), as ``WorldModel.decoder`` is."""
        h, z = states.split([self.hidden_dim, self.latent_dim], dim=-1)
        return self.decode(h, z)

    def member_frames(self, hs, zs, obs0=None, includes_start: bool = True):
        """Each member's dreamed frames (``WorldModel.decode_dream``) of its own states: (K, T', B, D)."""
        return torch.stack([m.decode_dream(hk, zk, obs0, includes_start=includes_start)
                            for m, hk, zk in zip(self.members, self._hs(hs), self._zs(zs))])

    def decode_dream(self, hs, zs, obs0, includes_start: bool = True):
        """The members' mean dreamed frames (see ``WorldModel.decode_dream``): (T', B, D)."""
        return self.member_frames(hs, zs, obs0, includes_start).mean(0)

    def accumulate(self, out, obs0, dim: int = 0):
        """``WorldModel.accumulate`` of the mean output (linear, and the members share ``delta_std``)."""
        return self.members[0].accumulate(out, obs0, dim)

    def step(self, h, z, action):
        """One dreamed step: (h', z', the members' mean decoder output)."""
        h, z = self.img_step(h, z, action)
        return h, z, self.decode(h, z)

    def filter(self, obs, act):
        """Every member filters the same real sequences: h (B, T+1, K*H), z (B, T+1, K*Z)."""
        out = [m.filter(obs, act) for m in self.members]
        return self._join(h for h, _ in out), self._join(z for _, z in out)

    def warm(self, ctx_obs, ctx_act):
        """Filter the context frames; the last (h, z), concatenated over members."""
        h, z = self.filter(ctx_obs, ctx_act)
        return h[:, -1], z[:, -1]

    def observe(self, obs, act):
        """The members' mean (recon_loss, dyn_loss); training goes member by member (see wm_stage.py)."""
        losses = [m.observe(obs, act) for m in self.members]
        return (torch.stack([r for r, _ in losses]).mean(), torch.stack([d for _, d in losses]).mean())

    # --- the penalty ---------------------------------------------------------------------------
    def disagreement(self, states, std=None, obs0=None, includes_start: bool = False):
        """How far apart the members put the block: (..., K*(H+Z)) states -> (...).

        For each state, the root-mean-square distance of the members' decoded block centres (dims
        2:4 of each member's frame) from their mean, i.e. sqrt(var_x + var_y) across members, with
        population variances. Units: normalised observation units when ``std`` is None; metres when
        ``std`` (D,) is given (the block's dims are scaled back first). Zero where all members
        agree, for K = 1 in particular; differentiable, with a zero (not NaN) gradient at zero.

        ``states`` (T', B, S) stacks a dream's states in time order (any leading shape for a
        ``"state"`` model). ``obs0`` (B, D) and ``includes_start`` are as in ``decode_dream``: a
        ``"delta"`` model's frames are its decoded changes added up from the start frame.
        """
        hs, zs = states.split([self.hidden_dim, self.latent_dim], dim=-1)
        if self.predicts == "state":
            frames = self.member_outputs(hs, zs)                           # (K, ..., D)
        else:
            frames = self.member_frames(hs, zs, obs0, includes_start)
        return block_disagreement(frames, std)


def ensemble_history(hists: list[dict]) -> dict:
    """The members' world-model training curves -> ``recon``/``dyn`` (their mean per update, what
    metrics.json reads) plus ``recon_members``/``dyn_members`` (K, updates)."""
    out = {}
    for key in ("recon", "dyn"):
        per_member = np.stack([h[key] for h in hists])
        out[key], out[f"{key}_members"] = per_member.mean(0), per_member
    return out


@torch.inference_mode()
def dream_disagreement(wm: EnsembleWorldModel, obs0: np.ndarray, actions: np.ndarray, mean, std):
    """Re-dream recorded actions from real start frames and measure the members' disagreement.

    ``obs0`` (B, 6) metres: the start frames (``rollouts["real"].obs[0]``); ``actions`` (T, B, 2):
    the dream's own actions (``rollouts["dream"].actions``). The dream is warmed exactly as
    ``evaluate.dream`` warms it (h = 0, z from the start frame), so under the deterministic policy
    it retraces the evaluation dream. Returns (T, B): metres, after each dreamed step.
    """
    mean_np, std_np = mean.detach().cpu().numpy(), std.detach().cpu().numpy()
    norm0 = torch.as_tensor((obs0 - mean_np) / std_np, dtype=torch.float32, device=mean.device)
    acts = torch.as_tensor(actions, dtype=torch.float32, device=mean.device)
    h, _ = wm._init(norm0.shape[0])
    z = wm.filter_step(h, norm0)
    states = [torch.cat([h, z], dim=-1)]
    for a in acts:
        h, z = wm.img_step(h, z, a)
        states.append(torch.cat([h, z], dim=-1))
    d = wm.disagreement(torch.stack(states), std, obs0=norm0, includes_start=True)   # (T+1, B)
    return d[1:].double().cpu().numpy()


def disagreement_metrics(wm: EnsembleWorldModel, rollouts: dict, mean, std, train_horizon: int) -> dict:
    """metrics.json's view of the ensemble: its members' mean disagreement (m) along the trained
    policy's evaluation dream, over the actor's training horizon and over the whole dream."""
    d = dream_disagreement(wm, rollouts["real"].obs[0], rollouts["dream"].actions, mean, std)
    return {"wm_ensemble_disagreement_train_horizon": float(d[:train_horizon].mean()),
            "wm_ensemble_disagreement_eval_horizon": float(d.mean())}
