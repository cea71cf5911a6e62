"""The chapter's predict-then-run exercises from a terminal.

    python -m pusht.exercise ex1                 # asks for your prediction, then runs the experiment
    python -m pusht.exercise ex2 --smoke         # the tiny config: seconds
    python -m pusht.exercise ex1 --predict b --reason "the model never learned how the block moves"    # no questions asked

Notebooks 04, 05, 06 and 07 each hold one exercise: read the question, lock a prediction (a letter
and one sentence of why), run the experiment, and read how the measurement compares. This module is
the same exercise without a notebook. It shows the notebook's question and options (the option
texts are the notebook modules' own ``EX1_OPTIONS`` to ``EX4_OPTIONS``), asks for the
prediction on the terminal and locks it with ``pusht.predict.lock_prediction``: the same letters,
the same reason rule, the same store (``.pusht_predictions.json`` in the working folder, or
``$PUSHT_PREDICTIONS``), and the first lock is kept, here and in the notebook alike. Then it runs
the notebook's experiment through ``pusht.predict.run_exercise`` (with tqdm progress bars) and
prints the reconciliation with the notebook's words (``ex1_reconciliation`` and its siblings in
``pusht.nb``).

Where the notebook hands the experiment the learner's own code (Exercise 1 evaluates the ``dream``
written in notebook 04, Exercise 4 plans with the ``cem_update`` written in notebook 07), the
terminal uses the package's: the exercise here is the prediction.

Exit status: 0 after the reconciliation; 1 when no usable prediction was given (too many refused
answers, or the input ended) or the experiment failed; 2 for a usage error (unknown exercise, bad
flags, no terminal to ask on); 130 when interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

TRIES = 3                        # answers refused in a row before giving up on a question
DEFAULT_OUT = "runs/exercise"    # --out: trained models are cached under <out>/cache


class Stop(Exception):
    """Ends the command with ``message`` on stderr and exit status ``code``, without a traceback."""

    def __init__(self, message: str, code: int = 1):
        super().__init__(message)
        self.code = code


# --- the exercises: what each notebook runs, called through the package -----------------------------
def _experiment_ex1(session, progress):
    """Notebook 04's ``experiment_ex1``: train (or load from the cache) the world model and actor of
    seeds SEED and SEED + 1, then evaluate each policy in the dream and in reality from the same
    held-out starts, with the controls (``two_world_eval``). {seed: evaluation metrics}."""
    from pusht.data import EVAL_SEED_BASE, start_seeds
    from pusht.evaluate import two_world_eval
    from pusht.sweep import run_many

    cfg = session.cfg
    seeds = [cfg.seed, cfg.seed + 1]
    runs = run_many([cfg.replace(seed=s) for s in seeds], cache_dir=session.cache, model_cache=session.cache,
                    progress=progress, desc="seeds")
    out = {}
    for seed, res in zip(seeds, runs):
        (session.metrics / f"seed{seed}.json").write_text(json.dumps(res.metrics, sort_keys=True, indent=2) + "\n")
        T = res.data.torch(cfg.device)
        metrics, _ = two_world_eval(res.wm, res.agent, res.init_agent,
                                    start_seeds(EVAL_SEED_BASE, seed, cfg.eval_episodes), cfg.eval_horizon,
                                    T["mean"], T["std"], train_horizon=cfg.imag_horizon)
        out[seed] = {**metrics, "eval_episodes": cfg.eval_episodes}
    return out


def _reconcile_ex1(session, result) -> tuple[str, str]:
    from pusht.nb.gap import ex1_reconciliation

    return ex1_reconciliation(result, session.cfg.eval_episodes)


def _experiment_ex2(session, progress):
    """Notebook 05's ``experiment_ex2``: one actor per (imagination horizon, actor seed), all on the
    frozen world model of SEED, each evaluated in both worlds. {(horizon, actor seed): RunResult}."""
    from pusht.nb.horizon import EX2_ACTOR_SEEDS, EX2_HORIZONS
    from pusht.sweep import run_many

    cfg = session.cfg
    keys = [(h, a) for h in EX2_HORIZONS for a in EX2_ACTOR_SEEDS]
    runs = run_many([cfg.replace(imag_horizon=h, actor_seed=a) for h, a in keys], cache_dir=session.cache,
                    model_cache=session.cache, progress=progress, desc="sweep runs")
    for (h, a), res in zip(keys, runs):
        (session.metrics / f"seed{cfg.seed}_h{h}_actor{a}.json").write_text(
            json.dumps(res.metrics, sort_keys=True, indent=2) + "\n")
    return dict(zip(keys, runs))


def _reconcile_ex2(session, result) -> tuple[str, str]:
    from pusht.nb.horizon import ex2_reconciliation
    from pusht.predict import prediction

    return ex2_reconciliation({key: res.metrics for key, res in result.items()}, session.cfg.eval_episodes,
                              session.cfg.eval_horizon, predicted=getattr(prediction("ex2"), "choice", None))


def _experiment_ex3(session, progress):
    """Notebook 06's ``experiment_ex3``: round 0 (the offline run, cached) and ``loop_rounds`` rounds
    of collect, model, behave, both worlds measured after each; one line printed per round."""
    from tqdm import tqdm

    from pusht import loop

    cfg = session.cfg
    result = loop.run_loop(cfg, cache_dir=session.cache, model_cache=session.cache, log=None, progress=progress,
                           on_round=lambda m: tqdm.write(loop.round_line(m)))
    loop.save_loop(result, session.metrics / f"loop_seed{cfg.seed}")
    return result


def _reconcile_ex3(session, result) -> tuple[str, str]:
    from pusht.nb.closing import ex3_reconciliation

    return ex3_reconciliation(result.rounds)


def _experiment_ex4(session, progress):
    """Notebook 07's ``experiment_ex4``: the two world models it acts in, the chapter's and the recipe's
    (trained or loaded from the cache, each one's gate read on the held-out starts, as the notebook's
    sections 1-3 do before its prediction), then the actor trained in the recipe's model and the
    planner in both, in reality from the same starts, with zero actions and the expert. ``Ex4Result``."""
    from pusht.nb import planning as nb07

    cfg = session.cfg
    s = nb07.settings(cfg)
    seeds = nb07.starts(cfg, s)
    rungs = nb07.train_ladder(cfg, seeds, s, session.cache, progress=progress, names=["chapter", "recipe"])
    result = nb07.experiment(cfg, rungs, s, seeds, session.cache, progress=progress)
    (session.metrics / f"ex4_seed{cfg.seed}.json").write_text(
        json.dumps(nb07.as_json(rungs, {}, result, cfg, s), sort_keys=True, indent=2, default=float) + "\n")
    return result


def _reconcile_ex4(session, result) -> tuple[str, str]:
    from pusht.nb.planning import ex4_reconciliation

    return ex4_reconciliation(result)


@dataclass(frozen=True)
class Exercise:
    """One predict-then-run exercise: its words, and the notebook's experiment and reconciliation."""

    name: str                   # "ex1", the key of its lock in the store
    notebook: str               # the notebook that holds it
    summary: str                # one line, for --help
    context: str                # what the experiment does, as the notebook says it
    question: str               # the question itself, the notebook's words
    module: str                 # the pusht.nb module with its option texts
    options_name: str           # ... under this name
    note_name: str | None       # ... and the rule printed above them (None: none)
    metrics: str                # the notebook's metrics folder under OUT (its set-up call)
    experiment: Callable        # (session, progress) -> result
    reconciliation: Callable    # (session, result) -> (measured letter, explanation)

    def texts(self) -> tuple[str, dict]:
        """(the rule shown above the options, or "", {letter: option text}), from the notebook's module."""
        import importlib

        mod = importlib.import_module(self.module)
        return (getattr(mod, self.note_name) if self.note_name else ""), getattr(mod, self.options_name)


EXERCISES = {ex.name: ex for ex in [
    Exercise(
        "ex1", "04_imagination_gap",
        "notebook 04: the same policy in the dream and in reality; is the dream rosier, and why? (2 seeds)",
        "The trained policy now runs from held-out starts it has never seen, in the dream and in the real "
        "simulator, on two seeds (two independently trained world models and actors). Alongside it, the same "
        "evaluation runs a control: a pusher that never moves (zero actions), in the dream and in reality, "
        "from the same starts.",
        "What do you expect, over the 10 s evaluation?",
        "pusht.nb.gap", "EX1_OPTIONS", None, "metrics", _experiment_ex1, _reconcile_ex1),
    Exercise(
        "ex2", "05_horizon",
        "notebook 05: train the actor with 5-, 15- and 30-step dreams; what happens to the gap? (12 runs)",
        "We train the actor with three imagination horizons, 5, 15 and 30 steps (0.5, 1.5 and 3 s of dreamed "
        "time per update), and at each horizon with four actor seeds (0, 1, 2, 3), all on the same frozen world "
        "model of your --seed. Every one of the twelve policies is then evaluated the same way, in the dream and "
        "in reality. The number to predict is the imagination gap: imagined minus real reward per step over "
        "the whole evaluation. Positive means the dream rates the policy above what reality pays it; negative "
        "means below. The letter is decided by the shortest horizon against the longest, by the rule below.",
        "From 5 to 30 steps, what happens to the gap?",
        "pusht.nb.horizon", "EX2_OPTIONS", "EX2_RULE", "metrics/horizon_sweep", _experiment_ex2, _reconcile_ex2),
    Exercise(
        "ex3", "06_closing_the_gap",
        "notebook 06: Dreamer's real-data loop for a few rounds; does the gap shrink, does the policy succeed?",
        "Dreamer's loop, round after round: the current policy collects real episodes (with exploration "
        "noise), the world model goes on training on everything seen so far, and the actor-critic goes on "
        "training in the new model; after each round both worlds are measured as in notebook 04. We run a "
        "few rounds of the loop from round 0 (the default is three). The number to predict is the "
        "imagination gap over the whole evaluation (imagined minus real reward per step, as in notebooks 04 "
        "and 05), and whether the policy starts to succeed in reality. The note below defines what "
        "\"shrinks\" means.",
        "Which outcome do you expect?",
        "pusht.nb.closing", "EX3_OPTIONS", "EX3_NOTE", "metrics/closing", _experiment_ex3, _reconcile_ex3),
    Exercise(
        "ex4", "07_planning",
        "notebook 07: an actor trained in a better world model, and a planner searching in it; which succeeds?",
        "Notebook 07's recipe for a better world model: richer data (the expert with noise, pauses mid-push, "
        "random walks and pokes), a model that predicts the change of each frame, twice as wide. Two ways to "
        "act in it, from the same held-out starts: the actor-critic of notebook 03, trained in its dreams and "
        "deployed; and a planner that trains nothing: at every real step it samples short plans, dreams each "
        "one, refits a Gaussian to the best (the cross-entropy method), takes the first action of its final "
        "plan in the real simulator, and plans again from the true state. The same planner also runs in the "
        "chapter's own model. Here the experiment first trains (or loads) both models and reads each one's "
        "gate, as the notebook does before its prediction; the planner uses the package's refit where the "
        "notebook uses yours.",
        "Which of the actor and the planner **succeeds in reality**?",
        "pusht.nb.planning", "EX4_OPTIONS", "EX4_NOTE", "metrics/planning", _experiment_ex4, _reconcile_ex4),
]}


# --- the terminal ----------------------------------------------------------------------------------
def _plain(markdown: str) -> str:
    """The notebooks' markdown as terminal text: bold and code marks dropped."""
    return markdown.replace("**", "").replace("`", "")


def _wrap(text: str, first: str = "") -> str:
    """``text`` as terminal lines (at most 100 columns), after ``first``, the later lines indented as far."""
    width = min(100, shutil.get_terminal_size((100, 24)).columns)
    return textwrap.fill(text, width=width, initial_indent=first, subsequent_indent=" " * len(first))


def show_question(ex: Exercise) -> dict:
    """Print the exercise's question, rule and options; return the options {letter: text}."""
    note, options = ex.texts()
    print(_wrap(f"Exercise {ex.name[2:]} (notebook {ex.notebook}) · Predict, then run"))
    print()
    print(_wrap(ex.context))
    print()
    print(_wrap(_plain(ex.question)))
    if note:
        print()
        print(_wrap(_plain(note)))
    print()
    for letter, text in options.items():
        print(_wrap(_plain(text), f"  ({letter}) "))
    print()
    return options


def _letter(answer: str) -> str:
    """An answer as ``lock_prediction`` reads a letter ("B", "(b)", " b " are all b);
    ``tests/test_exercise.py`` checks that the two agree, so the terminal refuses no letter the
    notebook takes. ``lock_prediction`` still judges the letter when it locks."""
    return answer.strip().lower().strip("()")


def ask_prediction(ex: Exercise, tries: int = TRIES):
    """Ask for the letter, then the sentence, on the terminal, and lock them; each question is asked
    again after a refused answer (with what was wrong), at most ``tries`` times."""
    from pusht.predict import MIN_WORDS, choices_of, lock_prediction

    letters = choices_of(ex.name)
    listed = ", ".join(letters[:-1]) + " or " + letters[-1]
    for _ in range(tries):
        choice = input(f"Your prediction ({listed}): ")
        if _letter(choice) in letters:
            break
        print(f"  {choice.strip()!r} is not one of the options: answer with one letter, {listed}.")
    else:
        raise Stop(f"no option chosen after {tries} tries; nothing is locked. Run it again to predict.")
    for _ in range(tries):
        reason = input(f"Why? One sentence (at least {MIN_WORDS} words): ")
        try:
            return lock_prediction(ex.name, choice, reason)
        except ValueError as e:
            print(f"  {e}")
    raise Stop(f"no usable reason after {tries} tries; nothing is locked. Run it again to predict.")


def _show_lock(p, options: dict, store: Path) -> None:
    print(_wrap(f"Your prediction for {p.exercise} is already locked (at {p.locked_at}, in {store}); "
                f"the first lock is kept, so the experiment runs with it:"))
    print(_wrap(_plain(options.get(p.choice, "")), f"  ({p.choice}) "))
    print(_wrap(p.reason, "  why: "))


def lock(ex: Exercise, options: dict, predict: str | None, reason: str | None):
    """The prediction the experiment runs with: the one already in the store if there is one (the
    first lock is kept), else the flags' (``--predict``/``--reason``), else asked on the terminal."""
    from pusht.predict import lock_prediction, prediction, store_path

    p = prediction(ex.name)
    if p is not None:
        _show_lock(p, options, store_path().resolve())
        if predict is not None and _letter(predict) != p.choice:
            print(f"  (--predict {predict} is not used: the first lock is kept.)")
        return p
    if predict is not None:
        try:
            return lock_prediction(ex.name, predict, reason)
        except ValueError as e:
            raise Stop(f"{e}\nnothing is locked.", code=2) from None
    if not sys.stdin.isatty():
        raise Stop(f"no terminal to ask for your prediction on (stdin is not a terminal). Run it in a "
                   f"terminal, or give the prediction as flags:\n  python -m pusht.exercise {ex.name} "
                   f"--predict LETTER --reason \"one sentence of why you expect it\"", code=2)
    return ask_prediction(ex)


def start(ex: Exercise, seed: int, smoke: bool, device: str, out):
    """The notebook's set-up cell (``pusht.nb.setup``): its config and its folders under ``out``.
    Done before the prediction, as in the notebook, so that an unusable folder fails before a lock."""
    from pusht.nb import setup

    session = setup(seed, smoke, device, out, metrics=ex.metrics)
    cfg = session.cfg
    print(f"config: seed {cfg.seed}, device {cfg.device}{'  [SMOKE: tiny config]' if cfg.smoke else ''}; "
          f"trained models cached under {session.cache}\n")
    return session


def run(ex: Exercise, session) -> None:
    """After the lock: the notebook's experiment through ``run_exercise`` with progress bars, the
    measured outcome, and the reconciliation."""
    from tqdm import tqdm

    from pusht.predict import reconcile, run_exercise

    print()
    t0 = time.perf_counter()
    result = run_exercise(ex.name, ex.experiment, session, tqdm)
    print(f"(the experiment took {time.perf_counter() - t0:.0f} s)\n")
    letter, explanation = ex.reconciliation(session, result)
    _, options = ex.texts()
    print(_wrap(_plain(options[letter]), f"Measured: ({letter}) "))
    print()
    reconcile(ex.name, letter, explanation)


def _seed(text: str) -> int:
    value = int(text)
    if value < 0:
        raise ValueError(text)
    return value


_seed.__name__ = "seed (a whole number, 0 or more)"     # argparse names the type in its message


def build_parser() -> argparse.ArgumentParser:
    listing = "\n".join(f"  {ex.name}  {ex.summary}" for ex in EXERCISES.values())
    p = argparse.ArgumentParser(
        prog="python -m pusht.exercise", formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Predict, then run: one of the chapter's exercises from a terminal. It shows the\n"
                    "question, locks your prediction (as the notebook does, in the same store), runs the\n"
                    "experiment and reconciles the measurement with your prediction.",
        epilog=f"exercises:\n{listing}\n\nPredictions are kept in .pusht_predictions.json in the current folder (or\n"
               f"the file $PUSHT_PREDICTIONS names), the store the notebooks use; the first lock of an\n"
               f"exercise is kept.")
    p.add_argument("exercise", nargs="?", metavar="EXERCISE", help=f"one of {', '.join(EXERCISES)}")
    p.add_argument("--seed", type=_seed, default=0, help="master seed, the notebooks' SEED (default: 0)")
    p.add_argument("--smoke", action="store_true", help="the tiny config: runs in seconds (the notebooks' SMOKE)")
    p.add_argument("--out", default=DEFAULT_OUT,
                   help=f"folder for the cache of trained models and the metrics (default: {DEFAULT_OUT}; "
                        f"runs/notebooks shares the notebooks' cache)")
    p.add_argument("--device", default="cpu", help="torch device (default: cpu, where results are recorded)")
    p.add_argument("--predict", metavar="LETTER", help="your prediction, without being asked (with --reason)")
    p.add_argument("--reason", metavar="SENTENCE", help="one sentence of why (with --predict)")
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.exercise is None:
        parser.print_usage(sys.stderr)
        print(f"error: name an exercise: {', '.join(EXERCISES)} (--help describes them)", file=sys.stderr)
        return 2
    ex = EXERCISES.get(args.exercise.strip().lower())
    if ex is None:
        parser.error(f"unknown exercise {args.exercise!r}: choose one of {', '.join(EXERCISES)} "
                     f"(--help describes them)")
    if (args.predict is None) != (args.reason is None):
        parser.error("--predict and --reason go together: give both, or neither to be asked")
    locked = False
    try:
        import torch

        try:
            torch.empty(0, device=args.device)     # an unusable device fails now, before any question
        except Exception as e:  # noqa: BLE001  torch raises RuntimeError or AssertionError here
            parser.error(f"--device {args.device} is not usable here ({str(e).splitlines()[0]}); "
                         f"use --device cpu")
        session = start(ex, args.seed, args.smoke, args.device, args.out)
        options = show_question(ex)
        if args.smoke:           # the question's words are the default config's
            from pusht.env import CONTROL_DT
            c = session.cfg
            print(_wrap(f"(--smoke: a tiny config. Its evaluation lasts {c.eval_horizon * CONTROL_DT:g} s and "
                        f"its loop {c.loop_rounds} rounds; the question's figures are the default config's.)"))
        lock(ex, options, args.predict, args.reason)
        locked = True
        run(ex, session)
    except Stop as e:
        print(f"error: {e}", file=sys.stderr)
        return e.code
    except OSError as e:                           # e.g. an --out that cannot be written
        print(f"error: {e} (is --out {args.out} a folder you can write in?)", file=sys.stderr)
        return 1
    except (EOFError, KeyboardInterrupt) as e:
        what = "interrupted" if isinstance(e, KeyboardInterrupt) else "input ended"
        if locked:
            print(f"\n{what}: the experiment did not finish; your prediction stays locked. Run "
                  f"`python -m pusht.exercise {ex.name}` again to run it.", file=sys.stderr)
        else:
            print(f"\n{what}: nothing is locked and nothing ran.", file=sys.stderr)
        return 130 if isinstance(e, KeyboardInterrupt) else 1
    return 0


if __name__ == "__main__":
    code = main()
    import gc

    gc.freeze()     # spares the interpreter's last collection from re-walking all of torch (see pusht.dreamer)
    sys.exit(code)
