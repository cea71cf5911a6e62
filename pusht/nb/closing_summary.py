"""Notebook 06's conclusion and the chapter's summary table across the notebooks' runs."""

from __future__ import annotations

import math

from ..env import SUCCESS_POS
from .closing_changes import COUNT_P, _series, metric_change, successes
from .closing_claims import (count_beyond_chance, dream_gloomier, dream_rosier, drift_crossed_zero,
                             error_size_grew, error_size_shrank, no_real_success)
from .closing_fixes import _expert_cell, _fix_line, _share_cell
from .closing_words import (ORDER_WORDS, _diff_se, error_size, expert_words, halves_order, path_words,
                            size_change, yaw_share)
from .fmt import mm, pm
from .stats import MIN_REWARD_EFFECT, count_rise_p, k_for


def _drift_words(m: dict, k: float) -> str:
    d, dse = m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]
    p, y = m["gap_drift_position_eval_horizon"], m["gap_drift_yaw_eval_horizon"]
    pse, yse = m["gap_drift_se_position_eval_horizon"], m["gap_drift_se_yaw_eval_horizon"]
    order = halves_order(p, y, _diff_se(m, "eval_horizon", "gap_drift"), int(m["eval_episodes"]))
    size, sse = error_size(m, "eval_horizon", "gap_drift")
    return (f"{pm(d, dse)} per step (position {pm(p, pse)}, yaw {pm(y, yse)}: {ORDER_WORDS[order]}, by the rule "
            f"of the gap's halves above; its size, |position| + |yaw|, {pm(size, sse)})")


def conclusion(rounds: list, state_m: dict, delta_m: dict, ens_m: dict) -> str:
    """What each fix bought in each world (whether it counts as a fix, its halves, real return and
    successes, the expert control), and, as open questions, what real success plausibly needs, each
    tied to a number and guarded by a claim."""
    first, last = rounds[0], rounds[-1]
    n, R = int(last["eval_episodes"]), last["round"]
    lines = [_fix_line(f"The real-data loop ({R} round{'s' if R != 1 else ''}, "
                       f"{last.get('policy_episodes', '?')} real policy episodes)",
                       first, last, "round 0"),
             _fix_line("Predicting changes", state_m, delta_m, "the state model"),
             _fix_line("An ensemble with a disagreement penalty", state_m, ens_m, "the single model")]
    runs = {"the loop": last, "the delta model": delta_m, "the ensemble": ens_m}
    if no_real_success(successes=[successes(m) for m in runs.values()]):
        lines.append("**No fix produced a single real success.** Closing a gap is not solving the task: the gap "
                     "can close from the dream's side alone.")
    else:
        # a success counts against the fix's own reference (round 0, the state model), never against zero
        refs = {"the loop": (first, "round 0"), "the delta model": (state_m, "the state model"),
                "the ensemble": (state_m, "the single model")}
        said = []
        for w, m in runs.items():
            ref, ref_name = refs[w]
            a, b = successes(ref), successes(m)
            if b == 0:
                continue
            if b > a:
                p = count_rise_p(a, b, n)
                said.append(f"{w} {b}/{n} against {a}/{n} for {ref_name} (Fisher's exact one-sided p = {p:.3f}, "
                            + ("beyond chance)" if count_beyond_chance(p=p, bar=COUNT_P) else "could be chance)"))
            else:
                said.append(f"{w} {b}/{n}, no more than {ref_name}'s {a}/{n}: not something the fix bought")
        lines.append("Real successes: " + "; ".join(said) + ". One seed and a few starts; rerun other seeds before "
                     "calling any of it a fix.")
    k = k_for(n)
    open_ = [f"*Data the policy never collects.* The loop corrects the model only where its policy goes: after "
             f"round {R} the real block ends {last['real_final_tee_dist']:.3f} m from the target on average "
             f"(a success needs {SUCCESS_POS:.2f} m). The expert's data reach the goal, but by the expert's "
             "actions; the states between, which a better policy would have to pass through with its own "
             "actions, are in neither data set, and nothing corrects the dream there. Exploration aimed at "
             "what the model does not know would plausibly be needed."]
    nums, ex = expert_words(last)
    open_.append(f"*A dream that can tell success from standing still.* After round {R}, {nums}: {ex}. An actor "
                 "trained in a dream can only learn the pushes that dream pays for.")
    tr, tse = last["gap_training_train_horizon"], last["gap_training_se_train_horizon"]
    kw = dict(value=tr, se=tse, k=k, min_effect=MIN_REWARD_EFFECT)
    if dream_rosier(**kw):
        open_.append(f"*Reward exploitation.* After round {R} training still makes the dream rosier than reality "
                     f"over the training horizon by {pm(tr, tse)} per step, beyond the noise and the minimum "
                     "effect: the actor keeps learning things only the model pays for, and a better actor would "
                     "find more of them.")
    elif dream_gloomier(**kw):
        open_.append(f"*Reward exploitation* is not what this run shows: after round {R} the gap's training term "
                     f"over the training horizon is {pm(tr, tse)}, training made the dream gloomier, not rosier, "
                     "than reality. A stronger actor, though, searches harder, and every model has errors to find.")
    else:
        open_.append(f"*Reward exploitation.* After round {R} the gap's training term over the training horizon "
                     f"is {pm(tr, tse)}, not beyond the noise and the minimum effect of {MIN_REWARD_EFFECT:.2f}; "
                     "but a stronger actor searches harder, and every model has errors to find.")
    dc = metric_change(first, last, "gap_drift_eval_horizon", "gap_drift_se_eval_horizon")
    d0se = first["gap_drift_se_eval_horizon"]
    causal = f"*Causal confusion.* With zero actions the round-0 dream is {_drift_words(first, k)} against reality"
    if dream_rosier(value=dc.first, se=d0se, k=k, min_effect=MIN_REWARD_EFFECT):
        causal += (": rosy with a pusher that never moves. In the expert data the block moves only when pushed, "
                   "and then toward the target's place and angle; a model can learn \"the block approaches the "
                   "target\" without the contact that causes it. ")
    else:
        causal += ". "
    sc = size_change(first, last, "eval_horizon", "gap_drift")
    kw = dict(first=sc.first, first_se=sc.first_se, last=sc.last, last_se=sc.last_se, k=sc.k,
              min_effect=sc.min_effect)
    flipped = drift_crossed_zero(first=dc.first, first_se=d0se, last=dc.last,
                                 last_se=last["gap_drift_se_eval_horizon"], k=k)
    fell, rose = error_size_shrank(**kw), error_size_grew(**kw)      # both evaluated, so both are recorded
    d = "flip" if flipped else "down" if fell else "up" if rose else "same"
    path = path_words(_series(rounds, "gap_drift_size_eval_horizon"))
    causal += (f"After round {R} that drift is {_drift_words(last, k)}. Judged by its size, as the gap is (halves "
               f"of opposite signs cancel in the signed drift), it went {sc.first:.3f} -> {sc.last:.3f}"
               + (f" ({path})" if path else "") + ": "
               + {"down": "it fell beyond the noise and the minimum effect, against round 0. ",
                  "up": "it rose beyond the noise and the minimum effect, against round 0. ",
                  "flip": "but the signed drift changed sign beyond the noise: the dream of a pusher that never "
                          "moves went from too rosy to too gloomy, the opposite error, not a smaller one. ",
                  "same": "not changed beyond the noise and the minimum effect. "}[d])
    pc, ec = last["wm_policy_one_step_block_copy_err"], last["wm_expert_one_step_block_copy_err"]
    z0, z1 = first["zero_dream_block_moved_eval_horizon"], last["zero_dream_block_moved_eval_horizon"]
    if d in ("down", "same") and not flipped and d0se > 0 and dc.first * dc.last < 0:
        causal += "(Its sign did change, though not beyond the noise.) "
    if d == "down" and pc < ec:
        if z1 < z0 - SUCCESS_POS:
            causal += (f"The policy's data, in which the block moves less (copy-last's one-step block error is "
                       f"{mm(pc)} on them, {mm(ec)} on the expert's), may have taught the model otherwise: its "
                       f"zero-action dream now moves the untouched block {z1:.3f} m, against {z0:.3f} m in round 0. ")
        else:
            causal += (f"Did the policy's data teach the model that an untouched block stays put? The control says "
                       f"not: its zero-action dream moves the untouched block {z1:.3f} m, against {z0:.3f} m in round "
                       "0 (a real one does not move). ")
    causal += ("Whether a model has the cause right is tested only by data where the cause and its usual "
               "companions come apart.")
    open_.append(causal)
    lines.append("**Open: what real success would plausibly need.** These runs suggest, they do not show: "
                 + " ".join(open_))
    return "\n\n".join(lines)


# --- every seed in this output folder ----------------------------------------------------------------
def _read_json(path):
    import json

    return json.loads(path.read_text())


def summary_runs(out_dir) -> dict:
    """Every seed's runs found under ``out_dir``: ``{seed: {"offline": m, "loop": last round,
    "delta": m, "ensemble": m}}`` (each present only where its file is). The offline run is the
    loop's round 0 (``metrics/closing/loop_seed<s>/loop.json``) or, without a loop, notebook 04's
    ``metrics/seed<s>.json``; the loop's entry is its last round; ``delta_seed<s>.json`` and
    ``ensemble_seed<s>.json`` are notebook 06's two other fixes."""
    import re
    from pathlib import Path

    out = Path(out_dir)
    closing = out / "metrics" / "closing"
    found: dict = {}

    def put(seed, kind, m):
        found.setdefault(int(seed), {})[kind] = m

    for path in sorted((out / "metrics").glob("seed*.json")):
        hit = re.fullmatch(r"seed(\d+)\.json", path.name)
        if hit:
            put(hit.group(1), "offline", _read_json(path))
    for path in sorted(closing.glob("loop_seed*/loop.json")):
        hit = re.fullmatch(r"loop_seed(\d+)", path.parent.name)
        rounds = _read_json(path)
        if hit and rounds:
            put(hit.group(1), "offline", rounds[0])
            if len(rounds) > 1:
                put(hit.group(1), "loop", rounds[-1])
    for kind in ("delta", "ensemble"):
        for path in sorted(closing.glob(f"{kind}_seed*.json")):
            hit = re.fullmatch(rf"{kind}_seed(\d+)\.json", path.name)
            if hit:
                put(hit.group(1), kind, _read_json(path))
    return dict(sorted(found.items()))


SUMMARY_KINDS = {"offline": "offline (single model)", "loop": "loop, last round", "delta": "delta model",
                 "ensemble": "ensemble + penalty"}


def summary_table(out_dir) -> str:
    """One markdown table, per seed and per fix found under ``out_dir`` (:func:`summary_runs`): the
    gap over the whole evaluation (± SE), the zero-action drift (± SE), the yaw share of the gap,
    real successes and the expert signal in the dream (± SE); and which seeds it found."""
    runs = summary_runs(out_dir)
    if not runs:
        return (f"No metrics found under `{out_dir}` (notebook 04 writes `metrics/seed<s>.json`, this notebook "
                "`metrics/closing/`).")
    head = ["seed", "run", "gap (whole evaluation)", "drift (zero actions)", "yaw share of the gap",
            "real successes", "expert signal in the dream", "rounds"]
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    missing = []
    for seed, kinds in runs.items():
        for kind, label in SUMMARY_KINDS.items():
            m = kinds.get(kind)
            if m is None:
                missing.append(f"seed {seed}: {label}")
                continue
            share = yaw_share(m)
            rows.append("| " + " | ".join([
                str(seed), label,
                pm(m["imagination_gap_eval_horizon"], m["imagination_gap_se_eval_horizon"]),
                pm(m["gap_drift_eval_horizon"], m["gap_drift_se_eval_horizon"]),
                "n/a" if math.isnan(share) else _share_cell(m),
                f"{successes(m)}/{int(m['eval_episodes'])}", _expert_cell(m),
                str(m.get("round", "")) if kind == "loop" else ""]) + " |")
    seeds = list(runs)
    text = [f"Seeds found under `{out_dir}`: {', '.join(str(s) for s in seeds)} ({len(seeds)} seed"
            f"{'s' if len(seeds) != 1 else ''}).", "", *rows, "",
            "Reward per step over the whole evaluation, ± one standard error over the evaluation starts. Gap: "
            "imagined minus real; drift: the same with zero actions (the model on its own); yaw share: |yaw "
            "half| / (|position half| + |yaw half|) of the gap; expert signal: the scripted expert's actions "
            "minus zero actions, in the dream (a dream that recognises success pays the expert's pushes more "
            "than standing still)."]
    if missing:
        text.append("Not found (that notebook or seed was not run into this folder): " + "; ".join(missing) + ".")
    return "\n".join(text)
