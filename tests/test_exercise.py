"""``python -m pusht.exercise``: the predict-then-run exercises from a terminal.

Each test runs the module in a child process, in a temporary working folder, with its prediction
store (``$PUSHT_PREDICTIONS``) in that folder and the smoke config. The interactive ones drive it
through a real pseudo-terminal (``pty``), typing the answers as a learner would; the others give it
no terminal at all (stdin from /dev/null). The trained models are cached in one folder shared by the
whole file, so only the first run of a config trains.
"""

from __future__ import annotations

import json
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time
from dataclasses import asdict
from pathlib import Path

import pytest

from pusht import exercise, predict

ROOT = Path(__file__).resolve().parents[1]
REASON = "The actor exploits errors of the model, so the dream pays more than reality."


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    """--out for every run here: one cache of trained smoke models for the whole file."""
    return tmp_path_factory.mktemp("exercise_out")


@pytest.fixture
def env(tmp_path):
    e = {**os.environ, "PUSHT_PREDICTIONS": str(tmp_path / "predictions.json"), "PYTHONPATH": str(ROOT),
         "COLUMNS": "100", "TERM": "dumb"}
    e.pop("NBGRADER_EXECUTION", None)
    return e


def store(env) -> dict:
    path = Path(env["PUSHT_PREDICTIONS"])
    return json.loads(path.read_text()) if path.exists() else {}


def args(name, out, *more):
    return [sys.executable, "-m", "pusht.exercise", name, "--smoke", "--out", str(out), *more]


def no_terminal(argv, env, cwd, timeout=120):
    """Run with stdin from /dev/null (no terminal); (exit status, stdout, stderr)."""
    p = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, env=env, cwd=cwd,
                       timeout=timeout)
    return p.returncode, p.stdout, p.stderr


class Terminal:
    """A child process on a pseudo-terminal: ``expect`` what it prints, ``send`` what is typed."""

    def __init__(self, argv, env, cwd):
        self.pid, self.fd = pty.fork()
        if self.pid == 0:                           # the child: the pty is its controlling terminal
            try:
                os.chdir(cwd)
                os.execve(argv[0], argv, env)
            finally:
                os._exit(127)
        self.text, self.pos = "", 0

    def _read(self, timeout: float) -> bool:
        ready, _, _ = select.select([self.fd], [], [], timeout)
        if not ready:
            return True
        try:
            chunk = os.read(self.fd, 65536)
        except OSError:                             # EIO: the child is gone and the pty closed
            return False
        self.text += chunk.decode(errors="replace").replace("\r\n", "\n")
        return bool(chunk)

    def expect(self, pattern: str, timeout: float = 60) -> None:
        """Wait until ``pattern`` is printed after what the last ``expect`` matched."""
        deadline = time.monotonic() + timeout
        while (i := self.text.find(pattern, self.pos)) < 0:
            if time.monotonic() > deadline or not self._read(max(0.0, deadline - time.monotonic())):
                raise AssertionError(f"never printed {pattern!r}; printed:\n{self.text}")
        self.pos = i + len(pattern)

    def send(self, line: str) -> None:
        os.write(self.fd, line.encode())

    def alive(self, seconds: float) -> bool:
        """Read for up to ``seconds``; is the child still running?"""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            if not self._read(max(0.0, deadline - time.monotonic())):
                return False
        return True

    def wait(self, timeout: float = 120) -> int:
        """Read to the end; the exit status (a signal's number as 128 + n)."""
        deadline = time.monotonic() + timeout
        while self._read(max(0.0, deadline - time.monotonic())):
            if time.monotonic() > deadline:
                os.kill(self.pid, signal.SIGKILL)
                raise AssertionError(f"still running after {timeout} s; printed:\n{self.text}")
        _, status = os.waitpid(self.pid, 0)
        os.close(self.fd)
        return os.waitstatus_to_exitcode(status) if hasattr(os, "waitstatus_to_exitcode") else status >> 8


def in_order(text: str, *needles: str) -> None:
    at = -1
    for n in needles:
        i = text.find(n, at + 1)
        assert i > at, f"{n!r} not found after position {at}; printed:\n{text}"
        at = i


# --- whole exercises, answered on a terminal ----------------------------------------------------------
def test_ex1_on_a_terminal_locks_runs_and_reconciles(out, env, tmp_path):
    t = Terminal(args("ex1", out), env, tmp_path)
    t.expect("What do you expect, over the 10 s evaluation?")
    t.expect("(d) No real success beyond chance, and the dream is no rosier than reality.")
    t.expect("Your prediction (a, b, c or d): ")
    t.send("b\n")
    t.expect("Why? One sentence (at least 6 words): ")
    t.send(REASON + "\n")
    assert t.wait() == 0, t.text
    in_order(t.text, "[prediction locked] ex1: (b) at", "[experiment started] ex1 at", "[experiment finished] ex1",
             "Measured: (", "Reconcile ex1: you predicted (b); the measurement says (")
    assert "Traceback" not in t.text
    lock = store(env)["ex1"]
    assert (lock["choice"], lock["reason"]) == ("b", REASON)
    assert f"(prediction locked at {lock['locked_at']})" in t.text         # the run used this lock
    assert (out / "metrics" / "seed0.json").exists() and (out / "metrics" / "seed1.json").exists()


@pytest.mark.slow                  # runs exercise 2's horizon sweep
def test_ex2_on_a_terminal_asks_again_after_a_refused_letter_and_an_empty_reason(out, env, tmp_path):
    t = Terminal(args("ex2", out), env, tmp_path)
    t.expect("From 5 to 30 steps, what happens to the gap?")
    t.expect("Your prediction (a, b or c): ")
    t.send("d\n")                                  # ex2 has no (d)
    t.expect("'d' is not one of the options: answer with one letter, a, b or c.")
    t.expect("Your prediction (a, b or c): ")
    t.send("(A)\n")                                # read as lock_prediction reads it
    t.expect("Why? One sentence (at least 6 words): ")
    t.send("\n")
    t.expect("reason must be one real sentence (at least 6 words)")
    t.expect("Why? One sentence (at least 6 words): ")
    t.send(REASON + "\n")
    assert t.wait() == 0, t.text
    in_order(t.text, "[prediction locked] ex2: (a) at", "[experiment started] ex2 at",
             "[experiment finished] ex2", "Measured: (", "Reconcile ex2: you predicted (a); the measurement says (")
    assert "Traceback" not in t.text
    assert store(env)["ex2"]["choice"] == "a" and set(store(env)) == {"ex2"}
    from pusht.nb.horizon import EX2_ACTOR_SEEDS, EX2_HORIZONS

    runs = len(EX2_HORIZONS) * len(EX2_ACTOR_SEEDS)
    assert len(list((out / "metrics" / "horizon_sweep").glob("seed0_h*_actor*.json"))) == runs


def test_ex4_with_flags_trains_both_models_plans_and_reconciles(out, env, tmp_path):
    # notebook 07's experiment: the chapter's and the recipe's world models, the actor in the recipe's,
    # the planner (the package's refit) in both; the prediction given as flags, no terminal needed
    code, stdout, stderr = no_terminal(args("ex4", out, "--predict", "(B)", "--reason", REASON), env, tmp_path,
                                       timeout=300)
    assert code == 0, (stdout, stderr)
    in_order(stdout, "Which of the actor and the planner succeeds in reality?", "(d) Neither succeeds",
             "[prediction locked] ex4: (b) at", "[experiment started] ex4 at", "[experiment finished] ex4",
             "Measured: (", "Reconcile ex4: you predicted (b); the measurement says (")
    assert "**" not in stdout and "Traceback" not in stdout + stderr and set(store(env)) == {"ex4"}
    saved = json.loads((out / "metrics" / "planning" / "ex4_seed0.json").read_text())
    assert set(saved["gates"]) == {"chapter", "recipe"} and saved["letter"] in "abcd"
    assert set(saved["outcomes"]) >= {"actor", "planner", "planner_chapter", "zero", "expert"}
    assert f"So the measured answer is ({saved['letter']})." in stdout


# --- refused and missing answers: a clear message, nothing locked, nothing run ------------------------
def test_a_letter_refused_three_times_gives_up(out, env, tmp_path):
    t = Terminal(args("ex1", out), env, tmp_path)
    for answer in ("e", "yes", "1"):
        t.expect("Your prediction (a, b, c or d): ")
        t.send(answer + "\n")
        t.expect(f"{answer!r} is not one of the options")
    assert t.wait() == 1
    assert "error: no option chosen after 3 tries; nothing is locked" in t.text
    assert "Traceback" not in t.text and "[experiment started]" not in t.text and store(env) == {}


@pytest.mark.parametrize("key,message,code", [("\x04", "input ended: nothing is locked and nothing ran", 1),
                                              ("\x03", "interrupted: nothing is locked and nothing ran", 130)])
def test_ctrl_d_and_ctrl_c_at_the_prompt_exit_cleanly(out, env, tmp_path, key, message, code):
    import signal

    if key == "\x03" and signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        # a suite started in the background of a non-interactive shell inherits SIGINT ignored, and so does
        # the exercise under test: Python then installs no KeyboardInterrupt handler, and Ctrl-C cannot work
        pytest.skip("SIGINT is ignored in this process (started in the background of a non-interactive shell)")
    t = Terminal(args("ex3", out), env, tmp_path)
    t.expect("Your prediction (a, b, c or d): ")
    t.send("a\n")
    t.expect("Why? One sentence (at least 6 words): ")
    t.send(key)
    if key == "\x03":
        # A SIGINT that lands after the prompt is printed but before input() blocks in read() waits
        # there, unseen, until the read returns (CPython): press Ctrl-C again, as a person would.
        for _ in range(20):
            if not t.alive(1.0):
                break
            t.send(key)
    assert t.wait() == code
    assert message in t.text and "Traceback" not in t.text and store(env) == {}


def test_no_terminal_and_no_flags_says_how_to_run_it(out, env, tmp_path):
    code, stdout, stderr = no_terminal(args("ex1", out), env, tmp_path)
    assert code == 2, (stdout, stderr)
    assert "no terminal to ask for your prediction on" in stderr
    assert "python -m pusht.exercise ex1 --predict LETTER --reason" in stderr
    assert "Traceback" not in stderr and store(env) == {}


def test_an_unknown_exercise_is_refused_with_the_list(out, env, tmp_path):
    code, _, stderr = no_terminal(args("ex9", out), env, tmp_path)
    assert code == 2 and "unknown exercise 'ex9': choose one of ex1, ex2, ex3, ex4" in stderr
    assert "Traceback" not in stderr


@pytest.mark.parametrize("flags,message", [
    (["--predict", "e", "--reason", REASON], "choice must be one of a, b, c, d (a single letter); got 'e'"),
    (["--predict", "b", "--reason", ""], "reason must be one real sentence (at least 6 words)"),
    (["--predict", "b"], "--predict and --reason go together"),
])
def test_bad_flags_are_refused_before_anything_runs(out, env, tmp_path, flags, message):
    code, stdout, stderr = no_terminal(args("ex1", out, *flags), env, tmp_path)
    assert code == 2 and message in stderr, (stdout, stderr)
    assert "Traceback" not in stderr and "[experiment started]" not in stdout and store(env) == {}


# --- an earlier lock is kept --------------------------------------------------------------------------
def test_an_existing_lock_is_shown_and_used_even_without_a_terminal(out, env, tmp_path):
    first = predict.Prediction("ex1", "c", "Zero actions already look rosy in the dream, so drift dominates.",
                               "2026-01-01T00:00:00.000+00:00")
    Path(env["PUSHT_PREDICTIONS"]).write_text(json.dumps({"ex1": asdict(first)}))
    code, stdout, stderr = no_terminal(args("ex1", out, "--predict", "a", "--reason", REASON), env, tmp_path)
    assert code == 0, (stdout, stderr)
    in_order(stdout, "already locked (at 2026-01-01T00:00:00.000+00:00", "(c) No real success",
             "why: Zero actions already look rosy", "(--predict a is not used: the first lock is kept.)",
             "(prediction locked at 2026-01-01T00:00:00.000+00:00)", "Reconcile ex1: you predicted (c)")
    assert "[prediction locked]" not in stdout and store(env) == {"ex1": asdict(first)}


# --- the pieces ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("answer", ["a", "B", "(c)", " d ", "(D)", "e", "", "ab", "(a", "a)", "1", "b."])
def test_the_terminal_reads_a_letter_as_lock_prediction_does(answer, tmp_path, monkeypatch):
    monkeypatch.setenv("PUSHT_PREDICTIONS", str(tmp_path / "p.json"))
    predict._reset_for_tests()
    try:
        predict.lock_prediction("ex1", answer, REASON)
        taken = True
    except ValueError as e:
        assert str(e).startswith("choice"), e
        taken = False
    finally:
        predict._reset_for_tests()
    assert (exercise._letter(answer) in predict.choices_of("ex1")) == taken


def test_help_lists_every_exercise_with_a_line():
    p = subprocess.run([sys.executable, "-m", "pusht.exercise", "--help"], capture_output=True, text=True,
                       cwd=ROOT, timeout=60)
    assert p.returncode == 0
    for name, ex in exercise.EXERCISES.items():
        assert re.search(rf"^  {name}  \S", p.stdout, re.M) and ex.summary.split(":")[0] in p.stdout


def test_the_questions_and_options_are_the_notebooks():
    """The question lines are the solution notebooks' words, and the options their modules' dicts."""
    for ex in exercise.EXERCISES.values():
        cells = json.loads((ROOT / "solutions" / f"{ex.notebook}.ipynb").read_text())["cells"]
        words = " ".join(" ".join("".join(c["source"]).split()) for c in cells if c["cell_type"] == "markdown")
        code = "".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        assert ex.question in words, (ex.name, ex.question)
        assert f"{ex.options_name}.items()" in code and (ex.note_name or "") in code
        note, options = ex.texts()
        assert set(options) == set(predict.choices_of(ex.name))
        assert (ex.note_name is None) == (note == "")
