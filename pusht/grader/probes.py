"""The hidden tests' probes: inputs built from the grader's specs, the raw numbers that came out.

A hidden test that asserts inside the student's kernel can be fooled by the student's own code,
and so can anything the kernel writes for the grader to read later. So the kernel's run of a
notebook decides no verdict. Once a notebook is handed in, the grader (``autograde/probe.py``)
takes the definitions of the notebook's cells above each test cell and runs them, with the probe
cases and a fresh random ``nonce`` the grader chose, in a process it started itself: a sandbox of
its own (``pusht.grader.probe_server``) in which this package's implementations of the exercises are
absent (their bodies replaced, ``reference`` below). The raw numbers come back over a pipe, and
the grader compares them with the same probes run on the real implementations in its own
process (``autograde/checks.py``). Every input of a hidden case is drawn from the run's nonce by a
generator of ``cases.py`` (``expand``, which ``probe`` calls first).

The chapter's implementations of the exercises (``reward_from_obs``, ``lambda_return``,
``actor_critic_losses``, ``dream``, ``block_disagreement``, ``cem_update``) are marked ``@reference``; the grader
finds them by that mark (``autograde/stripped.py``, by ``pusht.reference``'s mark) and ships the probe process a copy of the
package in which each of them only raises ``ReferenceRefused``. The hidden test cells' own line,
``pusht.grading.submit``, is the learner's side of this and lives apart (``pusht/grading.py``).
"""

from __future__ import annotations

import base64
import json

from .cases import CASE_SEEDS, GENERATORS, Draw, expand, generator  # noqa: F401  (reached through here too)

MAX_RESULTS = 4 << 20      # bytes of encoded results: far more than any test's probes give


# --- building the probe inputs (the grader builds exactly the same ones in its own process) -------
def _torch():
    import torch
    return torch


def build_arg(spec, fresh: int, helpers: dict | None = None):
    """One argument of a probe call from its JSON spec.

    ``{"agent": {"seed", "state", "hidden"}}`` a freshly seeded ``ActorCritic``;
    ``{"fn": name}`` the function ``helpers[name]`` (the chapter's lambda-return, which the losses
    exercise is given: the grader sends its source to that probe alone); ``{"t": nested list}`` a float32 tensor; ``{"randn": shape, "seed": s}`` standard normal from
    ``torch.Generator().manual_seed(s)`` (``"fresh": true`` adds the per-run random ``fresh`` to
    the seed, so inputs cannot be known in advance); ``{"rand": shape, "seed": s, "lo", "hi"}``
    uniform; ``"grad": true`` makes it a leaf that requires grad. Numbers, tensors and modules pass
    through (a generated case's arguments, ``expand``).
    """
    torch = _torch()
    if not isinstance(spec, dict):
        return spec
    if "agent" in spec:                   # {"agent": {"seed", "state", "hidden"}}: an ActorCritic
        from ..agent import ActorCritic

        a = spec["agent"]
        torch.manual_seed(int(a["seed"]))
        return ActorCritic(int(a["state"]), 2, int(a["hidden"]))
    if "fn" in spec:                      # a function the grader hands the probe (``helpers``)
        if spec["fn"] not in (helpers or {}):
            raise ValueError(f"this probe needs the function {spec['fn']!r}, which it was not given")
        return helpers[spec["fn"]]
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


def _dream_models(case, fresh: int = 0):
    """The world model, policy and start frames of a ``dream`` probe, built from seeds."""
    torch = _torch()
    from ..agent import ActorCritic
    from ..evaluate import policy_of, zero_policy
    from ..world_model import WorldModel

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
    obs0 = build_arg(case["obs0"], fresh)
    return wm, policy, obs0, seen


def probe(case: dict, fn, fresh: int = 0, helpers: dict | None = None) -> dict:
    """Run one probe case on ``fn``; returns {name: float64 array} (or raises what ``fn`` raised).

    A generated case (``"gen"``) is expanded first (``expand``). Kinds: ``call`` (the outputs, and
    every tensor argument after the call, to catch in-place edits), ``grad`` (gradients of the sum
    of output ``of`` (optionally row ``row``) with respect to every argument that requires grad,
    and to the parameters of each module argument's parts named in ``module_grads``), ``dream``
    (decoded frames, actions, encoder and posterior call counts, the states a recording policy
    saw, the largest change of any model parameter).
    """
    import numpy as np

    torch = _torch()
    out: dict = {}
    case = expand(case, fresh)
    kind = case["kind"]
    if kind in ("call", "grad"):
        args = [build_arg(a, fresh, helpers) for a in case["args"]]
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
        wm, policy, obs0, seen = _dream_models(case, fresh)
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


def run_probes(cases: list, fn, fresh: int, helpers: dict | None = None) -> list:
    """Every case of a test on ``fn``: a list, per case, of {name: float64 array} or the error it raised
    (a string). A KeyboardInterrupt or SystemExit stops the cases after it (each is an error)."""
    out = []
    for case in cases:
        try:
            out.append(probe(case, fn, fresh, helpers))
        except Exception as e:            # noqa: BLE001  the student's function raised it
            out.append(f"{type(e).__name__}: {str(e)[:300]}")
        except BaseException as e:        # noqa: BLE001  exit, interrupt: the remaining cases are not run
            out.append(f"{type(e).__name__}: {str(e)[:300]}")
            out += ["not run: an earlier case stopped the function"] * (len(cases) - len(out))
            break
    return out


def encode_results(results: list, setup: list = ()) -> bytes:
    """``run_probes``'s results as bytes for the pipe: JSON, arrays as float64 bytes in base64;
    ``setup``: what went wrong defining the function (a few lines for the learner)."""
    import numpy as np

    def one(r):
        if isinstance(r, str):
            return {"error": r[:400]}
        return {k: [list(v.shape), base64.b64encode(np.ascontiguousarray(v, dtype="<f8").tobytes()).decode()]
                for k, v in r.items()}
    return json.dumps({"setup": [str(x)[:400] for x in list(setup)[:5]],
                       "results": [one(r) for r in results]}).encode()


def decode_results(data: bytes, n_cases: int) -> tuple[list, list]:
    """The inverse of ``encode_results``, for bytes that came from an untrusted process: (the setup
    lines, a list of ``n_cases`` entries, each {name: float64 array} or an error string). Bytes that are too many,
    not this format, or arrays whose size does not match their shape raise ValueError. Nothing is
    decompressed, nothing evaluated, and no array is larger than the bytes that carried it."""
    import numpy as np

    if len(data) > MAX_RESULTS:
        raise ValueError(f"more than {MAX_RESULTS} bytes of results")
    try:
        whole = json.loads(data.decode("utf-8"))
    except (RecursionError, UnicodeDecodeError) as e:
        raise ValueError(f"unreadable results ({type(e).__name__})") from None
    if not isinstance(whole, dict) or not isinstance(whole.get("setup"), list):
        raise ValueError("not the probe format")
    setup = [str(x)[:400] for x in whole["setup"][:5]]
    raw = whole.get("results")
    if not isinstance(raw, list) or len(raw) != n_cases:
        raise ValueError("not one result per case")
    out = []
    for r in raw:
        if not isinstance(r, dict):
            raise ValueError("a result is not a mapping")
        if set(r) == {"error"}:
            out.append(str(r["error"])[:400])
            continue
        arrays = {}
        for k, v in r.items():
            if not (isinstance(k, str) and len(k) < 64 and isinstance(v, list) and len(v) == 2
                    and isinstance(v[0], list) and isinstance(v[1], str) and len(v[0]) <= 8
                    and all(isinstance(d, int) and 0 <= d for d in v[0])):
                raise ValueError("a result is not in the probe format")
            buf = base64.b64decode(v[1], validate=True)
            size = 1
            for d in v[0]:
                size *= d
            if size * 8 != len(buf):
                raise ValueError(f"{k}: {len(buf)} bytes for shape {tuple(v[0])}")
            arrays[k] = np.frombuffer(buf, dtype="<f8").reshape(v[0]).astype(np.float64)
        out.append(arrays)
    return setup, out
