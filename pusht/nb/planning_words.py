"""The sentences and tables notebook 07 prints, each run-dependent reading decided by a claim
(``planning_claims``), and Exercise 4: its options and note, its measured letter and reconciliation,
which the notebook and ``python -m pusht.exercise ex4`` print alike."""

from __future__ import annotations

from pusht.env import CONTROL_DT as DT, SUCCESS_POS

from .fmt import pm
from .planning_claims import (actor_below_zero_in_dream, actor_exploits, below_zero_action, change_lowered_signal, change_raised_signal,
                              drift_toward_target, gate_passes, gate_predicted, succeeds_in_reality,
                              zero_only_on_target)
from .planning_measure import LABELS, succeeds
from .prose import note, options
from .stats import MIN_REWARD_EFFECT

EX4_OPTIONS = options("07_planning", "ex4")
EX4_NOTE = note("07_planning", "ex4", min_effect=f"{MIN_REWARD_EFFECT:.2f}")


def _cm(x: float) -> str:
    return f"{100 * x:.1f} cm"


def _cap(text: str) -> str:
    return text[:1].upper() + text[1:]


# --- the gate --------------------------------------------------------------------------------------
def passes(rung) -> bool:
    """The gate's verdict on one rung, through its claim (the same test ``gate.verdict`` applies)."""
    g = rung.gate
    return gate_passes(signal=g["expert_signal_dream"], se=g["expert_signal_dream_se"], k=g["k"],
                       min_effect=g["min_effect"], quantity=f"gate {rung.name}")


def gate_table(rungs: dict) -> str:
    """One row per world model: the expert's pushes minus zero actions in the dream and in reality,
    how far the dream moves an untouched block, and the verdict."""
    head = ("| world model | expert − zero actions, dream | ... in reality | untouched block moved in the dream "
            "| the gate |\n| --- | --- | --- | --- | --- |")
    rows = []
    for r in rungs.values():
        g = r.gate
        rows.append(f"| {r.label} | {pm(g['expert_signal_dream'], g['expert_signal_dream_se'])} | "
                    f"{pm(g['expert_signal_real'], g['expert_signal_real_se'])} | {_cm(g['zero_dream_block_moved'])} | "
                    f"{'**passes**' if passes(r) else 'fails'} |")
    r0 = next(iter(rungs.values()))
    return (head + "\n" + "\n".join(rows) + f"\n\nReward per step over the planner's {r0.gate['horizon']} steps, "
            f"mean ± standard error over {r0.gate['n_starts']} held-out starts. The gate passes when the dream's "
            f"number is above zero by more than k = {r0.gate['k']:.2f} standard errors and by at least "
            f"{MIN_REWARD_EFFECT:.2f} per step (the minimum effect).")


def gate_sentence(rung) -> str:
    """What the gate says of one model, in words."""
    g = rung.gate
    dream, real = pm(g["expert_signal_dream"], g["expert_signal_dream_se"]), pm(g["expert_signal_real"], g["expert_signal_real_se"])
    if passes(rung):
        return (f"**{_cap(rung.say)} passes the gate.** Its dream pays the expert's pushes {dream} per step "
                f"more than standing still; reality pays {real}. The dream ranks them as reality does.")
    return (f"**{_cap(rung.say)} fails the gate.** Reality pays the expert's pushes {real} per step more "
            f"than standing still; this model's dream pays them {dream}: it cannot tell the pushes that solve the "
            f"task from doing nothing, so nothing planned or trained in it can be expected to find them.")


def drift_sentence(rung) -> str:
    """Where the dream takes a block nobody touches (the zero-action dream), guarded by its claim."""
    import numpy as np

    from .planning_measure import paired

    t = paired(rung.toward, np.zeros_like(rung.toward))
    toward = drift_toward_target(value=t["diff"], se=t["se"], k=t["k"], tolerance=SUCCESS_POS,
                                 quantity=f"drift {rung.name}")
    moved = _cm(float(rung.moved.mean()))
    if toward:
        return (f"With nobody pushing, the dream of {rung.say} moves the block by up to {moved} on average within "
                f"{rung.gate['horizon']} steps, and **toward the target**: it ends {_cm(t['diff'])} ± "
                f"{_cm(t['se'])} nearer than it started. In reality it stays where it is.")
    return (f"With nobody pushing, the dream of {rung.say} moves the block by up to {moved} on average within "
            f"{rung.gate['horizon']} steps, and not toward the target beyond the noise and the {_cm(SUCCESS_POS)} "
            f"tolerance ({_cm(t['diff'])} ± {_cm(t['se'])} nearer).")


# --- the data --------------------------------------------------------------------------------------
def census_sentence(chapter: dict, rich: dict) -> str:
    """How often a zero action appears in each data set, and where."""
    only = zero_only_on_target(zero=chapter["zero"], zero_off_target=chapter["zero_off_target"])
    share = f"{chapter['zero_share']:.1%}"
    if only:
        first = (f"In the chapter's data ({chapter['sequences']} expert sequences) a zero action is {share} of the "
                 f"steps ({chapter['zero']} of {chapter['steps']}), and **every one of them comes with the block "
                 f"already on the target**: the padding after an early success. The model never saw a zero action "
                 f"meet a block that is off the target and must stay there.")
    elif chapter["zero"] == 0:
        first = (f"In the chapter's data ({chapter['sequences']} expert sequences) no step has a zero action: "
                 f"the model never saw the pusher stand still.")
    else:
        first = (f"In the chapter's data ({chapter['sequences']} expert sequences) a zero action is {share} of the "
                 f"steps ({chapter['zero']} of {chapter['steps']}); {chapter['zero_on_target']} of them with the "
                 f"block on the target, {chapter['zero_off_target']} with it off.")
    kinds = ", ".join(f"{v['sequences']} {k}" for k, v in rich["by_kind"].items())
    second = (f" The richer data ({kinds} sequences) has {rich['zero']} zero-action steps "
              f"({rich['zero_share']:.1%}), {rich['zero_off_target']} of them with the block off the target.")
    return first + second


# --- the model: the 2x2 ------------------------------------------------------------------------------
_SHARE_WORDS = {"data": ("the richer data", "the chapter's model", "the chapter's model on the richer data"),
                "delta_alone": ("predicting changes", "at the chapter's width", None),
                "delta_with_size": ("predicting changes", "at twice the width", None),
                "size_alone": ("twice the width", "predicting states", None),
                "size_with_delta": ("twice the width", "predicting changes", None)}


def change_verdict(name: str, t: dict) -> str:
    """"raised", "lowered" or "no change" for one change's paired effect, through its claims."""
    args = dict(diff=t["diff"], se=t["se"], k=t["k"], min_effect=t["min_effect"], quantity=f"change {name}")
    if change_raised_signal(**args):
        return "raised"
    if change_lowered_signal(**args):
        return "lowered"
    return "no change beyond the noise"


def shares_table(shares: dict) -> str:
    """Each change's effect on the dream's expert signal, paired over the same starts."""
    head = "| change | with | effect on the dream's expert signal | verdict |\n| --- | --- | --- | --- |"
    rows = []
    for name, t in shares.items():
        what, where, _ = _SHARE_WORDS[name]
        rows.append(f"| {what} | {where} | {pm(t['diff'], t['se'])} | {change_verdict(name, t)} |")
    t0 = next(iter(shares.values()))
    return (head + "\n" + "\n".join(rows) + f"\n\nReward per step, the model with the change minus the model "
            f"without it, each start's difference averaged (± standard error); a verdict needs more than "
            f"k = {t0['k']:.2f} standard errors and at least {t0['min_effect']:.2f}.")


def shares_sentence(shares: dict) -> str:
    """Which of the two model changes carried the gate, in words."""
    v = {name: change_verdict(name, t) for name, t in shares.items()}
    delta = [v["delta_alone"], v["delta_with_size"]]
    size = [v["size_alone"], v["size_with_delta"]]

    if delta[0] == size[0] == "raised" and delta[1] == size[1] == "no change beyond the noise":
        return ("On your run, **each change alone raised the dream's expert signal, and neither added to the other** "
                "beyond the noise: predicting changes and twice the width repair the same thing here.")

    def says(verdicts, what):
        if all(x == "raised" for x in verdicts):
            return f"{what} raised the dream's expert signal with and without the other change"
        if verdicts[0] == "raised":
            return f"{what} raised the dream's expert signal alone, but added nothing beyond the noise on top of the other"
        if verdicts[1] == "raised":
            return f"{what} raised the dream's expert signal only on top of the other change"
        if any(x == "lowered" for x in verdicts):
            return f"{what} did not raise the dream's expert signal (lowered it {sum(x == 'lowered' for x in verdicts)} time(s) of 2)"
        return f"{what} made no difference to the dream's expert signal beyond the noise"
    return f"On your run, {says(delta, 'predicting changes')}; {says(size, 'twice the width')}."


# --- the planner and the actor ---------------------------------------------------------------------
_ROWS = {"planner": "planner, recipe's model", "planner_chapter": "planner, chapter's model",
         "actor": "actor, recipe's model", "zero": "zero actions", "expert": "scripted expert"}


def outcome_table(res) -> str:
    """Every policy's real result on the same held-out starts."""
    head = ("| policy (in reality) | solved | 95% interval | reward/step | minus zero actions | final distance "
            "| final yaw error |\n| --- | --- | --- | --- | --- | --- | --- |")
    rows = []
    for name, label in _ROWS.items():
        o = res.outcomes[name]
        vs = "" if name == "zero" else pm(o["minus_zero"], o["minus_zero_se"])
        rows.append(f"| {label} | {o['successes']}/{o['n']} | {100 * o['low']:.0f}-{100 * o['high']:.0f}% | "
                    f"{pm(o['reward'], o['reward_se'])} | {vs} | {_cm(o['final_dist'])} | {o['final_yaw_deg']:.0f}° |")
    o = res.outcomes["planner"]
    return (head + "\n" + "\n".join(rows) + f"\n\n{o['n']} held-out starts, {res.rollouts['zero'].actions.shape[0]} "
            f"real steps each; ± one standard error over the starts (the difference from zero actions is paired "
            f"per start); the interval of the success rate is Wilson's.")


def decided(res, name: str) -> dict:
    """The claims' readings of one policy's outcome: succeeds, below zero actions."""
    o = res.outcomes[name]
    args = dict(diff=o["minus_zero"], se=o["minus_zero_se"], k=o["k"], min_effect=o["min_effect"], quantity=name)
    return {"succeeds": succeeds_in_reality(successes=o["successes"], **args), "below": below_zero_action(**args)}


def _policy_words(res, name: str, label: str) -> str:
    o, d = res.outcomes[name], decided(res, name)
    rate = f"{o['successes']} of {o['n']} starts solved ({100 * o['low']:.0f}-{100 * o['high']:.0f}%)"
    if d["succeeds"]:
        return f"{label} **succeeds in reality**: {rate}, and it earns more per step than standing still beyond the noise"
    if d["below"]:
        return f"{label} does not succeed: {rate}, and it earns **less** per step than standing still, beyond the noise"
    if o["successes"]:
        return f"{label} does not succeed by this test: {rate}, but its reward per step is not above standing still's beyond the noise"
    return f"{label} does not succeed: {rate}, and its reward per step is level with standing still's"


def outcome_sentence(res) -> str:
    """The planner and the actor in the same model, and the planner in the chapter's model."""
    return (_policy_words(res, "planner", "The planner in the recipe's model") + ". "
            + _policy_words(res, "actor", "The actor trained in the same model") + ". "
            + _policy_words(res, "planner_chapter", "The same planner in the chapter's model") + ".")


def actor_sentence(res, train_horizon: int) -> str:
    """Why the actor failed, read against two controls on the same starts: its own dream's rating of
    it against the same dream's zero actions (did it learn a good policy even in the model?), and its
    dream against reality over the whole evaluation and over the steps it trains on (did it exploit
    the model?)."""
    from .planning_measure import actor_readings

    r = actor_readings(res, train_horizon)
    vs, whole, short = r["dream_vs_zero"], r["gap_eval"], r["gap_train"]
    below = actor_below_zero_in_dream(diff=vs["diff"], se=vs["se"], k=vs["k"], min_effect=vs["min_effect"],
                                      quantity="actor dream vs zero")
    rosy = {span: actor_exploits(gap=t["diff"], se=t["se"], k=t["k"], min_effect=t["min_effect"], quantity=f"actor gap {span}")
            for span, t in (("eval", whole), ("train", short))}
    steps = res.rollouts["zero"].actions.shape[0]
    first = (f"The actor's own dream of the {steps} steps rates it {r['dream']:+.3f} per step, and the same dream "
             f"rates standing still {r['dream_zero']:+.3f}: ")
    if below:
        first += (f"**even in the model, the actor is worse than doing nothing** ({pm(vs['diff'], vs['se'])}). Its "
                  f"training did not find a good policy in the dream itself, so its failure in reality is first a "
                  f"failure of its learning, not of the model alone.")
    elif vs["up"]:
        first += f"in the model, it is better than doing nothing ({pm(vs['diff'], vs['se'])})."
    else:
        first += f"in the model, it is level with doing nothing ({pm(vs['diff'], vs['se'])})."
    if rosy["train"]:
        second = (f" Over the {train_horizon} steps it learns from, its dream is rosier than reality by "
                  f"**{pm(short['diff'], short['se'])}** per step, beyond the noise: the short dreams it is trained on "
                  f"pay it more than reality does, and it learned from them.")
    else:
        second = (f" Over the {train_horizon} steps it learns from, its dream and reality differ by "
                  f"{pm(short['diff'], short['se'])} per step, not beyond the noise and the minimum effect.")
    if rosy["eval"]:
        second += (f" Over the whole evaluation the dream rates it {pm(whole['diff'], whole['se'])} above reality: it "
                   f"exploits even the model that passes the gate.")
    else:
        second += (f" Over the whole evaluation its dream does not rate it above reality beyond the noise and the "
                   f"minimum effect (dream minus reality {pm(whole['diff'], whole['se'])}).")
    return first + second


def gate_predicted_sentence(res) -> str:
    """Did each model's gate, read before planning, predict the planner's outcome in it?"""
    passed = [bool(res.gates[n]["passed"]) for n in ("planner", "planner_chapter")]
    worked = [decided(res, n)["succeeds"] for n in ("planner", "planner_chapter")]
    pairs = "; ".join(f"{label}: the gate {'passed' if p else 'failed'}, the planner {'succeeded' if w else 'did not succeed'}"
                      for label, p, w in zip(("the recipe's model", "the chapter's model"), passed, worked))
    if gate_predicted(passed=passed, succeeded=worked):
        return (f"**The gate predicted the planner's outcome in both models** ({pairs}): read in seconds, before "
                f"any planning.")
    return (f"**On your run the gate did not predict every outcome** ({pairs}). The gate is necessary evidence, "
            f"not a guarantee: a model can rank the expert's pushes right and still mislead a search elsewhere, "
            f"and a search can find a few real successes in a model the gate did not trust.")


# --- Exercise 4 --------------------------------------------------------------------------------------
def ex4_verdict(res) -> str:
    """The measured letter: which of the actor and the planner (in the recipe's model) succeed."""
    planner, actor = decided(res, "planner")["succeeds"], decided(res, "actor")["succeeds"]
    return {(False, True): "a", (True, False): "b", (True, True): "c", (False, False): "d"}[(planner, actor)]


def ex4_reconciliation(res) -> tuple[str, str]:
    """(measured letter, explanation): the words the notebook and ``python -m pusht.exercise ex4`` print."""
    letter = ex4_verdict(res)
    words = [_policy_words(res, "planner", "The planner") + ".",
             _policy_words(res, "actor", "The actor, trained in the same model") + ".",
             "Both act in the same frozen model. The actor learned its behaviour once, in the dream, and then "
             "acts on it without ever comparing a prediction with reality; the planner dreams only "
             f"{res.gates['planner']['horizon']} steps ({res.gates['planner']['horizon'] * DT:.1f} s) ahead and "
             "starts again from the true state at every real step, so a dream's error has little time to grow, "
             f"and what it promised is checked against reality every {DT:.1f} s.",
             f"So the measured answer is ({letter})."]
    return letter, " ".join(w.replace("**", "") for w in words)


__all__ = ["EX4_NOTE", "EX4_OPTIONS", "LABELS", "census_sentence", "change_verdict", "decided", "drift_sentence",
           "ex4_reconciliation", "ex4_verdict", "actor_sentence", "gate_predicted_sentence", "gate_sentence",
           "gate_table", "outcome_sentence", "outcome_table", "passes", "shares_sentence", "shares_table",
           "succeeds"]
