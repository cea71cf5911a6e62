"""Where a metric key is born: the templates of every composed key in ``metrics.json``, and the one
function, :func:`key`, that fills them, for the code that writes a metric and the code that reads it.

A key that is written whole (``"real_success_rate"``) is a literal at its one writer: grep finds it.
A key made of parts (``gap_drift_se_position_train_horizon``: a term, its standard error, a half of
the reward, a span of steps) is built here, from a named template, at both ends, so grepping the
template's name (``GAP_TERM``) finds every writer and reader, and ::

    python -m pusht.metric_keys gap_drift_se_position_train_horizon

says which template a key comes from, what it measures and in which unit. The key grammar is the one
metrics files have always had (no key is renamed by this module): an optional ``_se`` (its standard
error over the evaluation's starts), an optional ``_position``/``_yaw`` (that term of the reward
alone), an optional ``_train_horizon``/``_eval_horizon`` (the span of steps), in the order each
template shows.
"""

from __future__ import annotations

import itertools
import re
import string
import sys
from dataclasses import dataclass

from .env import OBS_NAMES

# --- the parts a template is filled with ---------------------------------------------------------
# each optional part renders as "" when absent and as "_<value>" when given
OPTIONAL = {"_se": (True,), "_part": ("position", "yaw"), "_span": ("train_horizon", "eval_horizon")}
DOMAINS = {
    "policy": ("zero", "untrained", "trained", "expert"),
    "world": ("dream", "real"),
    "term": ("drift", "motion", "training", "drift_minus_half_gap"),
    "error": ("imagination_gap", "gap_drift"),
    "data": ("", "expert", "policy"),          # the model's error on: the run's data / expert clips / policy data
    "kind": ("one_step", "open_loop"),
    "body": ("pusher", "block"),
    "dim": OBS_NAMES,
}


@dataclass(frozen=True)
class Template:
    pattern: str
    means: str
    unit: str
    written_by: str


# --- the templates ---------------------------------------------------------------------------------
RETURN = "{policy}_{world}_return_per_step{_se}{_part}{_span}"
GAP = "imagination_gap{_se}{_part}{_span}"
GAP_TERM = "gap_{term}{_se}{_part}{_span}"
ERROR_SIZE = "{error}_size{_se}{_span}"
YAW_MINUS_POSITION = "{error}_yaw_minus_position{_se}{_span}"
EXPERT_SIGNAL = "expert_signal{_part}_{world}{_se}{_span}"
EXPERT_GAP = "expert_gap{_se}{_span}"
ZERO_BLOCK_MOVED = "zero_dream_block_moved{_span}"
FINAL_YAW = "{policy}_{world}_final_yaw_err_deg"
WM_RATIO = "wm{_data}_{kind}_ratio_{dim}"
WM_ERR = "wm{_data}_{kind}_{body}_err"
WM_COPY_ERR = "wm{_data}_{kind}_{body}_copy_err"

SPLIT = "pusht.split"    # its three functions, called by pusht.evaluate.two_world_eval for each span
TEMPLATES = {
    RETURN: Template(RETURN, "what a world pays a policy, per step, mean over the starts", "reward/step",
                     "pusht.split.gap_split; the expert's, pusht.split.expert_signal"),
    GAP: Template(GAP, "the imagination gap: the trained policy's dream minus its reality", "reward/step",
                  SPLIT + ".gap_split"),
    GAP_TERM: Template(GAP_TERM, "a term of the gap's split (drift: zero actions; motion: the untrained "
                       "actor's actions; training: what training adds); drift_minus_half_gap: Exercise 1's "
                       "question as one quantity", "reward/step", SPLIT + ".gap_split"),
    ERROR_SIZE: Template(ERROR_SIZE, "the error's size: |position half| + |yaw half|", "reward/step",
                         SPLIT + ".size_split"),
    YAW_MINUS_POSITION: Template(YAW_MINUS_POSITION, "which half of the error is larger: |yaw half| - "
                                 "|position half|", "reward/step", SPLIT + ".size_split"),
    EXPERT_SIGNAL: Template(EXPERT_SIGNAL, "the scripted expert minus zero actions, in one world: does "
                            "it rank the expert's pushes above standing still", "reward/step",
                            SPLIT + ".expert_signal"),
    EXPERT_GAP: Template(EXPERT_GAP, "the expert's own gap: the dream's pay for its replayed pushes minus "
                         "reality's", "reward/step", SPLIT + ".expert_signal"),
    ZERO_BLOCK_MOVED: Template(ZERO_BLOCK_MOVED, "how far the zero-action dream moves a block nobody touches "
                               "(mean over starts of the largest displacement)", "m", SPLIT + ".expert_signal"),
    FINAL_YAW: Template(FINAL_YAW, "the block's yaw error at the end of the evaluation, mean over the starts",
                        "degrees", "pusht.evaluate.two_world_eval"),
    WM_RATIO: Template(WM_RATIO, "the world model's prediction error over copy-last's, one state dimension "
                       "(below 1: the model beats copying the last state)", "ratio",
                       "pusht.dreamer.summarize (no data part); pusht.loop.measure_round (expert, policy)"),
    WM_ERR: Template(WM_ERR, "the world model's position error for one body, RMSE over x and y", "m",
                     "pusht.loop.measure_round"),
    WM_COPY_ERR: Template(WM_COPY_ERR, "copy-last's position error for one body, RMSE over x and y", "m",
                          "pusht.loop.measure_round"),
}


def fields(template: str) -> list[str]:
    """The names of a template's parts, in order."""
    return [name for _, name, _, _ in string.Formatter().parse(template) if name]


def key(template: str, *, se: bool = False, part: str | None = None, span: str | None = None, **parts) -> str:
    """The metric key ``template`` names for these parts: ``se`` (its standard error), ``part``
    (``"position"``/``"yaw"``: that term of the reward), ``span`` (``"train_horizon"``/
    ``"eval_horizon"``), and the template's own parts (``policy=``, ``world=``, ...). A part the
    template does not have, a value outside its domain, or a missing one is an error."""
    if template not in TEMPLATES:
        raise ValueError(f"{template!r} is not a metric-key template (see pusht.metric_keys.TEMPLATES)")
    names = fields(template)
    given = {"_se": True if se else None, "_part": part, "_span": span,
             **{("_" + k if "_" + k in names else k): v for k, v in parts.items()}}
    values = {}
    for name, value in given.items():
        if name not in names:
            if value is None:
                continue
            raise ValueError(f"template {template!r} has no part {name.lstrip('_')!r}")
        domain = OPTIONAL.get(name) or DOMAINS.get(name.lstrip("_"))
        if value is not None and value not in domain and not (name.startswith("_") and value == ""):
            raise ValueError(f"{name.lstrip('_')}={value!r} is not one of {domain} (template {template!r})")
        if name == "_se":
            values[name] = "_se" if value else ""
        elif name.startswith("_"):
            values[name] = f"_{value}" if value else ""
        else:
            values[name] = value
    values.update({n: "" for n in names if n.startswith("_") and n not in values})   # an optional part left out
    missing = [n for n in names if n not in values]
    if missing:
        raise ValueError(f"template {template!r} needs {', '.join(m.lstrip('_') for m in missing)}")
    return template.format(**values)


def expand(template: str) -> dict[str, dict]:
    """Every key ``template`` can make, mapped to the parts that make it."""
    names = fields(template)
    choices = [((None,) + OPTIONAL[n]) if n in OPTIONAL else DOMAINS[n.lstrip("_")] for n in names]
    out = {}
    for combo in itertools.product(*choices):
        parts = {n.lstrip("_"): v for n, v in zip(names, combo) if v not in (None, "")}
        out[key(template, **parts)] = parts
    return out


def explain(name: str) -> tuple[Template, dict] | None:
    """The template and parts that make the key ``name``; None for a key written whole (grep for it)."""
    for pattern, template in TEMPLATES.items():
        rx = "^" + re.sub(r"\\\{[^}]+\\\}", ".*", re.escape(pattern)) + "$"
        if re.match(rx, name):
            parts = expand(pattern).get(name)
            if parts is not None:
                return template, parts
    return None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        for pattern, t in TEMPLATES.items():
            print(f"{pattern}\n    {t.means} [{t.unit}]; written by {t.written_by}")
        return 0
    for name in argv:
        found = explain(name)
        if found is None:
            print(f"{name}: written whole, not from a template: `grep -rn '\"{name}\"' pusht` finds its writer")
            continue
        t, parts = found
        const = next(k for k, v in globals().items() if v == t.pattern and k.isupper() and k != "pattern")
        where = ", ".join(f"{k}={v}" for k, v in parts.items()) or "no parts"
        print(f"{name}: template {const} = {t.pattern!r} ({where})\n    {t.means} [{t.unit}]; "
              f"written by {t.written_by}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
