"""What the autograder runs inside a student's kernel: probes that record raw numbers, nothing else.

A hidden test that asserts inside the student's kernel can be fooled by the student's own code
(patch ``torch.allclose``, replace the reference, return an always-equal object, hide the error).
So while grading, a test cell only calls ::

    submit("reward_impl_tests", reward_from_obs)

which reads the probe cases the grader wrote to ``$PUSHT_GRADING_DIR/cases/<test>.json``, calls the
student's function on each, and saves what came back (plain float arrays, shapes, gradients, error
messages) to ``$PUSHT_GRADING_DIR/results/<test>.npz``. The verdict is made afterwards, outside
the kernel, by the grader's own process: it runs the SAME probes on the package's reference
implementation and compares the arrays (``autograde/checks.py``). Nothing the student's code does
in the kernel can change the reference numbers, and an object that is not a plain array of numbers
cannot be saved at all.

Outside grading (``PUSHT_GRADING_DIR`` unset), ``submit`` does nothing, so learners never notice it.

The chapter's reference implementations of the exercises (``reward_from_obs``, ``lambda_return``,
``actor_critic_losses``, ``dream``, ``block_disagreement``) are marked ``@reference``: during a
probe they refuse to run, so a submission that merely delegates to the package's own
implementation produces no numbers (and the grader's static check of the student's source says
why it earns no credit).
"""

from __future__ import annotations

import functools
import json
import os
import sys
from pathlib import Path

_PROBING = False           # True only while submit() runs a student's function


class ReferenceRefused(RuntimeError):
    """The package's reference implementation of an exercise was called during grading."""


def reference(exercise: str):
    """Mark a package function as the reference implementation of ``exercise``."""
    def wrap(fn):
        @functools.wraps(fn)
        def guarded(*args, **kwargs):
            if _PROBING:
                raise ReferenceRefused(
                    f"{fn.__module__}.{fn.__name__} is the package's own solution to {exercise}; "
                    f"while grading, your function must compute the result itself")
            return fn(*args, **kwargs)
        guarded.__pusht_reference__ = exercise
        return guarded
    return wrap


# --- building the probe inputs (the grader builds exactly the same ones in its own process) -------
def _torch():
    import torch
    return torch


def build_arg(spec, fresh: int):
    """One argument of a probe call from its JSON spec.

    ``{"agent": {"seed", "state", "hidden"}}`` a freshly seeded ``ActorCritic``;
    ``{"fn": "lambda_return"}`` the chapter's lambda-return (not refused while probing: an
    exercise may build on it); ``{"t": nested list}`` a float32 tensor; ``{"randn": shape, "seed": s}`` standard normal from
    ``torch.Generator().manual_seed(s)`` (``"fresh": true`` adds the per-run random ``fresh`` to
    the seed, so inputs cannot be known in advance); ``{"rand": shape, "seed": s, "lo", "hi"}``
    uniform; ``"grad": true`` makes it a leaf that requires grad. Numbers pass through.
    """
    torch = _torch()
    if not isinstance(spec, dict):
        return spec
    if "agent" in spec:                   # {"agent": {"seed", "state", "hidden"}}: an ActorCritic
        from .agent import ActorCritic

        a = spec["agent"]
        torch.manual_seed(int(a["seed"]))
        return ActorCritic(int(a["state"]), 2, int(a["hidden"]))
    if spec.get("fn") == "lambda_return":   # the chapter's return, usable while probing
        from .imagination import lambda_return
        return lambda_return.__wrapped__
    if "t" in spec:
        x = torch.tensor(spec["t"], dtype=torch.float32)
    else:
        seed = int(spec.get("seed", 0)) + (fresh if spec.get("fresh") else 0)
        g = torch.Generator().manual_seed(seed)
        if "randn" in spec:
            x = torch.randn(*spec["randn"], generator=g)
        else:
            lo, hi = spec.get("lo", 0.0), spec.get("hi", 1.0)
            x = lo + (hi - lo) * torch.rand(*spec["rand"], generator=g)
    if spec.get("grad"):
        x.requires_grad_(True)
    return x


def _as_array(x):
    """A float64 numpy array of a tensor (or of something numeric); raises TypeError otherwise."""
    import numpy as np

    torch = _torch()
    if type(x) is torch.Tensor or (isinstance(x, torch.Tensor) and type(x).__module__.startswith("torch")):
        return np.array(x.detach().cpu().double().numpy(), dtype=np.float64, copy=True)
    if isinstance(x, (int, float)) and not isinstance(x, bool):
        return np.array(float(x))
    raise TypeError(f"expected a torch tensor, got {type(x).__name__}")


def _outputs(result) -> list:
    return list(result) if isinstance(result, (tuple, list)) else [result]


def _dream_models(case):
    """The world model, policy and start frames of a ``dream`` probe, built from seeds."""
    torch = _torch()
    from .agent import ActorCritic
    from .evaluate import policy_of, zero_policy
    from .world_model import WorldModel

    m = case["model"]
    torch.manual_seed(m["seed"])
    wm = WorldModel(6, 2, latent_dim=m["latent"], hidden_dim=m["hidden"], embed_dim=m["embed"]).eval()
    seen = []
    if case["policy"] == "zero":
        policy = zero_policy
    elif case["policy"] == "recording":
        def policy(state):
            seen.append(state.detach().clone())
            return torch.tanh(state[:, :2] + 0.3)
    else:
        policy = policy_of(ActorCritic(m["hidden"] + m["latent"], 2, int(case["policy"])))
    obs0 = build_arg(case["obs0"], 0)
    return wm, policy, obs0, seen


def probe(case: dict, fn, fresh: int = 0) -> dict:
    """Run one probe case on ``fn``; returns {name: float64 array} (or raises what ``fn`` raised).

    Kinds: ``call`` (the outputs, and every tensor argument after the call, to catch in-place
    edits), ``grad`` (gradients of the sum of output ``of`` (optionally row ``row``) with respect
    to every argument that requires grad, and to the parameters of each module argument's parts
    named in ``module_grads``), ``dream`` (decoded frames, actions, encoder and
    posterior call counts, the states a recording policy saw, the largest change of any model
    parameter).
    """
    import numpy as np

    torch = _torch()
    out: dict = {}
    kind = case["kind"]
    if kind in ("call", "grad"):
        args = [build_arg(a, fresh) for a in case["args"]]
        with torch.enable_grad():
            result = _outputs(fn(*args))
            if kind == "grad":
                y = result[case.get("of", 0)]
                if not isinstance(y, torch.Tensor) or not y.requires_grad:
                    raise TypeError("the result is not differentiable (no gradient reaches the inputs): "
                                    "stay in torch, no .item(), numpy or torch.no_grad")
                if "row" in case:
                    y = y[case["row"]]
                y.sum().backward()
                for j, a in enumerate(args):
                    if isinstance(a, torch.Tensor) and a.requires_grad:
                        out[f"grad{j}"] = _as_array(a.grad if a.grad is not None else torch.zeros_like(a))
                    elif isinstance(a, torch.nn.Module):
                        for part in case.get("module_grads", []):
                            params = list(getattr(a, part).parameters())
                            out[f"grad{j}.{part}"] = np.concatenate([
                                _as_array(p.grad if p.grad is not None else torch.zeros_like(p)).ravel()
                                for p in params])
                return out
        for k, r in enumerate(result):
            out[f"out{k}"] = _as_array(r)
        for j, a in enumerate(args):
            if isinstance(a, torch.Tensor):
                out[f"arg{j}_after"] = _as_array(a)
        return out
    if kind == "dream":
        wm, policy, obs0, seen = _dream_models(case)
        before = [p.detach().clone() for p in wm.parameters()]
        calls = {"posterior": 0, "encoder": 0}
        hooks = [getattr(wm, k).register_forward_hook(
            lambda mod, inp, o, k=k: calls.__setitem__(k, calls[k] + 1)) for k in calls]
        mode = torch.inference_mode() if case.get("mode") == "inference" else torch.no_grad()
        try:
            with mode:
                result = _outputs(fn(wm, policy, obs0, int(case["horizon"])))
        finally:
            for hk in hooks:
                hk.remove()
        for k, r in enumerate(result[:2]):
            out[f"out{k}"] = _as_array(r)
        out["n_outputs"] = np.array(float(len(result)))
        out["calls"] = np.array([float(calls["posterior"]), float(calls["encoder"])])
        if case["policy"] == "recording":
            out["policy_inputs"] = (np.stack([_as_array(s) for s in seen]) if seen else np.zeros(0))
        out["param_change"] = np.array(max(float((p.detach() - b).abs().max())
                                           for p, b in zip(wm.parameters(), before)))
        return out
    raise ValueError(f"unknown probe kind {kind!r}")


def submit(test_id: str, fn) -> None:
    """Record ``fn``'s raw results on the grader's probe cases for ``test_id`` (grading only)."""
    global _PROBING
    root = os.environ.get("PUSHT_GRADING_DIR")
    if not root:
        return
    import numpy as np

    cases = json.loads((Path(root) / "cases" / f"{test_id}.json").read_text())
    fresh = int.from_bytes(os.urandom(3), "little")
    saved: dict = {"fresh": np.array(float(fresh))}
    stopped = None
    for i, case in enumerate(cases):
        _PROBING = True
        try:
            for key, value in probe(case, fn, fresh).items():
                saved[f"c{i}.{key}"] = value
        except BaseException as e:        # a KeyboardInterrupt from the cell timeout stops here too
            saved[f"c{i}.error"] = np.array(f"{type(e).__name__}: {str(e)[:300]}")
            if not isinstance(e, Exception):
                stopped = e
                break
        finally:
            _PROBING = False
    out = Path(root) / "results"
    out.mkdir(parents=True, exist_ok=True)
    np.savez(out / f"{test_id}.npz", **saved)
    if stopped is not None:
        raise stopped
    print(f"[graded outside this kernel] {test_id}: {len(cases)} checks recorded", file=sys.stdout)
