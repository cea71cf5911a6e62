"""Honest variants of the six graded functions: the instructor's answers, rewritten through the
ways Python binds and mutates module state, each one worth full marks.

    python -m autograde.classes.variants OUT.zip [--n 40] [--seed 0] [--work DIR] [--executed DIR]
                                                 [--grade COURSE] [--timeout 120]

A variant is drawn from a ``Recipe``: one graded function, and one choice on each of these axes
(each a "kind"), every combination allowed unless it makes no sense:

* ``store``: where the numbers the function reads live, outside it: nowhere (``none``: the
  literals stay in the body), module globals, a dict, a class's attributes, an instance's
  attributes, a dataclass instance, a list;
* ``binder``: how that store is filled: a literal, tuple unpacking, a function with a ``global``
  statement (called directly, from another function, or from a loop), ``globals().update``, a
  function that mutates its argument (``SCALES = {}; fill(SCALES)``), an alias mutated
  (``c = CONFIG; c['x'] = ...``), a loop, a comprehension, a method (``.update``, a classmethod
  setting class attributes, an instance method), ``__init__``, a class decorator, dataclass
  defaults, or a file that one cell writes (json, text, ``np.save``, pickle; a relative path, the
  temp folder or a ``pathlib.Path``; any handle name) and a later cell reads;
* ``wrap``: the filling statements as they are, or inside ``with torch.no_grad():``, a
  ``contextlib.contextmanager`` of the notebook's own, an ``if``, or a ``try``;
* ``impl``: how the graded name is bound: a ``def``, an alias of a def, a def under an ``if``, a
  decorator that registers it in a dict, a ``functools.wraps`` decorator, ``functools.partial``, a
  lambda, a closure made by a factory, default arguments, a classmethod, a staticmethod, a
  callable instance;
* ``mods``: ``future`` (``from __future__ import annotations`` in the first cell or a cell of its
  own, with annotations naming types the notebook never imports), ``try_import`` (the module the
  function uses imported in a ``try``/``except ImportError``, next to a ``scipy`` import that
  fails here), ``split`` (the filling statements in cells of their own above the answer).

Which of the function's constants leave its body (``keys``) and every name (containers, helpers,
file handles, paths) are drawn too. ``render(recipe)`` is deterministic, so a recipe (printed and
written as JSON next to the class) reproduces its variant exactly. Every variant computes the
instructor's numbers on every input: ``check_in_process`` runs it as IPython would (cell by cell,
``__future__`` flags carried from cell to cell) and judges it with the hidden tests themselves.

``draw_class(n, seed)`` picks ``n`` recipes from many random draws, greedily, so that every kind
(and every store/binder pair, as far as ``n`` allows) appears; the notebook 03 carries two variants
(``lambda_return`` and ``actor_critic_losses``) in one hand-in. ``build`` really executes each
hand-in in a kernel (``honest.execute``: the release, the answers typed in, smoke config), so the
notebook's visible asserts pass on every variant before it is graded.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import random
import re
import textwrap
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

# --- the graded functions, with the constants a variant may move out of the body --------------------


@dataclass(frozen=True)
class Const:
    key: str            # the name it has in a store (and as a local)
    value: str          # its value, as code in the notebook's namespace ({torch}, {F}: module aliases)
    kind: str           # "float", "int" or "fn" (a function: never written to a file)


@dataclass(frozen=True)
class Graded:
    function: str
    notebook: str
    grade_id: str
    test_id: str
    tag: str                        # for the names a variant makes (two variants share notebook 03)
    params: tuple                   # the signature's parameters, defaults included
    ann: dict                       # parameter -> annotation (types the notebook never imports)
    ret: str
    consts: tuple
    body: str                       # with {key} for each constant, {torch} and {F}
    preamble: str                   # what the notebook has bound above the answer (for in-process runs)


GRADED = {g.function: g for g in (
    Graded("reward_from_obs", "02_reward", "reward_impl", "reward_impl_tests", "reward",
           ("norm_obs", "mean", "std"),
           {"norm_obs": "Tensor", "mean": "Tensor", "std": "Tensor"}, "tuple[Tensor, Tensor, Tensor]",
           (Const("pos_scale", "POS_SCALE", "float"), Const("ang_scale", "ANG_SCALE", "float"),
            Const("half", "0.5", "float"), Const("xy0", "2", "int"), Const("xy1", "4", "int"),
            Const("sin_i", "4", "int"), Const("cos_i", "5", "int"),
            Const("norm", "{torch}.linalg.vector_norm", "fn")),
           "obs = norm_obs * std + mean\n"
           "pos_err = {norm}(obs[..., {xy0}:{xy1}], dim=-1)\n"
           "ang_err = {torch}.abs({torch}.atan2(obs[..., {sin_i}], obs[..., {cos_i}]))\n"
           "reward = -{half} * (pos_err / {pos_scale} + ang_err / {ang_scale})\n"
           "return reward, pos_err, ang_err\n",
           "import sys\nimport numpy as np\nimport torch\nfrom pusht.env import ANG_SCALE, POS_SCALE\n"),
    Graded("lambda_return", "03_imagination_actor", "lambda_return_impl", "lambda_return_impl_tests", "lr",
           ("rewards", "values", "gamma", "lam"),
           {"rewards": "Tensor", "values": "Tensor", "gamma": "float", "lam": "float"}, "Tensor",
           (Const("end", "-1", "int"), Const("tdim", "0", "int"), Const("one", "1", "int"),
            Const("stack", "{torch}.stack", "fn")),
           "out, last = [], values[{end}]\n"
           "for t in reversed(range(rewards.shape[{tdim}])):\n"
           "    last = rewards[t] + gamma * (({one} - lam) * values[t + 1] + lam * last)\n"
           "    out.append(last)\n"
           "return {stack}(out[::-1])\n",
           "import sys\nimport numpy as np\nimport torch\nimport torch.nn.functional as F\n"),
    Graded("actor_critic_losses", "03_imagination_actor", "losses_impl", "losses_impl_tests", "ac",
           ("agent", "states", "rewards", "entropy", "gamma", "lam", "ent_coef", "return_fn=lambda_return"),
           {"agent": "Agent", "states": "Tensor", "rewards": "Tensor", "entropy": "Tensor", "gamma": "float",
            "lam": "float", "ent_coef": "float", "return_fn": "Callable[..., Tensor]"}, "tuple[Tensor, Tensor]",
           (Const("half", "0.5", "float"), Const("drop", "-1", "int"), Const("mse", "{F}.mse_loss", "fn")),
           "values = agent.value(states)\n"
           "returns = return_fn(rewards, values, gamma, lam)\n"
           "actor_loss = -(returns.mean() + ent_coef * entropy)\n"
           "critic_loss = {half} * {mse}(agent.value(states.detach())[:{drop}], returns.detach())\n"
           "return actor_loss, critic_loss\n",
           "import sys\nimport numpy as np\nimport torch\nimport torch.nn.functional as F\n"
           "from pusht.imagination import lambda_return\n"),
    Graded("dream", "04_imagination_gap", "dream_impl", "dream_impl_tests", "dream",
           ("wm", "policy", "norm_obs0", "horizon"),
           {"wm": "WorldModel", "policy": "Callable[[Tensor], Tensor]", "norm_obs0": "Tensor", "horizon": "int"},
           "tuple[Tensor, Tensor]",
           (Const("bdim", "0", "int"), Const("cdim", "-1", "int"), Const("cat", "{torch}.cat", "fn"),
            Const("stack", "{torch}.stack", "fn")),
           "h, _ = wm._init(norm_obs0.shape[{bdim}])\n"
           "z = wm.filter_step(h, norm_obs0)\n"
           "hs, zs, actions = [h], [z], []\n"
           "for _ in range(horizon):\n"
           "    a = policy({cat}([h, z], dim={cdim}))\n"
           "    h, z = wm.img_step(h, z, a)\n"
           "    hs.append(h)\n"
           "    zs.append(z)\n"
           "    actions.append(a)\n"
           "return wm.decode({stack}(hs), {stack}(zs)), {stack}(actions)\n",
           "import sys\nimport numpy as np\nimport torch\n"),
    Graded("block_disagreement", "06_closing_the_gap", "block_disagreement_impl", "block_disagreement_impl_tests",
           "bd", ("frames", "std"), {"frames": "Tensor", "std": "Tensor"}, "Tensor",
           (Const("b0", "2", "int"), Const("b1", "4", "int"), Const("kdim", "0", "int"), Const("corr", "0", "int"),
            Const("one", "1.0", "float"), Const("zero", "0.0", "float"), Const("where", "{torch}.where", "fn")),
           "block = frames[..., {b0}:{b1}] * std[{b0}:{b1}]\n"
           "var = block.var(dim={kdim}, correction={corr}).sum(-1)\n"
           "positive = var > {zero}\n"
           "return {where}(positive, {where}(positive, var, {one}).sqrt(), {zero})\n",
           "import sys\nimport numpy as np\nimport torch\n"),
    Graded("cem_update", "07_planning", "cem_update_impl", "cem_update_impl_tests", "cem",
           ("samples", "scores", "elites", "min_std=0.0"),
           {"samples": "Tensor", "scores": "Tensor", "elites": "int", "min_std": "float"}, "tuple[Tensor, Tensor]",
           (Const("sdim", "1", "int"), Const("corr", "0", "int"), Const("stack", "{torch}.stack", "fn")),
           "idx = scores.topk(elites, dim={sdim}).indices\n"
           "best = {stack}([samples[b, idx[b]] for b in range(samples.shape[0])])\n"
           "return best.mean({sdim}), best.std({sdim}, correction={corr}).clamp_min(min_std)\n",
           "import sys\nimport numpy as np\nimport torch\n"),
)}
NOTEBOOK_FUNCTIONS = {}
for _g in GRADED.values():
    NOTEBOOK_FUNCTIONS.setdefault(_g.notebook, []).append(_g.function)

# --- the kinds ----------------------------------------------------------------------------------------
BINDERS = {
    "none": ("inline",),
    "globals": ("literal", "unpack", "global_fn", "globals_update", "mutate_arg", "alias", "loop", "file"),
    "dict": ("literal", "mutate_arg", "alias", "loop", "comprehension", "method", "global_fn", "file"),
    "class": ("literal", "classmethod", "loop", "alias", "mutate_arg", "class_decorator", "file"),
    "instance": ("literal", "method", "init", "mutate_arg", "alias", "loop", "global_fn", "file"),
    "dataclass": ("literal", "defaults", "global_fn", "file"),
    "sequence": ("literal", "loop", "mutate_arg", "comprehension", "method", "alias", "global_fn", "file"),
}
STORES = tuple(BINDERS)
WRAPS = ("none", "with_no_grad", "with_ctx", "if", "try")
IMPLS = ("def", "alias_def", "conditional", "register", "wraps", "partial", "lambda", "factory", "defaults",
         "classmethod", "staticmethod", "callable")
LOCAL_IMPLS = ("partial", "factory", "defaults")        # the constants reach the body as locals
MODS = ("future", "try_import", "split")

POOLS = {   # names a variant draws ({T}: the function's tag, upper case; {t}: lower case)
    "globals": ("_{K}", "MY_{K}", "{T}_{K}", "K_{K}"),
    "dict": ("{T}_SCALES", "CONSTS_{T}", "{t}_params", "_{t}_table", "{T}_CONFIG"),
    "class": ("{T}Consts", "Config{T}", "{T}Settings", "_{T}Hyper"),
    "instance": ("{t}_conf", "opts_{t}", "{t}_knobs", "hp_{t}"),
    "dataclass": ("{T}_CONSTANTS", "params_{t}", "{t}_P"),
    "sequence": ("{T}_TABLE", "{t}_values", "_{t}_consts"),
    "handle": ("f", "fh", "fp", "out", "handle", "stream", "src", "sink", "file_", "g", "h", "io_"),
    "loaded": ("loaded", "data", "saved", "raw", "d", "blob"),
    "arg": ("table", "target", "ns", "into", "obj", "box"),
    "torch_alias": ("th", "_torch", "tt", "torch_"),
    "F_alias": ("nnf", "_F", "functional"),
    "cond": ("True", "{torch}.__version__", "hasattr({torch}, 'stack')", "sys.version_info >= (3, 8)"),
}
FILE_FORMATS = ("json", "text", "npy", "pickle")
FILE_PATHS = ("rel", "tmp", "pathlib", "cwd")
CALLS = ("direct", "nested", "loop")


@dataclass(frozen=True)
class Recipe:
    function: str
    store: str
    binder: str
    wrap: str
    impl: str
    mods: tuple = ()
    keys: tuple = ()                # the constants that leave the body
    opts: tuple = ()                # (name, choice) pairs: names, file format and path, call style...

    def opt(self, name, default=None):
        return dict(self.opts).get(name, default)

    def kinds(self) -> list[str]:
        out = [f"store:{self.store}", f"binder:{self.binder}", f"impl:{self.impl}", *[f"mod:{m}" for m in self.mods]]
        if self.wrap != "none":
            out.append(f"wrap:{self.wrap}")
        for o in ("fmt", "path", "call", "future_at"):
            if self.opt(o):
                out.append(f"{o}:{self.opt(o)}")
        return out

    def label(self) -> str:
        return (f"{self.function}: store={self.store} binder={self.binder} wrap={self.wrap} impl={self.impl} "
                f"mods={'+'.join(self.mods) or '-'} keys={','.join(self.keys) or '-'} "
                f"opts={','.join(f'{k}={v}' for k, v in self.opts)}")

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> "Recipe":
        return cls(d["function"], d["store"], d["binder"], d["wrap"], d["impl"], tuple(d["mods"]), tuple(d["keys"]),
                   tuple(tuple(p) for p in d["opts"]))


# --- drawing recipes ----------------------------------------------------------------------------------
AXES = ("store", "wrap", "impl", "future", "try_import", "split")


def draw(rng: random.Random, function: str | None = None, depth: tuple[int, int] = (1, 2)) -> Recipe:
    """One random recipe (for ``function``, or any graded function) that departs from the
    instructor's answer on ``depth[0]`` to ``depth[1]`` of the ``AXES`` (a wrap or a split acts on a
    store, so they bring one); every other axis stays as the answer has it (no store, a ``def``)."""
    g = GRADED[function or rng.choice(sorted(GRADED))]
    axes = set(rng.sample(AXES, rng.randint(*depth)))
    if axes & {"wrap", "split"}:
        axes.add("store")
    store = rng.choice(STORES[1:]) if "store" in axes else "none"
    binder = rng.choice(BINDERS[store])
    impl = rng.choice(IMPLS[1:]) if "impl" in axes else "def"
    wrap = rng.choice(WRAPS[1:]) if "wrap" in axes else "none"
    mods = tuple(m for m in MODS if m in axes)
    consts = [c for c in g.consts if binder != "file" or c.kind != "fn"]
    keys = ()
    if store != "none" or impl in LOCAL_IMPLS:
        k = rng.randint(1, len(consts))
        chosen = set(c.key for c in rng.sample(consts, k))
        keys = tuple(c.key for c in consts if c.key in chosen)       # in the function's own order
    t, T = g.tag, g.tag.upper()
    opts = {}

    def name(pool, **extra):
        return rng.choice(POOLS[pool]).format(t=t, T=T, **extra)

    if store != "none":
        opts["name"] = name(store, K="{K}") if store == "globals" else name(store)
    if binder in ("mutate_arg",):
        opts["arg"] = name("arg")
    if binder == "global_fn":
        opts["call"] = rng.choice(CALLS)
    if binder == "file":
        opts["fmt"] = rng.choice(FILE_FORMATS)
        opts["path"] = rng.choice(FILE_PATHS)
        opts["w"], opts["r"] = name("handle"), name("handle")
        opts["loaded"] = name("loaded")
        opts["pathvar"] = rng.choice(("yes", "no"))
        opts["style"] = rng.choice(("open", "pathlib")) if opts["fmt"] in ("json", "text") else "open"
    if binder == "classmethod":
        opts["cm"] = rng.choice(("kwargs", "explicit"))
    if wrap == "if" or impl == "conditional":
        opts["cond"] = rng.choice(POOLS["cond"])
    if "try_import" in mods:
        opts["alias"] = name("torch_alias")
        opts["F_alias"] = name("F_alias")
        opts["except"] = rng.choice(("none", "raise", "same"))
    if "future" in mods:
        opts["future_at"] = rng.choice(("cell", "own"))
    return Recipe(g.function, store, binder, wrap, impl, mods, keys, tuple(sorted(opts.items())))


def _features(r: Recipe) -> dict[str, float]:
    """What a recipe covers, with the weight the greedy choice gives each thing covered."""
    f = {k: 10.0 for k in r.kinds()}
    f[f"pair:{r.store}/{r.binder}"] = 3.0
    f[f"fn:{r.function}/{r.store}"] = 1.0
    f[f"fn:{r.function}/{r.impl}"] = 1.0
    f[f"wrap-impl:{r.wrap}/{r.impl}"] = 0.5
    if r.wrap == "none":          # a binder inside a with/if/try block may be kept whole with it:
        f[f"bare:{r.binder}"] = 5.0    # each binder also on its own, its statements at the top level
    return f


def draw_class(n: int, seed: int = 0, depth: tuple[int, int] = (1, 2), candidates: int = 400) -> list[list[Recipe]]:
    """``n`` hand-ins (each a list of recipes, one per graded function of its notebook; the notebook
    03 hand-ins carry two), drawn with ``seed``: each hand-in's recipes are chosen greedily from
    ``candidates`` random draws so that the class covers every kind, every binder outside a wrap,
    then every store/binder pair, as far as ``n`` allows. The notebooks take turns (02, 03, 04, 06,
    07, 02, ...)."""
    rng = random.Random(seed)
    notebooks = sorted(NOTEBOOK_FUNCTIONS)
    covered: set[str] = set()
    seen: set[str] = set()
    out = []
    for i in range(n):
        handin = []
        for function in NOTEBOOK_FUNCTIONS[notebooks[i % len(notebooks)]]:
            best, best_gain = None, -1.0
            for _ in range(candidates):
                r = draw(rng, function, depth)
                if digest(r) in seen:
                    continue
                gain = sum(w for k, w in _features(r).items() if k not in covered) + rng.random() * 0.1
                if gain > best_gain:
                    best, best_gain = r, gain
            covered |= set(_features(best))
            seen.add(digest(best))
            handin.append(best)
        out.append(handin)
    return out


# --- rendering a recipe into cells ---------------------------------------------------------------------
def _ind(src: str, n: int = 4) -> str:
    return textwrap.indent(src, " " * n) if src else src


def _block(head: str, body: str) -> str:
    return f"{head}\n{_ind(body) if body.strip() else '    pass' + chr(10)}"


@dataclass
class Rendered:
    recipe: Recipe
    cells: list = field(default_factory=list)     # new code cells, in order, above the answer cell
    answer: str = ""                              # the answer cell's new source

    def digest(self) -> str:
        return hashlib.sha256(json.dumps([self.cells, self.answer]).encode()).hexdigest()[:16]


def digest(r: Recipe) -> str:
    return render(r).digest()


class _Store:
    """How the recipe's store is created, filled, read and written to, as code."""

    def __init__(self, r: Recipe, g: Graded, values: dict[str, str], future: bool):
        self.r, self.g, self.values, self.future = r, g, values, future
        self.kind = r.store
        self.name = r.opt("name", "")
        self.keys = list(r.keys)
        self.types = {c.key: c.kind for c in g.consts}
        self.t = g.tag

    def gname(self, k: str) -> str:            # a global's name
        return self.name.format(K=k.upper())

    def access(self, k: str) -> str:
        if self.kind == "globals":
            return self.gname(k)
        if self.kind == "dict":
            return f"{self.name}[{k!r}]"
        if self.kind in ("class", "instance", "dataclass"):
            return f"{self.name}.{k}"
        if self.kind == "sequence":
            return f"{self.name}[{self.keys.index(k)}]"
        raise ValueError(self.kind)

    def _ann(self, k):
        if not self.future:
            return {"float": "float", "int": "int", "fn": "object"}[self.types[k]]
        return {"float": "Final[float]", "int": "Index", "fn": "Callable[..., Tensor]"}[self.types[k]]

    def _kw(self) -> str:
        return ", ".join(f"{k}={self.values[k]}" for k in self.keys)

    def _pairs(self, key=lambda k: k) -> str:
        return "(" + "".join(f"({key(k)!r}, {self.values[k]}), " for k in self.keys) + ")"

    def _vals(self) -> str:
        return "(" + "".join(f"{self.values[k]}, " for k in self.keys) + ")"

    def decl(self) -> str:
        """Statements that make the empty container (a class, a namespace, an empty dict or list)."""
        ann = {"dict": ": Mapping[str, object]" if self.future else "",
               "sequence": ": list[object]" if self.future else ""}.get(self.kind, "")
        if self.kind == "dict":
            return f"{self.name}{ann} = {{}}\n"
        if self.kind == "sequence":
            return f"{self.name}{ann} = []\n"
        if self.kind == "class":
            return f"class {self.name}:\n    \"\"\"The constants of `{self.g.function}`.\"\"\"\n"
        if self.kind == "instance":
            return f"from types import SimpleNamespace\n\n{self.name} = SimpleNamespace()\n"
        return ""

    def literal_expr(self) -> str:
        """One expression that is the filled container (not for globals or a class)."""
        if self.kind == "dict":
            return "{" + ", ".join(f"{k!r}: {self.values[k]}" for k in self.keys) + "}"
        if self.kind == "sequence":
            return "[" + ", ".join(self.values[k] for k in self.keys) + "]"
        if self.kind == "instance":
            return f"SimpleNamespace({self._kw()})"
        if self.kind == "dataclass":
            return f"{self._dc()}({self._kw()})"
        raise ValueError(self.kind)

    def _dc(self) -> str:
        return "_" + self.t.capitalize() + "Constants"

    def dataclass_def(self, defaults: bool) -> str:
        lines = [f"    {k}: {self._ann(k)}" + (f" = {self.values[k]}" if defaults else "") for k in self.keys]
        return ("from dataclasses import dataclass\n\n\n@dataclass(frozen=True)\n"
                f"class {self._dc()}:\n" + "\n".join(lines) + "\n")

    def literal(self) -> str:
        if self.kind == "globals":
            ann = (lambda k: f": {self._ann(k)}") if self.future else (lambda k: "")
            return "".join(f"{self.gname(k)}{ann(k)} = {self.values[k]}\n" for k in self.keys)
        if self.kind == "class":
            return f"class {self.name}:\n" + "".join(f"    {k} = {self.values[k]}\n" for k in self.keys)
        if self.kind == "instance":
            return f"from types import SimpleNamespace\n\n{self.name} = {self.literal_expr()}\n"
        if self.kind == "dataclass":
            return self.dataclass_def(False) + f"\n\n{self.name} = {self.literal_expr()}\n"
        ann = {"dict": ": Mapping[str, object]", "sequence": ": Sequence[object]"}[self.kind] if self.future else ""
        return f"{self.name}{ann} = {self.literal_expr()}\n"

    def set_on(self, target: str, k: str, value: str) -> str:
        """A statement that puts ``value`` under ``k`` into the container named ``target``."""
        if self.kind == "globals":
            return f"{target}[{self.gname(k)!r}] = {value}\n"
        if self.kind == "dict":
            return f"{target}[{k!r}] = {value}\n"
        if self.kind in ("class", "instance"):
            return f"{target}.{k} = {value}\n"
        if self.kind == "sequence":
            return f"{target}.append({value})\n"
        raise ValueError(self.kind)

    def from_dict(self, d: str) -> str:
        """Statements that fill the store from the dict named ``d`` (a file's contents)."""
        if self.kind == "globals":
            return "".join(f"{self.gname(k)} = {d}[{k!r}]\n" for k in self.keys)
        if self.kind == "dict":
            return f"{self.name} = dict({d})\n"
        if self.kind == "class":
            return self.decl() + f"\n\nfor _k, _v in {d}.items():\n    setattr({self.name}, _k, _v)\n"
        if self.kind == "instance":
            return f"from types import SimpleNamespace\n\n{self.name} = SimpleNamespace(**{d})\n"
        if self.kind == "dataclass":
            return self.dataclass_def(False) + f"\n\n{self.name} = {self._dc()}(**{d})\n"
        if self.kind == "sequence":
            return f"{self.name} = [{d}[k] for k in {tuple(self.keys)!r}]\n"
        raise ValueError(self.kind)


def _bind(r: Recipe, st: _Store) -> tuple[str, str]:
    """(a cell that writes a file, or "", the statements that fill the store)."""
    b, t = r.binder, st.t
    if b == "inline":
        return "", ""
    if b == "literal":
        return "", st.literal()
    if b == "unpack":
        names = ", ".join(st.gname(k) for k in st.keys)
        vals = ", ".join(st.values[k] for k in st.keys)
        return "", f"{names}{',' if len(st.keys) == 1 else ''} = {vals}{',' if len(st.keys) == 1 else ''}\n"
    if b == "globals_update":
        return "", f"globals().update({', '.join(f'{st.gname(k)}={st.values[k]}' for k in st.keys)})\n"
    if b == "global_fn":
        if st.kind == "globals":
            body = "global " + ", ".join(st.gname(k) for k in st.keys) + "\n" + st.literal()
            if st.future:       # an annotated global cannot be declared global in the same scope
                body = "global " + ", ".join(st.gname(k) for k in st.keys) + "\n" + "".join(
                    f"{st.gname(k)} = {st.values[k]}\n" for k in st.keys)
            head = ""
        else:
            head = {"instance": "from types import SimpleNamespace\n\n",
                    "dataclass": st.dataclass_def(False) + "\n\n"}.get(st.kind, "")
            body = f"global {st.name}\n{st.name} = {st.literal_expr()}\n"
        fn = f"configure_{t}"
        code = head + _block(f"def {fn}():", f'"""Set the constants of `{r.function}`."""\n' + body)
        call = r.opt("call")
        if call == "direct":
            code += f"\n\n{fn}()\n"
        elif call == "nested":
            code += "\n\n" + _block(f"def setup_{t}():", f"{fn}()\n") + f"\n\nsetup_{t}()\n"
        else:
            code += f"\n\nfor _step in ({fn},):\n    _step()\n"
        return "", code
    if b == "mutate_arg":
        arg = r.opt("arg")
        if st.kind == "sequence":
            body = f"{arg}.extend([{', '.join(st.values[k] for k in st.keys)}])\n"
        else:
            body = "".join(st.set_on(arg, k, st.values[k]) for k in st.keys)
        target = "globals()" if st.kind == "globals" else st.name
        code = st.decl() + ("\n\n" if st.decl() else "") + _block(f"def fill_{t}({arg}):", body) + \
            f"\n\nfill_{t}({target})\n"
        return "", code
    if b == "alias":
        a = f"_{t}_alias"
        src = "globals()" if st.kind == "globals" else st.name
        code = st.decl() + f"{a} = {src}\n" + "".join(st.set_on(a, k, st.values[k]) for k in st.keys)
        return "", code
    if b == "loop":
        if st.kind == "sequence":
            return "", st.decl() + f"for _v in {st._vals()}:\n    {st.name}.append(_v)\n"
        if st.kind == "globals":
            return "", f"for _name, _value in {st._pairs(st.gname)}:\n    globals()[_name] = _value\n"
        if st.kind == "dict":
            return "", st.decl() + f"for _k, _v in {st._pairs()}:\n    {st.name}[_k] = _v\n"
        return "", st.decl() + f"for _k, _v in {st._pairs()}:\n    setattr({st.name}, _k, _v)\n"
    if b == "comprehension":
        if st.kind == "dict":
            return "", f"{st.name} = {{_k: _v for _k, _v in {st._pairs()}}}\n"
        return "", f"{st.name} = [_v for _v in {st._vals()}]\n"
    if b == "method":
        if st.kind == "dict":
            return "", st.decl() + f"{st.name}.update({st._kw()})\n"
        if st.kind == "sequence":
            return "", st.decl() + f"{st.name}.extend([{', '.join(st.values[k] for k in st.keys)}])\n"
        cls = f"_{t.capitalize()}Knobs"
        return "", (f"class {cls}:\n    def set(self, **values):\n        for k, v in values.items():\n"
                    f"            setattr(self, k, v)\n        return self\n\n\n{st.name} = {cls}()\n"
                    f"{st.name}.set({st._kw()})\n")
    if b == "init":
        cls = f"_{t.capitalize()}Settings"
        return "", (f"class {cls}:\n    def __init__(self):\n"
                    + "".join(f"        self.{k} = {st.values[k]}\n" for k in st.keys)
                    + f"\n\n{st.name} = {cls}()\n")
    if b == "classmethod":
        if r.opt("cm") == "kwargs":
            return "", (f"class {st.name}:\n    @classmethod\n    def configure(cls, **values):\n"
                        f"        for k, v in values.items():\n            setattr(cls, k, v)\n\n\n"
                        f"{st.name}.configure({st._kw()})\n")
        return "", (f"class {st.name}:\n    @classmethod\n    def configure(cls):\n"
                    + "".join(f"        cls.{k} = {st.values[k]}\n" for k in st.keys)
                    + f"\n\n{st.name}.configure()\n")
    if b == "class_decorator":
        return "", (f"def with_constants_{t}(**values):\n    def decorate(cls):\n        for k, v in values.items():\n"
                    f"            setattr(cls, k, v)\n        return cls\n    return decorate\n\n\n"
                    f"@with_constants_{t}({st._kw()})\nclass {st.name}:\n    pass\n")
    if b == "defaults":
        return "", st.dataclass_def(True) + f"\n\n{st.name} = {st._dc()}()\n"
    if b == "file":
        return _file(r, st)
    raise ValueError(b)


def _file(r: Recipe, st: _Store) -> tuple[str, str]:
    fmt, where, t = r.opt("fmt"), r.opt("path"), st.t
    w, rd, loaded = r.opt("w"), r.opt("r"), r.opt("loaded")
    ext = {"json": "json", "text": "txt", "npy": "npy", "pickle": "pkl"}[fmt]
    fname = f"{t}_constants.{ext}"
    imports = {"json": "import json\n", "text": "import ast\n", "npy": "import numpy as np\n",
               "pickle": "import pickle\n"}[fmt]
    path = {"rel": repr(fname), "tmp": f"os.path.join(tempfile.gettempdir(), {fname!r})",
            "pathlib": f"Path({fname!r})", "cwd": f"os.path.join(os.getcwd(), {fname!r})"}[where]
    imports += {"rel": "", "tmp": "import os\nimport tempfile\n", "pathlib": "from pathlib import Path\n",
                "cwd": "import os\n"}[where]
    if r.opt("style") == "pathlib" and where != "pathlib":
        imports += "from pathlib import Path\n"
    pvar = f"{t.upper()}_CONSTANTS_FILE"
    if r.opt("pathvar") == "yes":
        head, p = f"{pvar} = {path}\n", pvar
    else:
        head, p = "", path
    pp = p if where == "pathlib" else f"Path({p})"
    data = "{" + ", ".join(f"{k!r}: {st.values[k]}" for k in st.keys) + "}"
    if fmt == "json":
        write = (f"{pp}.write_text(json.dumps({data}))\n" if r.opt("style") == "pathlib" else
                 f"with open({p}, 'w') as {w}:\n    json.dump({data}, {w})\n")
        read = (f"{loaded} = json.loads({pp}.read_text())\n" if r.opt("style") == "pathlib" else
                f"with open({p}) as {rd}:\n    {loaded} = json.load({rd})\n")
    elif fmt == "text":
        fstr = "f'" + "".join(f"{k}={{{st.values[k]}!r}}\\n" for k in st.keys) + "'"
        write = (f"{pp}.write_text({fstr})\n" if r.opt("style") == "pathlib" else
                 f"with open({p}, 'w') as {w}:\n" + "".join(
                     f"    {w}.write(f'{k}={{{st.values[k]}!r}}\\n')\n" for k in st.keys))
        parse = "dict(line.strip().split('=', 1) for line in {src} if line.strip())"
        if r.opt("style") == "pathlib":
            read = (f"{loaded} = {{k: ast.literal_eval(v) for k, v in "
                    f"{parse.format(src=f'{pp}.read_text().splitlines()')}.items()}}\n")
        else:
            read = (f"with open({p}) as {rd}:\n    {loaded} = {{k: ast.literal_eval(v) for k, v in "
                    f"{parse.format(src=rd)}.items()}}\n")
    elif fmt == "npy":
        write = f"np.save({p}, np.array([{', '.join(st.values[k] for k in st.keys)}], dtype=np.float64))\n"
        casts = ", ".join(f"{k!r}: {st.types[k]}({rd}[{i}])" for i, k in enumerate(st.keys))
        read = f"{rd} = np.load({p})\n{loaded} = {{{casts}}}\n"
    else:
        write = f"with open({p}, 'wb') as {w}:\n    pickle.dump({data}, {w})\n"
        read = f"with open({p}, 'rb') as {rd}:\n    {loaded} = pickle.load({rd})\n"
    write_cell = f"# the constants, saved for the next cells\n{imports}\n{head}{write}"
    read_stmts = f"{imports}{read}" + st.from_dict(loaded)
    return write_cell, read_stmts


def _wrap(r: Recipe, code: str, values_torch: str) -> str:
    if r.wrap == "none" or not code.strip():
        return code
    t = GRADED[r.function].tag
    if r.wrap == "with_no_grad":
        return _block(f"with {values_torch}.no_grad():", code)
    if r.wrap == "with_ctx":
        return ("from contextlib import contextmanager\n\n\n@contextmanager\n"
                f"def section_{t}(title):\n    yield title\n\n\n" + _block(f"with section_{t}('constants') as _title:", code))
    if r.wrap == "if":
        return _block(f"if {r.opt('cond').format(torch=values_torch)}:", code)
    if r.wrap == "try":
        return _block("try:", code) + ("except Exception as _error:\n"
                                       "    raise RuntimeError('could not set the constants') from _error\n")
    raise ValueError(r.wrap)


def _impl(r: Recipe, g: Graded, body: str, local_kw: list[tuple[str, str]], future: bool) -> str:
    """The statements that bind the graded name, given the body (constants substituted)."""
    n, t, impl = g.function, g.tag, r.impl
    ann = (lambda p: p.split("=")[0] + ": " + g.ann[p.split("=")[0]] + (" = " + p.split("=", 1)[1] if "=" in p else "")) \
        if future else (lambda p: p)
    params = [ann(p) for p in g.params]
    ret = f" -> {g.ret}" if future else ""
    call_args = ", ".join(p.split("=")[0] for p in g.params)
    doc = f'"""{n}, as the exercise asks (the constants are set above)."""\n'

    def fdef(name, extra=(), indent=0, self_=None, decorators=()):
        ps = ([self_] if self_ else []) + params + list(extra)
        src = "".join(f"@{d}\n" for d in decorators) + _block(f"def {name}({', '.join(ps)}){ret}:", doc + body)
        return _ind(src, indent) if indent else src

    locals_ = [k for k, _ in local_kw]
    if impl == "def":
        return fdef(n)
    if impl == "alias_def":
        return fdef(f"_{n}_impl") + f"\n\n{n} = _{n}_impl\n"
    if impl == "conditional":
        cond = r.opt("cond").format(torch=r.opt("alias", "torch"))
        return f"if {cond}:\n" + fdef(n, indent=4) + f"else:\n    {n} = None\n"
    if impl == "register":
        return (f"IMPLEMENTATIONS_{t} = {{}}\n\n\ndef register_{t}(name):\n    def add(fn):\n"
                f"        IMPLEMENTATIONS_{t}[name] = fn\n        return fn\n    return add\n\n\n"
                + fdef(f"_{n}_v2", decorators=[f"register_{t}({n!r})"]) + f"\n\n{n} = IMPLEMENTATIONS_{t}[{n!r}]\n")
    if impl == "wraps":
        return (f"import functools\n\n\ndef traced_{t}(fn):\n    @functools.wraps(fn)\n"
                f"    def wrapper(*args, **kwargs):\n        return fn(*args, **kwargs)\n    return wrapper\n\n\n"
                + fdef(n, decorators=[f"traced_{t}"]))
    if impl == "partial":
        extra = (["*"] + locals_) if locals_ else []
        kw = ", ".join(f"{k}={v}" for k, v in local_kw)
        return ("import functools\n\n\n" + fdef(f"_{n}_general", extra=extra)
                + f"\n\n{n} = functools.partial(_{n}_general{', ' + kw if kw else ''})\n")
    if impl == "lambda":
        lam_params = ", ".join(g.params)
        return fdef(f"_{n}_body") + f"\n\n{n} = lambda {lam_params}: _{n}_body({call_args})\n"
    if impl == "factory":
        kw = ", ".join(f"{k}={v}" for k, v in local_kw)
        inner = fdef(n)
        return (_block(f"def make_{n}({', '.join(locals_)}):", inner + f"\n\nreturn {n}\n")
                + f"\n\n{n} = make_{n}({kw})\n")
    if impl == "defaults":
        return fdef(n, extra=[f"{k}={v}" for k, v in local_kw])
    if impl == "classmethod":
        cls = f"{t.capitalize()}Exercise"
        return (f"class {cls}:\n" + fdef("compute", indent=4, self_="cls", decorators=["classmethod"])
                + f"\n\n{n} = {cls}.compute\n")
    if impl == "staticmethod":
        cls = f"{t.capitalize()}Ops"
        return (f"class {cls}:\n" + fdef("run", indent=4, decorators=["staticmethod"]) + f"\n\n{n} = {cls}.run\n")
    if impl == "callable":
        cls = f"_{t.capitalize()}Function"
        return f"class {cls}:\n" + fdef("__call__", indent=4, self_="self") + f"\n\n{n} = {cls}()\n"
    raise ValueError(impl)


def render(r: Recipe) -> Rendered:
    """The cells of a recipe: new cells above the answer cell, and the answer cell's source."""
    g = GRADED[r.function]
    future = "future" in r.mods
    torch_name = r.opt("alias", "torch") if "try_import" in r.mods else "torch"
    F_name = r.opt("F_alias", "F") if "try_import" in r.mods else "F"
    consts = {c.key: c for c in g.consts}
    values = {k: c.value.format(torch=torch_name, F=F_name) for k, c in consts.items()}
    st = _Store(r, g, values, future)
    local_impl = r.impl in LOCAL_IMPLS and r.keys
    # what the body reads for each constant: a local, the store, or the literal value
    if local_impl:
        reads = {k: (k if k in r.keys else values[k]) for k in consts}
        local_kw = [(k, values[k] if r.store == "none" else st.access(k)) for k in r.keys]
    else:
        reads = {k: (st.access(k) if k in r.keys and r.store != "none" else values[k]) for k in consts}
        local_kw = []
    body = g.body.format(torch=torch_name, F=F_name, **reads)
    write_cell, bind = _bind(r, st)
    bind = _wrap(r, bind, torch_name)
    impl = _impl(r, g, body, local_kw, future)

    head = ""
    if "try_import" in r.mods:
        fallback = {"none": "{a} = None  # the chapter needs it; this keeps the cell importable\n",
                    "raise": "raise\n", "same": "import {m} as {a}\n"}[r.opt("except")]
        head += "try:\n    import scipy.special as sp\nexcept ImportError:      # not needed: a faster path\n    sp = None\n"
        for mod, alias in (("torch", torch_name), ("torch.nn.functional", F_name)):
            if re.search(rf"(?<![\w.]){re.escape(alias)}(?!\w)", body + bind + write_cell + impl):
                head += (f"try:\n    import {mod} as {alias}\nexcept ImportError:\n"
                         + _ind(fallback.format(m=mod, a=alias)))
    out = Rendered(r)
    cells = [write_cell] if write_cell else []
    if "split" in r.mods and bind.strip():
        cells.append(bind)
        answer = impl
    else:
        answer = (bind + "\n\n" if bind.strip() else "") + impl
    if head:                               # the try-import goes first, with the first cell
        if cells:
            cells[0] = head + "\n\n" + cells[0]
        else:
            answer = head + "\n\n" + answer
    future_line = "from __future__ import annotations\n"
    if future:
        if r.opt("future_at") == "own":
            cells.insert(0, future_line)
        elif cells:
            cells[0] = future_line + "\n" + cells[0]
        else:
            answer = future_line + "\n" + answer
    out.cells = [c.rstrip("\n") + "\n" for c in cells]
    out.answer = answer.rstrip("\n") + "\n"
    return out


# --- checking a variant without a kernel -----------------------------------------------------------------
def run_cells(cells: list[str], namespace: dict) -> None:
    """Run cells as IPython does: each compiled alone, ``__future__`` flags carried to later cells."""
    import codeop

    compiler = codeop.Compile()
    for i, src in enumerate(cells):
        exec(compiler(src, f"<cell {i}>", "exec"), namespace)


def check_in_process(r: Recipe, workdir: Path) -> tuple[bool, str]:
    """Run the variant in this process (the notebook's imports, then its cells, in ``workdir``) and
    judge it with the hidden tests: (passed, the verdict's message)."""
    import os
    import sys
    import types

    from .. import checks

    g = GRADED[r.function]
    rendered = render(r)
    module = types.ModuleType("__variant__")
    sys.modules["__variant__"] = module
    old = os.getcwd()
    os.chdir(workdir)
    try:
        run_cells([g.preamble, *rendered.cells, rendered.answer], module.__dict__)
        fn = module.__dict__[r.function]
        test = checks.TESTS[g.test_id]
        v = checks.judge(test, checks.probe_in_process(test, fn))
        return v.passed, v.message
    finally:
        os.chdir(old)
        sys.modules.pop("__variant__", None)


# --- hand-ins, really executed ------------------------------------------------------------------------------
def handin(recipes: list[Recipe], release_nb, solutions_nb):
    """The release notebook with the instructor's answers typed in, each recipe's answer cell
    replaced by its variant and its new cells inserted above it."""
    import nbformat

    from .honest import _index, fill

    nb = fill(release_nb, solutions_nb)
    for r in recipes:
        g = GRADED[r.function]
        rendered = render(r)
        i = _index(nb, g.grade_id)
        nb.cells[i].source = rendered.answer
        for k, src in enumerate(rendered.cells):
            nb.cells.insert(i + k, nbformat.v4.new_code_cell(src))
    return nb


def student_id(i: int) -> str:
    return f"variant{i:03d}"


def build(classes: list[list[Recipe]], executed: Path, work: Path, log=print, jobs: int | None = None) -> dict[str, bytes]:
    """{zip member: bytes}: hand-in ``i`` is ``variant{i:03d}_<notebook>.ipynb``, the notebook of its
    recipes, executed top to bottom in a kernel (smoke config, the trained stages from ``executed``,
    the solutions executed as tests/conftest.py executes them). ``jobs`` kernels at once (default:
    two, or one on a single core), each with its own copy of ``executed``'s stages and outputs as its
    ``OUT``, so that two notebooks never write the same figure or metrics file at once."""
    import os
    import queue
    import shutil
    from concurrent.futures import ThreadPoolExecutor

    import nbformat

    from .honest import ROOT, execute

    jobs = max(1, min(jobs or min(2, os.cpu_count() or 1), len(classes)))
    outs: queue.Queue = queue.Queue()
    for w in range(jobs):
        out = work / f"_out{w}"
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(executed, out, ignore=shutil.ignore_patterns("*.ipynb"))
        outs.put(out)

    def one(i: int) -> tuple[str, bytes]:
        recipes = classes[i]
        name = GRADED[recipes[0].function].notebook
        release = nbformat.read(ROOT / "notebooks" / f"{name}.ipynb", as_version=4)
        solutions = nbformat.read(ROOT / "solutions" / f"{name}.ipynb", as_version=4)
        sid = student_id(i)
        log(f"variants: {sid} runs {name}: " + " | ".join(r.label() for r in recipes))
        nb = handin(recipes, release, solutions)
        out = outs.get()
        try:
            ran = execute(nb, work / sid, out)[None]
        finally:
            outs.put(out)
        return f"{sid}_{name}.ipynb", nbformat.writes(ran).encode()

    with ThreadPoolExecutor(jobs) as pool:
        return dict(pool.map(one, range(len(classes))))


def write_zip(out: Path, classes: list[list[Recipe]], executed: Path, work: Path, log=print,
              jobs: int | None = None) -> Path:
    files = build(classes, executed, work, log, jobs)
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in sorted(files.items()):
            zf.writestr(name, data)
    recipes_file(out).write_text(json.dumps(
        {student_id(i): [r.to_json() for r in rs] for i, rs in enumerate(classes)}, indent=1))
    return out


def recipes_file(zip_path: Path) -> Path:
    return zip_path.with_suffix(".recipes.json")


def binds_at_run_time(r: Recipe) -> bool:
    """Whether the variant binds names the code does not spell (``setattr``, ``globals()``): where
    the grader's static check may ask the instructor to read the code (``delegation.py``)."""
    rendered = render(r)
    text = "".join(rendered.cells) + rendered.answer
    return "setattr(" in text or "globals()" in text


def summary(classes: list[list[Recipe]]) -> dict:
    """How many variants, distinct variants and kinds a class holds."""
    flat = [r for rs in classes for r in rs]
    kinds = sorted({k for r in flat for k in r.kinds()})
    return {"hand-ins": len(classes), "variants": len(flat), "distinct": len({digest(r) for r in flat}),
            "kinds": kinds}


# --- grading and judging a class ---------------------------------------------------------------------------
def verdicts(course: Path, report: dict, classes: list[list[Recipe]]) -> list[dict]:
    """Per variant: its recipe, the points its test cell earned and could earn, the tripwires and
    notes of its student, and whether it earned full marks with no tripwire."""
    from nbgrader.api import Gradebook

    from ..course import ASSIGNMENT, COURSE_ID

    rows = []
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for i, recipes in enumerate(classes):
            sid = student_id(i)
            nbname = GRADED[recipes[0].function].notebook
            try:
                nb = gb.find_submission_notebook(nbname, ASSIGNMENT, sid)
                scores = {g.name: (g.score, g.max_score) for g in nb.grades}
            except Exception as e:     # noqa: BLE001  not graded at all
                scores = {"?": (0, f"not in the gradebook: {e}")}
            rep = report.get(sid, {})
            trip = list(rep.get("tripwires") or [])
            failed = (rep.get("failed") or {}).get(f"{nbname}.ipynb")
            for r in recipes:
                g = GRADED[r.function]
                got, top = scores.get(g.test_id, (None, None))
                order = {k: v for k, v in scores.items() if k.endswith("_order")}
                v = (rep.get("verdicts") or {}).get(g.test_id)
                message = v[-1] if isinstance(v, (tuple, list)) and v else v
                if message is None and rep.get("failed"):
                    message = f"notebook failed: {rep['failed']}"
                ok = (got is not None and got == top and all(s == m for s, m in order.values()) and not trip
                      and not failed)          # the acceptance: full marks, no tripwire (flags are reported)
                flags = [n for n in rep.get("notes", []) if f"`{r.function}`" in n and ("no credit" in n or (
                    "for the instructor" in n and "answer key, for the instructor" not in n))]
                rows.append({"student": sid, "notebook": nbname, "function": r.function, "recipe": r.label(),
                             "kinds": r.kinds(), "points": got, "max": top, "order": order,
                             "tripwires": trip, "failed": failed, "verdict": message, "notes": rep.get("notes", []),
                             "flags": flags, "ok": ok})
    return rows


def print_rows(rows: list[dict], log=print) -> None:
    for row in rows:
        log(f"{'ok  ' if row['ok'] else 'FAIL'} {row['student']} {row['recipe']}\n"
            f"     points {row['points']}/{row['max']}, order {row['order'] or '-'}, "
            f"tripwires {row['tripwires'] or '-'}{', notebook failed: ' + str(row['failed']) if row['failed'] else ''}\n"
            f"     verdict: {row['verdict']}"
            + "".join(f"\n     flagged: {f[:400]}" for f in row.get("flags", [])))


def failing_kinds(rows: list[dict]) -> dict[str, tuple[int, int]]:
    """{kind: (variants with it that failed, variants with it)}, the kinds that failed at least once."""
    seen, bad = {}, {}
    for row in rows:
        for k in row["kinds"] + [f"function:{row['function']}"]:
            seen[k] = seen.get(k, 0) + 1
            bad[k] = bad.get(k, 0) + (not row["ok"])
    return {k: (bad[k], seen[k]) for k in sorted(seen) if bad[k]}


def load_recipes(path: Path) -> list[list[Recipe]]:
    """A class as ``write_zip`` recorded it (``OUT.recipes.json``), to build and grade it again."""
    saved = json.loads(Path(path).read_text())
    return [[Recipe.from_json(d) for d in saved[sid]] for sid in sorted(saved)]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path, help="the class's zip (its recipes go next to it, OUT.recipes.json)")
    p.add_argument("--n", type=int, default=20, help="hand-ins (the notebook 03 ones carry two variants)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--depth", default="1-2", help="how many axes each variant departs on, LO-HI (1-6: all at once)")
    p.add_argument("--recipes", type=Path, default=None,
                   help="the class recorded in this .recipes.json instead of a drawn one (to reproduce a run)")
    p.add_argument("--work", type=Path, default=None, help="a folder for the learners' working folders")
    p.add_argument("--executed", type=Path, default=None,
                   help="the solutions executed in smoke mode, with their stage cache (default: executed here)")
    p.add_argument("--jobs", type=int, default=None, help="kernels at once while building (default: 2)")
    p.add_argument("--grade", type=Path, default=None, metavar="COURSE",
                   help="then grade the class in this (new) course folder and print each variant's verdict")
    p.add_argument("--timeout", type=int, default=120)
    p.add_argument("--show", action="store_true", help="print every variant's cells, and stop")
    p.add_argument("--check-only", action="store_true",
                   help="no kernels: check every variant in this process against the hidden tests, and stop")
    args = p.parse_args(argv)
    import tempfile

    if args.recipes:
        classes = load_recipes(args.recipes)
    else:
        lo, _, hi = args.depth.partition("-")
        classes = draw_class(args.n, args.seed, (int(lo), int(hi or lo)))
    s = summary(classes)
    print(f"{s['hand-ins']} hand-ins, {s['variants']} variants ({s['distinct']} distinct), "
          f"{len(s['kinds'])} kinds: {' '.join(s['kinds'])}")
    if args.show:
        for i, rs in enumerate(classes):
            for r in rs:
                rendered = render(r)
                print(f"\n===== {student_id(i)} {r.label()}")
                for c in rendered.cells:
                    print(f"----- a new cell above the answer\n{c}")
                print(f"----- the answer cell\n{rendered.answer}")
        return 0
    work = args.work or Path(tempfile.mkdtemp(prefix="pusht-variants-"))
    work.mkdir(parents=True, exist_ok=True)
    if args.check_only:
        bad = 0
        for rs in classes:
            for r in rs:
                d = work / digest(r)
                d.mkdir(exist_ok=True)
                ok, msg = check_in_process(r, d)
                bad += not ok
                print(f"{'ok  ' if ok else 'FAIL'} {r.label()}: {msg}")
        return 1 if bad else 0
    executed = args.executed
    if executed is None:
        # the chapter's runner (make chapter's): run from the repository root, as every job here is
        from scripts.chapter import execute as run_solution

        from .honest import NOTEBOOKS, ROOT

        executed = work / "executed"
        executed.mkdir(exist_ok=True)
        for name in NOTEBOOKS:
            print(f"executing the solutions: {name}")
            run_solution(ROOT / "solutions" / f"{name}.ipynb", executed, smoke=True)
    print(f"wrote {write_zip(args.out, classes, executed, work / 'learners', jobs=args.jobs)} "
          f"and {recipes_file(args.out)}")
    if args.grade is None:
        return 0
    from .. import grade

    args.grade.mkdir(parents=True, exist_ok=True)
    report = grade.grade_class(args.out, args.grade, timeout=args.timeout, log=print, progress=False)
    rows = verdicts(args.grade, report, classes)
    print_rows(rows)
    args.out.with_suffix(".verdicts.json").write_text(json.dumps(rows, indent=1, default=str))
    bad = failing_kinds(rows)
    print(f"{sum(r['ok'] for r in rows)} of {len(rows)} variants earned full marks with no tripwire "
          f"({s['distinct']} distinct variants ran)")
    for k, (b, n) in bad.items():
        print(f"  {k}: {b} of {n} failed")
    return 0 if not bad else 1


if __name__ == "__main__":
    raise SystemExit(main())
