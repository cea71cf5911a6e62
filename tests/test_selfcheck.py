"""Self-check questions: an empty answer shows the question, a letter is checked on the spot,
and nothing ever raises in a learner's notebook."""

import pytest

from pusht.selfcheck import Question, ask, render

Q = Question("Which world pays?", {"a": "the dream", "b": "reality"}, "b", "Only reality's reward is real.")


def test_an_empty_answer_shows_the_options_and_asks_for_a_letter():
    text = render(Q, "")
    assert "**(a)** the dream" in text and "Type one of a, b" in text and "Only reality" not in text


def test_a_letter_is_checked_with_the_reason_either_way():
    assert "is right" in render(Q, "b") and "Only reality" in render(Q, "(B)")
    wrong = render(Q, "a")
    assert "Not (a)" in wrong and "the answer is (b)" in wrong and "Only reality" in wrong


def test_a_letter_that_is_not_an_option_is_named_not_raised(capsys):
    assert "'z' is not one of the options" in render(Q, "z")
    ask(Q, "z")                                    # outside Jupyter: printed, never raised
    assert "not one of the options" in capsys.readouterr().out


def test_a_question_whose_answer_is_not_an_option_is_refused():
    with pytest.raises(ValueError, match="not one of the options"):
        Question("?", {"a": "x"}, "b", "")
