"""3.1's world model: encoder, GRU, prior, posterior, decoder, with a deterministic latent.

The state is a pair: ``h`` (the GRU's memory of the past) and ``z`` (a latent for the present).

* filtering on real frames:  ``z_t = posterior(h_t, encoder(o_t))``,  ``h_{t+1} = gru([z_t, a_t], h_t)``
* dreaming, no frames:       ``h_{t+1} = gru([z_t, a_t], h_t)``,      ``z_{t+1} = prior(h_{t+1})``
* either way, an observation: ``o_hat = decoder(h, z)``

Training (``observe``) filters real sequences and minimises two losses: reconstruction (decode each
filtered state back to its frame) and dynamics (the prior, which never sees the frame, must predict
the posterior's latent from ``h`` alone). The dynamics loss is what makes dreaming possible: in a
dream only the prior is available.

What the decoder predicts (``predicts``):

* ``"state"`` (the chapter's model): ``decode(h, z)`` is the normalised observation itself.
* ``"delta"``: ``decode(h, z)`` is the CHANGE since the previous frame, ``o_t - o_{t-1}`` in
  normalised units, divided by ``delta_std`` (the std of those one-step changes in the training
  data, per dimension; set by :meth:`WorldModel.set_delta_scale`), as CS285's dynamics models
  predict normalised deltas. A dream's frames are the start frame plus the running sum of the
  decoded changes. The start state's own output is never used (it has no previous frame).

Every dream decodes through :meth:`WorldModel.decode_dream`, which gives frames for either kind
(for ``"state"`` it is exactly ``decode``).
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from .optim import Adam


def mlp(inp: int, hidden: int, out: int, final: nn.Module | None = None) -> nn.Sequential:
    """One hidden layer: the world model is deliberately tiny."""
    layers = [nn.Linear(inp, hidden), nn.ReLU(), nn.Linear(hidden, out)]
    return nn.Sequential(*layers, *([final] if final is not None else []))


PREDICTS = ("state", "delta")
DELTA_STD_FLOOR = 1e-6


class WorldModel(nn.Module):
    def __init__(self, obs_dim: int, act_dim: int, latent_dim: int, hidden_dim: int, embed_dim: int,
                 predicts: str = "state"):
        super().__init__()
        if predicts not in PREDICTS:
            raise ValueError(f"predicts must be one of {PREDICTS}, got {predicts!r}")
        self.latent_dim, self.hidden_dim, self.predicts = latent_dim, hidden_dim, predicts
        # (D,) scale of the decoded changes of a "delta" model (ones until set_delta_scale). A None
        # buffer for "state": nothing in its state_dict, so its weights hash as they always did.
        self.register_buffer("delta_std", torch.ones(obs_dim) if predicts == "delta" else None)
        self.encoder = mlp(obs_dim, hidden_dim, embed_dim)
        # tanh keeps both latents in [-1, 1], so the dynamics loss cannot shrink by rescaling z.
        self.posterior = mlp(hidden_dim + embed_dim, hidden_dim, latent_dim, nn.Tanh())
        self.prior = mlp(hidden_dim, hidden_dim, latent_dim, nn.Tanh())
        self.gru = nn.GRUCell(latent_dim + act_dim, hidden_dim)
        self.decoder = mlp(hidden_dim + latent_dim, hidden_dim, obs_dim)

    # --- the pieces --------------------------------------------------------------------------
    def _init(self, batch: int):
        """Zero state (h, z) for ``batch`` sequences."""
        w = self.prior[0].weight
        return w.new_zeros(batch, self.hidden_dim), w.new_zeros(batch, self.latent_dim)

    def filter_step(self, h, norm_obs):
        """Posterior latent of a real (normalised) frame given the memory h: (B, D) -> (B, Z)."""
        return self.posterior(torch.cat([h, self.encoder(norm_obs)], dim=-1))

    def img_step(self, h, z, action):
        """One dreamed step without decoding: (h, z, a) -> (h', z') from the prior."""
        h = self.gru(torch.cat([z, action], dim=-1), h)
        return h, self.prior(h)

    def decode(self, h, z):
        """The decoder's output for state (h, z); any leading shape. For ``"state"`` the normalised
        observation; for ``"delta"`` the change since the previous frame over ``delta_std``."""
        return self.decoder(torch.cat([h, z], dim=-1))

    def set_delta_scale(self, norm_obs) -> None:
        """``delta_std`` := per-dimension std of the one-step changes of ``norm_obs`` (N, T+1, D)
        (normalised training sequences), floored at 1e-6. Only for a ``"delta"`` model."""
        if self.predicts != "delta":
            raise ValueError(f"set_delta_scale is for a 'delta' model; this one predicts {self.predicts!r}")
        d = (norm_obs[:, 1:] - norm_obs[:, :-1]).reshape(-1, norm_obs.shape[-1])
        self.delta_std.copy_(d.std(dim=0).clamp_min(DELTA_STD_FLOOR))

    def decode_dream(self, hs, zs, obs0, includes_start: bool = True):
        """Normalised frames of a dream: every dream decodes through this.

        ``hs`` (T', B, H), ``zs`` (T', B, Z): the dream's states in time order; ``obs0`` (B, D) the
        normalised real frame the dream starts from (may be None for a ``"state"`` model).
        ``includes_start``: ``hs[0]`` is the state filtered on ``obs0`` itself (as in
        ``evaluate.dream``); otherwise ``hs[0]`` is the state one step after it (as in
        ``imagination.imagine``). Returns (T', B, D), frame t decoded from state t.

        * ``"state"``: exactly ``self.decode(hs, zs)``, the start included.
        * ``"delta"``: the start state decodes to ``obs0`` itself; each later frame is the previous
          one plus its state's decoded change times ``delta_std``.
        """
        out = self.decode(hs, zs)
        if self.predicts == "state":
            return out
        if obs0 is None:
            raise ValueError("a 'delta' model's dream needs the start frame obs0 to add its changes to")
        if includes_start:
            return torch.cat([obs0[None], self.accumulate(out[1:], obs0)])
        return self.accumulate(out, obs0)

    def accumulate(self, out, obs0, dim: int = 0):
        """Decoder outputs of consecutive states after the frame ``obs0``, in time order along
        ``dim`` -> their normalised frames. ``"state"``: ``out`` itself; ``"delta"``:
        ``obs0`` plus the running sum of ``out * delta_std``."""
        if self.predicts == "state":
            return out
        return obs0.unsqueeze(dim) + (out * self.delta_std).cumsum(dim)

    def step(self, h, z, action):
        """One dreamed step: returns (h', z', the decoder's output): the normalised observation for
        ``"state"``, the scaled change for ``"delta"`` (to get frames, see :meth:`accumulate`)."""
        h, z = self.img_step(h, z, action)
        return h, z, self.decode(h, z)

    # --- on real sequences ---------------------------------------------------------------------
    def filter(self, obs, act):
        """Filter real sequences. obs (B, T+1, D), act (B, T, A) -> h, z of shape (B, T+1, .)."""
        embed = self.encoder(obs)                                   # (B, T+1, E): all frames at once
        h, _ = self._init(obs.shape[0])
        hs, zs = [], []
        for t in range(obs.shape[1]):
            z = self.posterior(torch.cat([h, embed[:, t]], dim=-1))
            hs.append(h)
            zs.append(z)
            if t < act.shape[1]:
                h = self.gru(torch.cat([z, act[:, t]], dim=-1), h)
        return torch.stack(hs, 1), torch.stack(zs, 1)

    def observe(self, obs, act):
        """The two training losses on real sequences: (recon_loss, dyn_loss), both scalars.

        ``"state"``: reconstruction decodes every filtered state to its frame. ``"delta"``: it
        decodes each filtered state t >= 1 to (o_t - o_{t-1}) / delta_std (so its loss is in units
        of the changes' own variance, not comparable with a state model's)."""
        h, z = self.filter(obs, act)                                # (B, T+1, H), (B, T+1, Z)
        if self.predicts == "delta":
            target = (obs[:, 1:] - obs[:, :-1]) / self.delta_std
            recon_loss = F.mse_loss(self.decode(h[:, 1:], z[:, 1:]), target)
        else:
            recon_loss = F.mse_loss(self.decode(h, z), obs)
        # The prior learns to imitate the posterior; the posterior is shaped by reconstruction only.
        dyn_loss = F.mse_loss(self.prior(h[:, 1:]), z[:, 1:].detach())
        return recon_loss, dyn_loss

    def warm(self, ctx_obs, ctx_act):
        """Filter C+1 real frames (B, C+1, D) under C actions (B, C, A); the last (h, z)."""
        h, z = self.filter(ctx_obs, ctx_act)
        return h[:, -1], z[:, -1]


def train_world_model(wm, obs, act, cfg, gen: torch.Generator, progress=None, log=print):
    """Adam on recon + dyn over ``cfg.wm_epochs`` shuffled passes. Returns per-update losses.

    ``obs`` (N, T+1, D) and ``act`` (N, T, A) are normalised tensors; ``gen`` orders the batches.
    ``progress`` wraps the epoch range (e.g. ``tqdm``). ``log`` gets a line every 15 epochs.
    """
    opt = Adam(wm.parameters(), lr=cfg.wm_lr)
    recon_hist, dyn_hist = [], []
    epochs = range(cfg.wm_epochs)
    for epoch in (progress(epochs) if progress else epochs):
        for batch in torch.randperm(len(obs), generator=gen).split(cfg.batch_size):
            recon_loss, dyn_loss = wm.observe(obs[batch], act[batch])
            opt.zero_grad()
            (recon_loss + dyn_loss).backward()
            opt.step()
            recon_hist.append(recon_loss.item())
            dyn_hist.append(dyn_loss.item())
        if log and (epoch % 15 == 0 or epoch == cfg.wm_epochs - 1):
            n = -(-len(obs) // cfg.batch_size)
            log(f"[wm] epoch {epoch:3d}  recon {np.mean(recon_hist[-n:]):.5f}  "
                f"dyn {np.mean(dyn_hist[-n:]):.5f}")
    return {"recon": np.array(recon_hist), "dyn": np.array(dyn_hist)}


@torch.no_grad()
def prediction_error_vs_copy_last(wm, obs, act, std, context: int = 2):
    """3.1's measurement: per-dimension RMSE of the model against a copy-last-frame baseline.

    ``obs`` (N, T+1, D), ``act`` (N, T, A): normalised held-out sequences; ``std`` (D,) converts
    errors back to physical units (metres for positions, unitless for sin/cos).

    * one-step: filter the true frames up to t, dream one step under a_t, decode; copy-last
      predicts o_{t+1} = o_t. (A ``"delta"`` model predicts o_t plus its decoded change.)
    * open-loop: filter ``context`` + 1 frames, then dream the rest of the sequence under the true
      actions with no frames; copy-last holds the last filtered frame. (A ``"delta"`` model
      accumulates its changes from that frame.)

    Returns a dict of (D,) numpy arrays: ``one_step_model``, ``one_step_copy``,
    ``open_loop_model``, ``open_loop_copy`` and the fraction of one-step transitions in which the
    block moved more than 1 mm (``block_moving_fraction``, a scalar).
    """
    std = torch.as_tensor(std, dtype=obs.dtype)
    h, _ = wm.filter(obs, act)
    pred = wm.decode(h[:, 1:], wm.prior(h[:, 1:]))                  # (N, T, D): one-step predictions
    if wm.predicts == "delta":                                      # o_{t+1} = o_t + change
        pred = obs[:, :-1] + pred * wm.delta_std

    def rmse(a, b):
        return (((a - b) * std) ** 2).mean(dim=(0, 1)).sqrt().numpy()

    one_model, one_copy = rmse(pred, obs[:, 1:]), rmse(obs[:, :-1], obs[:, 1:])

    hc, zc = wm.warm(obs[:, : context + 1], act[:, :context])
    preds = []
    for t in range(context, act.shape[1]):
        hc, zc, o = wm.step(hc, zc, act[:, t])
        preds.append(o)
    preds = wm.accumulate(torch.stack(preds, 1), obs[:, context], dim=1)   # (N, T-context, D)
    target = obs[:, context + 1:]
    last = obs[:, context: context + 1].expand_as(target)
    block_step = ((obs[:, 1:, 2:4] - obs[:, :-1, 2:4]) * std[2:4]).norm(dim=-1)
    return {
        "one_step_model": one_model, "one_step_copy": one_copy,
        "open_loop_model": rmse(preds, target), "open_loop_copy": rmse(last, target),
        "block_moving_fraction": float((block_step > 1e-3).float().mean()),
    }
