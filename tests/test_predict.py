"""Predict-then-run: the experiment refuses to run until a prediction is locked, the first lock is
kept (even across a kernel restart), and the receipts record the order of events."""

import pytest

from pusht import predict


@pytest.fixture(autouse=True)
def fresh_store(tmp_path, monkeypatch):
    monkeypatch.setenv("PUSHT_PREDICTIONS", str(tmp_path / "locks.json"))
    predict._reset_for_tests()
    yield
    predict._reset_for_tests()


REASON = "The model never learned how the block moves, so the dream lies."


def test_experiment_refuses_to_run_without_a_lock():
    with pytest.raises(RuntimeError, match="lock your prediction first"):
        predict.run_exercise("ex1", lambda: 42)
    assert not predict.has_run("ex1")


def test_lock_then_run_prints_receipts_in_order(capsys):
    predict.lock_prediction("ex1", "B", REASON)
    assert predict.run_exercise("ex1", lambda x: x + 1, 41) == 42
    out = capsys.readouterr().out
    assert out.index("[prediction locked] ex1: (b) at ") < out.index("[experiment started] ex1 at ")


@pytest.mark.parametrize("choice, reason, message", [
    ("e", REASON, "choice must be one of a, b, c, d"),
    ("", REASON, "choice must be one of"),
    (None, REASON, "choice must be one of"),
    ("b", "", "one real sentence"),
    ("b", "because", "one real sentence"),
    ("b", "asdf qwer", "one real sentence"),
])
def test_invalid_predictions_are_refused_with_what_is_expected(choice, reason, message):
    with pytest.raises(ValueError, match=message):
        predict.lock_prediction("ex1", choice, reason)
    assert predict.prediction("ex1") is None


def test_the_first_lock_is_kept_even_after_a_kernel_restart(capsys):
    first = predict.lock_prediction("ex2", "a", REASON)
    predict._LOCKS.clear()                      # what a kernel restart forgets
    again = predict.lock_prediction("ex2", "c", "Now that I think about it, it will surely fail.")
    assert again == first and again.choice == "a"
    assert "already locked" in capsys.readouterr().out


def test_reconcile_only_after_the_experiment(capsys):
    predict.lock_prediction("ex1", "b", REASON)
    with pytest.raises(RuntimeError, match="run the experiment first"):
        predict.reconcile("ex1", "b", "...")
    predict.run_exercise("ex1", lambda: None)
    predict.reconcile("ex1", "b", "It did.")
    assert "which matches your prediction" in capsys.readouterr().out


def test_each_exercise_accepts_its_own_letters():
    """Exercise 1 has four options, Exercise 2 three: a "d" is refused for ex2 only."""
    with pytest.raises(ValueError, match="choice must be one of a, b, c;|one of a, b, c \\("):
        predict.lock_prediction("ex2", "d", REASON)
    assert predict.lock_prediction("ex1", "d", REASON).choice == "d"
