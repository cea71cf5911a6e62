"""The planner's measurements as one Markdown page, generated from the CSVs ``bench_plan`` wrote.

    python -m benchmarks.plan_table                       # prints it
    python -m benchmarks.plan_table --out benchmarks/plan_summary.md

Read, never typed: ``plan_notebook.csv`` (notebook 07's default planner with the recipe's model on
seeds 0-5: the acceptance table), ``plan_models.csv`` (the model ladder at that planner, the recipe
itself taken from ``plan_notebook.csv``), ``plan_sensitivity.csv`` (one planner setting changed at a
time on seeds 0-1; ``plan_seeds.csv``'s 256-sample rows of those seeds beside them). Every row says
its cost: the world model's seconds as it was built (from the run's JSON, where it recorded them;
data collection included, the first time a seed's data was needed), the planner's seconds for 30
starts x 100 real steps, and the host's 1-minute load when the seed started (2 cores: above 1 the
core was shared). Success is k/n with its Wilson 95% interval; "beats zero" is ``plan_beats_zero``:
the planner's reward per step minus zero actions', paired over the starts, beyond k standard errors
and at least the minimum effect. The gate (``pusht.gate``) is read at the evaluation's 100 steps:
passed or not, with the dream's expert-minus-zero signal ± its standard error.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import statistics
from pathlib import Path

from benchmarks.bench_plan import model_tag
from pusht.config import Config
from pusht.plan import NOTEBOOK_PLAN, RECIPE, PlanSettings
from pusht.stats import wilson

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
# The planner the ladder and the sensitivity were measured from: notebook 07's first default (samples
# 64, elites 8, knots 4; the rest PlanSettings' defaults). Rows that say no objective planned with the reward.
DEFAULT_SETTINGS = dict(horizon="16", knots="4", samples="64", iters="4", elites="8", init_std="0.5",
                        min_std="0.05", warm="True", window="0", starts="30", objective="reward")
FIRST = "first default (knots 4)"
# Notebook 07's default now (pusht.plan.NOTEBOOK_PLAN): section 3's best, confirmed in section 4.
NOTEBOOK_SETTINGS = {k: str(v) for k, v in dataclasses.asdict(PlanSettings(**NOTEBOOK_PLAN)).items()}
BENCH_OF: dict[int, Path] = {}    # each row read: the CSV it came from (its JSONs lie beside it)
MODEL_ORDER = ("chapter", "recipe data, state 64", "recipe data, delta 64", "recipe data, state 128", "recipe")


def fields(text: str) -> dict:
    """``"a=1 b=2"`` (a row's settings or model column) as a dict of strings."""
    return dict(part.split("=", 1) for part in text.split())


def model_label(model: str) -> str:
    """The ladder's name of a row's model column, else the fields it changes from the recipe."""
    m = fields(model)
    chapter = Config()
    if all(m[k] == str(getattr(chapter, k)) for k in m):
        return "chapter"
    recipe_data = {k: v for k, v in RECIPE.items() if k not in ("wm_predicts", "hidden_dim")}
    if all(m[k] == str(v) for k, v in recipe_data.items()):
        kind, size = m["wm_predicts"], m["hidden_dim"]
        return "recipe" if (kind, size) == (RECIPE["wm_predicts"], str(RECIPE["hidden_dim"])) \
            else f"recipe data, {kind} {size}"
    return "recipe with " + " ".join(f"{k}={v}" for k, v in m.items() if str(RECIPE.get(k, "")) != v)


def settings_label(settings: str) -> str:
    """What a row's planner changes from notebook 07's default."""
    s = fields(settings)
    diff = [f"{k} {v}" for k, v in s.items() if DEFAULT_SETTINGS.get(k) != v]
    return ", ".join(diff) if diff else FIRST


def is_notebook_default(r: dict) -> bool:
    """Whether a row planned with notebook 07's default (``NOTEBOOK_SETTINGS``; no objective: the reward)."""
    s = {"objective": "reward", **fields(r["settings"])}
    return s == NOTEBOOK_SETTINGS


def json_of(csv_path: Path, r: dict) -> Path:
    """The JSON ``bench_plan`` wrote beside the CSV for row ``r`` (its name from the settings and model)."""
    s = fields(r["settings"])
    tag = f"h{s['horizon']}k{s['knots']}n{s['samples']}i{s['iters']}e{s['elites']}" + \
        ("" if s["warm"] == "True" else "-cold") + (f"w{s['window']}" if s["window"] != "0" else "") + \
        f"_m{model_tag(r['model'])}"
    return csv_path.parent / csv_path.stem / f"seed{r['seed']}_{tag}.json"


def read(name: str, bench: Path = BENCH) -> list[dict]:
    """The rows of ``<bench>/<name>``, each with its file, labels and the world model's build cost."""
    import json

    path = Path(bench) / name
    if not path.exists():
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["file"], r["model_label"], r["settings_label"] = name, model_label(r["model"]), settings_label(r["settings"])
        BENCH_OF[id(r)] = path
        js = json_of(path, r)
        built = json.loads(js.read_text()).get("world_model") if js.exists() else None
        # the JSON is rewritten by a rerun of the same settings, model and seed: trust it only if it is this row's
        mine = built is not None and json.loads(js.read_text())["commit"] == r["commit"]
        r["wm_built_s"], r["wm_data_s"] = (built["built_s"], built["data_s"]) if mine else (None, None)
    return rows


def latest(rows: list[dict]) -> list[dict]:
    """The last row of each (settings, model, seed): a rerun replaces the earlier reading in aggregates."""
    out = {}
    for r in rows:
        out[(r["settings"], r["model"], r["seed"])] = r
    return list(out.values())


def yes(v: str) -> bool:
    return v == "True"


def pct(x: float) -> str:
    return f"{100 * x:.0f}%"


def success(r: dict) -> str:
    return f"{r['successes']}/{r['starts']} ({pct(float(r['success_low']))}-{pct(float(r['success_high']))})"


def pm(r: dict, col: str) -> str:
    return f"{float(r[col]):+.3f} ± {float(r[col + '_se']):.3f}"


def gate(r: dict, span: str = "eval_horizon") -> str:
    word = "pass" if yes(r[f"gate_{span}_passed"]) else "FAIL"
    return f"{word} {pm(r, f'gate_{span}_dream')}"


def wm_cost(r: dict) -> str:
    """The world model's seconds as built, of which data (a trailing * : only this run's cache load
    was recorded)."""
    if r["wm_built_s"] is None:
        return f"{float(r['world_model_s']):.0f}*"
    return f"{r['wm_built_s']:.0f} ({r['wm_data_s']:.0f})"


SEED_HEAD = ("| seed | success (95% CI) | plan reward/step | zero | expert | plan - zero ± se | beats zero? "
             "| gate (100 steps): dream ± se | gate (plan horizon) | world model s (data) | plan s | load |")


def seed_line(r: dict) -> str:
    return (f"| {r['seed']} | {success(r)} | {float(r['plan_reward_per_step']):+.3f} | "
            f"{float(r['zero_reward_per_step']):+.3f} | {float(r['expert_reward_per_step']):+.3f} | "
            f"{pm(r, 'plan_minus_zero')} | {'yes' if yes(r['plan_beats_zero']) else 'NO'} | {gate(r)} | "
            f"{gate(r, 'plan_horizon')} | {wm_cost(r)} | {float(r['plan_s']):.0f} | {r['load_1min_at_start']} |")


def head(line: str) -> list[str]:
    return [line, "|" + "---|" * (line.count("|") - 1)]


def pooled(rows: list[dict]) -> dict:
    """Over a setting's seeds: successes pooled with their interval, the median rate, seeds beating zero,
    gates passed, the gate agreeing with the outcome, median costs."""
    k, n = sum(int(r["successes"]) for r in rows), sum(int(r["starts"]) for r in rows)
    lo, hi = wilson(k, n)
    built = [r["wm_built_s"] for r in rows if r["wm_built_s"] is not None]
    return {"seeds": len(rows), "k": k, "n": n, "lo": lo, "hi": hi,
            "median": statistics.median(int(r["successes"]) / int(r["starts"]) for r in rows),
            "beats": sum(yes(r["plan_beats_zero"]) for r in rows),
            "gates": sum(yes(r["gate_eval_horizon_passed"]) for r in rows),
            "agree": sum(yes(r["gate_eval_horizon_passed"]) == yes(r["plan_beats_zero"]) for r in rows),
            "wm_s": statistics.median(built) if built else None,
            "plan_s": statistics.median(float(r["plan_s"]) for r in rows),
            "load": max(float(r["load_1min_at_start"]) for r in rows)}


POOL_HEAD = ("| {what} | seeds | successes pooled (95% CI) | median success | beats zero | gate passes "
             "| gate = outcome | world model s (median) | plan s (median) | max load |")


def pool_line(name: str, p: dict) -> str:
    wm = "-" if p["wm_s"] is None else f"{p['wm_s']:.0f}"
    return (f"| {name} | {p['seeds']} | {p['k']}/{p['n']} ({pct(p['lo'])}-{pct(p['hi'])}) | {pct(p['median'])} | "
            f"{p['beats']}/{p['seeds']} | {p['gates']}/{p['seeds']} | {p['agree']}/{p['seeds']} | {wm} | "
            f"{p['plan_s']:.0f} | {p['load']:.2f} |")


def by_seed(rows):
    return sorted(rows, key=lambda r: int(r["seed"]))


def notebook_section(rows: list[dict]) -> list[str]:
    out = ["## 1. Notebook 07's first default: samples 64, elites 8, horizon 16, knots 4, iters 4; the recipe's model",
           "", "`python -m benchmarks.bench_plan --samples 64 --elites 8 --seeds 0 1 2 3 4 5 "
           "--csv benchmarks/plan_notebook.csv`", ""]
    rows = by_seed(latest([r for r in rows if r["settings_label"] == FIRST and r["model_label"] == "recipe"]))
    if not rows:
        return out + ["(no rows yet)", ""]
    out += head(SEED_HEAD) + [seed_line(r) for r in rows] + [""]
    p = pooled(rows)
    out += head(POOL_HEAD.format(what="setting")) + [pool_line(FIRST, p), ""]
    chapter = sum(yes(r["gate_chapter_eval_horizon_passed"]) for r in rows)
    out += [f"- Median success over the seeds: **{pct(p['median'])}** (target: at least 20%: "
            f"**{'met' if p['median'] >= 0.2 else 'NOT met'}** at this setting).",
            f"- The planner's reward per step above zero actions' beyond the noise on **{p['beats']} of "
            f"{p['seeds']}** seeds (target: every seed: **{'met' if p['beats'] == p['seeds'] else 'NOT met'}**).",
            f"- The recipe model's gate passes on {p['gates']} of {p['seeds']} seeds; the chapter's default "
            f"model's gate (read in the same runs) passes on {chapter} of {p['seeds']}.",
            f"- A seed's whole run (world model as built, both gates with the chapter's model, planning, "
            f"baselines): median {statistics.median(seed_total(r) for r in rows):.0f} s, at most "
            f"{max(seed_total(r) for r in rows):.0f} s.", ""]
    return out


def default_section(rows: list[dict]) -> list[str]:
    """Notebook 07's default now (``pusht.plan.NOTEBOOK_PLAN``), from whichever CSV measured it per seed."""
    label = ", ".join(f"{k} {v}" for k, v in NOTEBOOK_SETTINGS.items()
                      if k in ("samples", "elites", "horizon", "knots", "iters", "objective"))
    out = [f"## 0. Notebook 07's default: {label}; the recipe's model", "",
           "Its rows on seeds 0-1 come from section 3 (chosen there), on seeds 2-5 from section 4 (the "
           "seeds it was not chosen on).", ""]
    rows = by_seed(latest([r for r in rows if is_notebook_default(r) and r["model_label"] == "recipe"]))
    if not rows:
        return out + ["(no rows yet)", ""]
    out += head(SEED_HEAD) + [seed_line(r) for r in rows] + [""]
    p = pooled(rows)
    out += head(POOL_HEAD.format(what="setting")) + [pool_line("07 default", p), ""]
    out += [f"- Median success over the seeds: **{pct(p['median'])}** (target: at least 20%: "
            f"**{'met' if p['median'] >= 0.2 else 'NOT met'}**).",
            f"- The planner's reward per step above zero actions' beyond the noise on **{p['beats']} of "
            f"{p['seeds']}** seeds (target: every seed: **{'met' if p['beats'] == p['seeds'] else 'NOT met'}**).",
            f"- The recipe model's gate passes on {p['gates']} of {p['seeds']} seeds.", ""]
    return out


def seed_total(r: dict) -> float:
    """A row's wall seconds, the world model at its build cost where known (not the cache's load)."""
    t = sum(float(r[c]) for c in ("gate_s", "chapter_gate_s", "plan_s", "baselines_s"))
    return t + (r["wm_built_s"] if r["wm_built_s"] is not None else float(r["world_model_s"]))


def models_section(ladder: list[dict], notebook: list[dict]) -> list[str]:
    out = ["## 2. The model ladder at 07's default planner (seeds 0-5)", "",
           "(a) the chapter's default model; (b) the recipe's data with the chapter's model (state, 64) trained "
           "the recipe's 60 epochs; (c) (b) predicting deltas; (d) (b) at hidden_dim 128; (e) the recipe "
           "(delta, 128: section 1's rows). Written by `python -m benchmarks.bench_plan --samples 64 --elites 8 "
           "--seeds 0 1 2 3 4 5 --csv benchmarks/plan_models.csv` with the model flags of each "
           "(logged in the commit messages).", ""]
    rows = [r for r in latest(ladder + notebook) if r["settings_label"] == FIRST]
    groups = {m: by_seed([r for r in rows if r["model_label"] == m]) for m in MODEL_ORDER}
    groups.update({m: by_seed([r for r in rows if r["model_label"] == m]) for m in
                   sorted({r["model_label"] for r in rows} - set(MODEL_ORDER))})
    groups = {m: g for m, g in groups.items() if g}
    if not groups:
        return out + ["(no rows yet)", ""]
    out += head(POOL_HEAD.format(what="model")) + [pool_line(m, pooled(g)) for m, g in groups.items()] + [""]
    out += ["### Each model and seed: the gate beside the outcome", ""]
    out += head("| model | " + SEED_HEAD[2:]) + [f"| {m} " + seed_line(r) for m, g in groups.items() for r in g]
    out += [""]
    grid = {(kind, size): groups.get(f"recipe data, {kind} {size}" if (kind, size) != ("delta", "128") else "recipe")
            for kind in ("state", "delta") for size in ("64", "128")}
    if all(grid.values()):
        out += ["### Delta's and size's shares on the recipe's data (successes pooled over seeds 0-5; "
                "seeds beating zero)", "", "| | hidden 64 | hidden 128 |", "|---|---|---|"]
        for kind in ("state", "delta"):
            cells = []
            for size in ("64", "128"):
                p = pooled(grid[kind, size])
                cells.append(f"{p['k']}/{p['n']} ({pct(p['lo'])}-{pct(p['hi'])}); {p['beats']}/{p['seeds']}")
            out.append(f"| {kind} | " + " | ".join(cells) + " |")
        out.append("")
    every = [r for g in groups.values() for r in g]
    for span, words in (("eval_horizon", "100 steps"), ("plan_horizon", "the plan's horizon")):
        gated = [yes(r[f"gate_{span}_passed"]) for r in every]
        agree = sum(g == yes(r["plan_beats_zero"]) for g, r in zip(gated, every))
        solved = sum(g == (int(r["successes"]) > 0) for g, r in zip(gated, every))
        wrong = [f"{r['model_label']} seed {r['seed']} ({'passes' if g else 'fails'}, "
                 f"{'beats' if yes(r['plan_beats_zero']) else 'does not beat'} zero)"
                 for g, r in zip(gated, every) if g != yes(r["plan_beats_zero"])]
        out.append(f"- The gate at {words} agrees with the outcome \"the planner beats zero actions beyond the "
                   f"noise\" on **{agree} of {len(every)}** (model, seed) pairs, and with \"at least one start "
                   f"solved\" on {solved} of {len(every)}" + (f"; it disagrees on: {'; '.join(wrong)}." if wrong else "."))
    out.append("")
    return out


def sensitivity_section(sens: list[dict], seeds: list[dict], notebook: list[dict]) -> list[str]:
    out = ["## 3. The planner's sensitivity: one setting changed at a time from 07's default (the recipe's "
           "model, seeds 0-1)", "",
           "`python -m benchmarks.bench_plan --samples 64 --elites 8 --seeds 0 1 --csv "
           "benchmarks/plan_sensitivity.csv` plus the one flag; the 256-sample rows are `plan_seeds.csv`'s, 07's "
           "default's are section 1's (an earlier reading of the same setting, model and seed, replaced here, "
           "stays in its file).", ""]
    rows = [r for r in latest(sens + seeds + notebook) if r["model_label"] == "recipe" and r["seed"] in ("0", "1")]
    if not rows:
        return out + ["(no rows yet)", ""]
    order = {}
    for r in rows:
        order.setdefault(r["settings_label"], []).append(r)
    out += head(POOL_HEAD.format(what="setting")) + [pool_line(f"{s} ({g[0]['file']})", pooled(by_seed(g)))
                                                     for s, g in order.items()] + [""]
    out += ["### Each setting and seed", ""]
    out += head("| setting | " + SEED_HEAD[2:]) + [f"| {s} " + seed_line(r) for s, g in order.items()
                                                  for r in by_seed(g)] + [""]
    return out


def confirm_section(confirm: list[dict], sens: list[dict], notebook: list[dict]) -> list[str]:
    out = ["## 4. Section 3's best, on the seeds it was not chosen on", "",
           "`python -m benchmarks.bench_plan --samples 64 --elites 8 --seeds 2 3 4 5 --csv benchmarks/plan_confirm.csv` "
           "plus the setting's flag; its seeds 0-1 are section 3's rows, 07's default is section 1's.", ""]
    confirm = [r for r in latest(confirm) if r["model_label"] == "recipe"]
    if not confirm:
        return out + ["(no rows yet)", ""]
    settings = {r["settings"] for r in confirm}
    default = [r for r in latest(notebook) if r["settings_label"] == FIRST and r["model_label"] == "recipe"]
    pool, detail, pool_notes = [], [], []
    for setting in sorted(settings):
        mine = [r for r in latest(confirm + sens) if r["settings"] == setting and r["model_label"] == "recipe"]
        for name, rows in ((settings_label(setting), mine), (FIRST, default)):
            for which, keep in (("seeds 2-5", lambda r: r["seed"] not in ("0", "1")), ("all seeds", lambda r: True)):
                chosen = by_seed([r for r in rows if keep(r)])
                if chosen:
                    pool.append(pool_line(f"{name}, {which}", pooled(chosen)))
        detail += [f"| {settings_label(setting)} " + seed_line(r) for r in by_seed(mine)]
        for which, rows in (("the seeds it was not chosen on", [r for r in mine if r["seed"] not in ("0", "1")]),
                            ("all seeds", mine)):
            pairs = paired(rows, default)
            if pairs:
                only, other, n, seeds = pairs
                pool_notes.append(f"- Paired on the same starts, {which} ({n} starts of seeds {seeds}): solved by "
                                  f"{settings_label(setting)} alone {only}, by 07's default alone {other}; "
                                  f"two-sided sign test on those {only + other}: p = {sign_test(only, other):.2g}.")
    out += head(POOL_HEAD.format(what="setting")) + pool + [""] + pool_notes + [""]
    out += head("| setting | " + SEED_HEAD[2:]) + detail + [""]
    return out


def per_start_success(r: dict) -> dict | None:
    """{start seed: solved?} of a row's planner, from its JSON (None if the JSON is another run's)."""
    import json

    js = json_of(BENCH_OF[id(r)], r)
    if not js.exists():
        return None
    res = json.loads(js.read_text())
    if res["commit"] != r["commit"]:
        return None
    return {p["start_seed"]: p["plan_success"] for p in res["per_start"]}


def paired(rows: list[dict], default: list[dict]):
    """Starts solved by one setting and not the other, over the seeds both were run on, from the JSONs."""
    base = {r["seed"]: r for r in default}
    only = other = n = 0
    seeds = []
    for r in by_seed(rows):
        if r["seed"] not in base:
            continue
        a, b = per_start_success(r), per_start_success(base[r["seed"]])
        if a is None or b is None or set(a) != set(b):
            continue
        seeds.append(r["seed"])
        n += len(a)
        only += sum(a[k] and not b[k] for k in a)
        other += sum(b[k] and not a[k] for k in a)
    return (only, other, n, ", ".join(seeds)) if seeds else None


def sign_test(b: int, c: int) -> float:
    """Two-sided exact binomial test of b successes in b + c at one half (McNemar's exact test)."""
    from math import comb

    n = b + c
    if n == 0:
        return 1.0
    tail = sum(comb(n, i) for i in range(min(b, c) + 1)) / 2 ** n
    return min(1.0, 2 * tail)


def summary(bench: Path = BENCH) -> str:
    """The page, from the CSVs in ``bench``."""
    notebook = read("plan_notebook.csv", bench)
    lines = ["# Planning in the learned model: notebook 07's default, the model ladder, the planner's sensitivity",
             "", "Generated by `python -m benchmarks.plan_table --out benchmarks/plan_summary.md` from the CSVs "
             "in `benchmarks/` (do not edit by hand). " + " ".join(__doc__.split("\n\n")[2].split()), "",
             "Columns: success k/30 with its Wilson 95% interval; reward per step (higher is better; the "
             "scripted expert's beside); plan - zero: paired over the starts, ± its standard error; gate: the "
             "dream's expert-minus-zero signal ± se and its verdict; world model s: as built, with its data's "
             "seconds (collected, or loaded from the data cache) in brackets (* = not recorded as built: the "
             "run's cache load); plan s: planning 30 starts; load: 1-minute load average at the "
             "seed's start on the 2-core host.", ""]
    sens = read("plan_sensitivity.csv", bench)
    lines += default_section(sens + read("plan_confirm.csv", bench) + notebook)
    lines += notebook_section(notebook)
    lines += models_section(read("plan_models.csv", bench), notebook)
    lines += sensitivity_section(sens, read("plan_seeds.csv", bench), notebook)
    lines += confirm_section(read("plan_confirm.csv", bench), sens, notebook)
    return "\n".join(lines).rstrip() + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=None, help="write the page there (default: print it)")
    args = p.parse_args(argv)
    text = summary()
    if args.out:
        args.out.write_text(text)
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
