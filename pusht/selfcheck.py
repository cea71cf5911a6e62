"""Self-check questions: answered in the notebook and checked on the spot, never graded.

A notebook's questions are written in ``pusht/nb/text/<notebook>.md`` and loaded
(``pusht.nb.prose``) into its support module's ``SELF_CHECKS``, so the notebook shows only the
question; the learner types a letter and runs the cell::

    from pusht.nb.actor import SELF_CHECKS
    ask(SELF_CHECKS["lam_one"], "")      # put your letter between the quotes

An empty answer shows the question and its options; a letter is checked at once, with the reason
shown either way. Nothing is recorded and nothing raises: a self-check never stops a notebook.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Question:
    text: str
    options: dict            # letter -> option text
    answer: str              # the right letter
    why: str                 # shown once the learner has answered

    def __post_init__(self):
        if self.answer not in self.options:
            raise ValueError(f"the answer {self.answer!r} is not one of the options {sorted(self.options)}")


def render(q: Question, given: str = "") -> str:
    """The markdown a learner sees for question ``q`` after answering ``given`` ('' = not yet)."""
    lines = [f"**Self-check.** {q.text}", ""]
    lines += [f"* **({k})** {v}" for k, v in q.options.items()]
    given = str(given).strip().lower().strip("()")
    if not given:
        lines += ["", f"*Type one of {', '.join(q.options)} between the quotes and run the cell again.*"]
    elif given not in q.options:
        lines += ["", f"*{given!r} is not one of the options; type one of {', '.join(q.options)}.*"]
    elif given == q.answer:
        lines += ["", f"✅ **({given}) is right.** {q.why}"]
    else:
        lines += ["", f"❌ **Not ({given}).** Think again, or read on: the answer is ({q.answer}). {q.why}"]
    return "\n".join(lines)


def ask(q: Question, given: str = "") -> None:
    """Show question ``q`` in a notebook, checked against ``given`` if a letter was typed."""
    try:
        from IPython import get_ipython
        from IPython.display import Markdown, display
        if get_ipython() is not None:
            display(Markdown(render(q, given)))
            return
    except ImportError:
        pass
    print(render(q, given))                               # outside Jupyter: plain text
