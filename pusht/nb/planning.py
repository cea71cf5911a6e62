"""Notebook 07, "When does the dream pay?": planning in the learned model, and the gate that predicts it.

The notebook's one import surface: its figures (``fig_*``), its self-checks, its experiment and
everything of its rooms it uses: ``planning_measure`` (the ladder of world models, the gate per model,
the data's zero actions, the real outcomes), ``planning_words`` (the sentences, each guarded by a
claim of ``planning_claims``, and Exercise 4).
"""

from __future__ import annotations

import time

import numpy as np

from pusht.palette import DREAM, REAL

from . import figure
from .planning_measure import (LABELS, Ex4Result, Rung, actor_readings, configs, cut, outcome, paired,  # noqa: F401
                               plan_in, read_rung, settings, shares, starts, zero_census)
from .planning_words import (EX4_NOTE, EX4_OPTIONS, actor_sentence, census_sentence, decided,  # noqa: F401
                             drift_sentence, ex4_reconciliation, ex4_verdict, gate_predicted_sentence,
                             gate_sentence, gate_table, outcome_sentence, outcome_table, passes, shares_sentence,
                             shares_table)
from .prose import self_checks

SELF_CHECKS = self_checks("07_planning")


def train_ladder(cfg, seeds, s, cache, progress=None, names=None) -> dict:
    """Train (or load from ``cache``) each world model of the ladder and read its gate on ``seeds``:
    ``{rung: Rung}`` in the ladder's order. ``names``: only these rungs."""
    from pusht.wm_stage import world_model_stage

    out = {}
    for name, c in configs(cfg).items():
        if names is not None and name not in names:
            continue
        t0 = time.perf_counter()
        stage = world_model_stage(c, cache, cache, None, progress)
        out[name] = read_rung(name, stage, seeds, s, cfg.eval_horizon, cfg.device)
        out[name].seconds = time.perf_counter() - t0
    return out


def experiment(cfg, rungs: dict, s, seeds, cache, progress=None, update=None) -> Ex4Result:
    """Exercise 4: the actor trained in the recipe's model (``dreamer.run``, cached), the planner in the
    same model and in the chapter's, all on ``seeds`` in the real sim, with zero actions and the
    scripted expert from the same starts. ``update``: the CEM refit the planner uses (the learner's)."""
    from pusht.dreamer import run

    t0 = time.perf_counter()
    actor = run(configs(cfg)["recipe"], cache_dir=cache, model_cache=cache, progress=progress, log=None)
    n = len(seeds)
    if actor.cfg.eval_episodes < n:
        raise ValueError(f"the actor is evaluated on {actor.cfg.eval_episodes} starts; the planner needs {n}")
    ro = {"actor": cut(actor.rollouts["real"], n), "zero": cut(actor.rollouts["real_zero"], n),
          "expert": cut(actor.rollouts["real_expert"], n)}
    seconds = {"actor_s": time.perf_counter() - t0}
    planned = []
    t0 = time.perf_counter()
    ro["planner"] = plan_in(rungs["recipe"].stage, seeds, cfg.eval_horizon, s, cfg.device, progress, update, planned)
    seconds["planner_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ro["planner_chapter"] = plan_in(rungs["chapter"].stage, seeds, cfg.eval_horizon, s, cfg.device, progress, update)
    seconds["planner_chapter_s"] = time.perf_counter() - t0
    outcomes = {name: outcome(r, ro["zero"]) for name, r in ro.items()}
    return Ex4Result(outcomes=outcomes, rollouts=ro, actor_dream=cut(actor.rollouts["dream"], n),
                     dream_zero=cut(actor.rollouts["dream_zero"], n), planned=planned,
                     actor_metrics=actor.metrics,
                     gates={"planner": rungs["recipe"].gate, "planner_chapter": rungs["chapter"].gate},
                     seconds=seconds)


def as_json(rungs: dict, census: dict, res: Ex4Result | None, cfg, s) -> dict:
    """The notebook's results as plain JSON (``metrics/planning/plan_seed<N>.json``)."""
    import dataclasses

    from pusht.gate import as_row

    out = {"seed": cfg.seed, "settings": dataclasses.asdict(s), "census": census,
           "gates": {name: as_row(r.gate) for name, r in rungs.items()},
           "world_model_s": {name: round(getattr(r, "seconds", float("nan")), 2) for name, r in rungs.items()}}
    if res is not None:
        out["outcomes"] = res.outcomes
        out["letter"] = ex4_verdict(res)
    return out


def summary_table(out) -> str:
    """Every seed whose results this notebook wrote under ``out`` (``metrics/planning/plan_seed<N>.json``):
    each world model's gate beside the planner's real outcome in it, and the actor's; each row names the
    planner it ran (a folder may hold runs of other settings)."""
    import json
    from pathlib import Path

    files = sorted(Path(out, "metrics", "planning").glob("plan_seed*.json"), key=lambda p: int(p.stem[9:]))
    rows = []
    for path in files:
        r = json.loads(path.read_text())
        if "outcomes" not in r:
            continue
        o, g = r["outcomes"], r["gates"]
        cell = {name: f"{x['successes']}/{x['n']} ({x['minus_zero']:+.3f} ± {x['minus_zero_se']:.3f})"
                for name, x in o.items()}
        p = r["settings"]
        plan = f"{p['samples']} samples, {p['knots']} knots, {p.get('objective', 'reward')}"
        rows.append(f"| {r['seed']} | {plan} | {'passes' if g['chapter']['passed'] else 'fails'} | {cell['planner_chapter']} | "
                    f"{'passes' if g['recipe']['passed'] else 'fails'} | {cell['planner']} | {cell['actor']} | "
                    f"({r['letter']}) |")
    if not rows:
        return "*No seed's results found yet.*"
    return ("| seed | planner | gate, chapter's model | planner in it: solved (minus zero actions, reward/step) | "
            "gate, recipe's model | planner in it | actor in it | Exercise 4 |\n"
            "| --- | --- | --- | --- | --- | --- | --- | --- |\n"
            + "\n".join(rows) + f"\n\n{len(rows)} seed(s) found in `{Path(out)}`.")


# --- figures ---------------------------------------------------------------------------------------
@figure
def fig_drift(rungs: dict, dt: float = 0.1):
    """How far each model's dream moves a block nobody touches (zero actions), mean over the starts,
    over the whole evaluation; reality's untouched block does not move."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.2))
    shades = plt.cm.Purples(np.linspace(0.45, 1.0, len(rungs)))          # every dream in the dream's hue
    for (name, r), style, color in zip(rungs.items(), ("-", "--", "-.", ":", "-"), shades):
        t = np.arange(len(r.drift_curve)) * dt
        ax.plot(t, 100 * r.drift_curve, style, lw=2.4 if name in ("chapter", "recipe") else 1.6,
                color=DREAM if name == "chapter" else color, label=f"dream: {r.label}")
    ax.axhline(0, color=REAL, lw=2, label="reality (the block stays put)")
    horizon = next(iter(rungs.values())).gate["horizon"]
    ax.axvline(horizon * dt, color="gray", lw=1, ls=":", label=f"the planner's horizon ({horizon * dt:.1f} s)")
    ax.set_xlabel("dreamed time (s)")
    ax.set_ylabel("untouched block's displacement (cm)")
    ax.set_title("Zero actions: where the dream takes a block nobody touches")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


@figure
def fig_gate(rungs: dict):
    """The gate per model: the expert's pushes minus zero actions, in the dream (purple) and in
    reality (orange), ± one standard error; the minimum effect dashed."""
    import matplotlib.pyplot as plt

    from pusht.stats import MIN_REWARD_EFFECT

    names = list(rungs)
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(9, 4.4))
    for dx, world, color in ((-0.18, "dream", DREAM), (0.18, "real", REAL)):
        v = [rungs[n].gate[f"expert_signal_{world}"] for n in names]
        e = [rungs[n].gate[f"expert_signal_{world}_se"] for n in names]
        ax.bar(x + dx, v, 0.36, yerr=e, capsize=4, color=color, label="in the dream" if world == "dream" else "in reality")
    ax.axhline(0, color="gray", lw=1)
    ax.axhline(MIN_REWARD_EFFECT, color="gray", lw=1, ls="--", label=f"minimum effect ({MIN_REWARD_EFFECT:.2f})")
    ax.set_xticks(x, [LABELS[n].replace(" + ", "\n+ ").replace("(the recipe)", "\n(the recipe)") for n in names],
                  fontsize=8)
    for i, n in enumerate(names):
        ax.text(i, ax.get_ylim()[0], "passes" if rungs[n].gate["passed"] else "fails", ha="center", va="bottom",
                fontsize=9, weight="bold")
    ax.set_xlabel("world model: the chapter's, then on the richer data with neither, one or both model changes")
    ax.set_ylabel("expert minus zero actions\n(reward per step; bars ± 1 s.e.)")
    ax.set_title("The gate: does the dream rank the expert's pushes above standing still?")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig


@figure
def fig_outcomes(res: Ex4Result):
    """Each policy's real reward per step (± one standard error) on the same starts, its successes
    written above it; zero actions' level dashed."""
    import matplotlib.pyplot as plt

    from .planning_words import _ROWS

    names = list(_ROWS)
    fig, ax = plt.subplots(figsize=(8.5, 4.2))
    v = [res.outcomes[n]["reward"] for n in names]
    e = [res.outcomes[n]["reward_se"] for n in names]
    colors = [REAL if n != "zero" else "gray" for n in names]
    ax.bar(range(len(names)), v, yerr=e, capsize=4, color=colors)
    ax.axhline(res.outcomes["zero"]["reward"], color="gray", ls="--", lw=1, label="zero actions")
    for i, n in enumerate(names):
        o = res.outcomes[n]
        ax.text(i, 0.005, f"{o['successes']}/{o['n']} solved", ha="center", va="bottom", fontsize=9)
    ax.set_xticks(range(len(names)), [_ROWS[n].replace(", ", ",\n") for n in names], fontsize=8)
    ax.set_ylim(min(v) - 0.1, 0.06)
    ax.set_xlabel("policy, all from the same held-out starts")
    ax.set_ylabel("real reward per step\n(higher is better; bars ± 1 s.e.)")
    ax.set_title("In reality, from the same held-out starts")
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    return fig


def pick_start(res: Ex4Result) -> int:
    """The start the picture shows: the first one the planner solved (else the first start)."""
    solved = np.flatnonzero(res.rollouts["planner"].success)
    return int(solved[0]) if len(solved) else 0


@figure
def fig_one_start(res: Ex4Result, i: int | None = None, every: int = 10):
    """One start, seen from above. Left: the actor: the block's centre in reality (orange) and in the
    actor's own open-loop dream (purple), 10 s each. Right: the planner: the block's centre in reality
    (orange), and every ``every`` real steps the plan it chose, as it dreamed it (purple), each
    starting from the true state of that step."""
    import matplotlib.pyplot as plt

    from pusht.draw import draw_state, setup_arena

    i = pick_start(res) if i is None else i
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.4))
    real_a, dream_a = res.rollouts["actor"].obs[:, i], res.actor_dream.obs[:, i]
    ax = setup_arena(axes[0], "The actor: one long dream,\nnever checked against reality")
    draw_state(ax, real_a[0], alpha=0.35)
    ax.plot(*real_a[:, 2:4].T, color=REAL, lw=2.2, label="block in reality")
    ax.plot(*dream_a[:, 2:4].T, color=DREAM, lw=2.2, ls="--", label="block in its dream")
    draw_state(ax, real_a[-1], target=False, tee_color=REAL, alpha=0.5, label="reality, at the end")
    ax.legend(fontsize=8, loc="lower left")
    real_p = res.rollouts["planner"].obs[:, i]
    ax = setup_arena(axes[1], f"The planner: a short dream from the true state\nat every step (every {every}th shown)")
    draw_state(ax, real_p[0], alpha=0.35)
    ax.plot(*real_p[:, 2:4].T, color=REAL, lw=2.2, label="block in reality")
    first = True
    for t in range(0, len(res.planned), every):
        plan = res.planned[t][i]
        if np.isnan(plan).any():
            break
        ax.plot(*plan[:, 2:4].T, color=DREAM, lw=1.6, ls="--", label="block in the chosen plan's dream" if first else None)
        ax.plot(*plan[0, 2:4], "o", color=DREAM, ms=3)
        first = False
    draw_state(ax, real_p[-1], target=False, tee_color=REAL, alpha=0.5, label="reality, at the end")
    ax.legend(fontsize=8, loc="lower left")
    solved = "solved" if res.rollouts["planner"].success[i] else "not solved"
    fig.suptitle(f"Held-out start {i + 1}: planner {solved}, actor "
                 f"{'solved' if res.rollouts['actor'].success[i] else 'not solved'}", fontsize=11)
    fig.tight_layout()
    return fig
