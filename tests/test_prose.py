"""The notebooks' fixed prose (``pusht/nb/text/*.md``, read by ``pusht.nb.prose``): every file reads,
every question's answer is one of its options, each notebook asks exactly the questions its file
holds, a malformed file names its line, and however a paragraph is wrapped it reads the same."""

from __future__ import annotations

import json
import random
import re
from pathlib import Path

import pytest

from pusht.nb import prose
from pusht.selfcheck import Question

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
MARKERS = ("#", "-", "Answer:", "Why:", "<!--")
ASKED = re.compile(r'SELF_CHECKS\[\\?"(\w+)\\?"\]')


def test_each_notebook_has_one_text_file_and_no_other_file_is_there():
    files = sorted(p.stem for p in prose.TEXT.glob("*.md") if p.name != "README.md")
    assert len(NOTEBOOKS) == 7 and files == NOTEBOOKS


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_every_file_parses_and_every_answer_is_among_its_options(notebook):
    questions = prose.self_checks(notebook)
    assert len(questions) >= 3
    for name, q in questions.items():
        assert isinstance(q, Question) and q.text and q.why, name
        assert q.answer in q.options and list(q.options) == list("abcdefgh"[:len(q.options)]), name
        assert all(isinstance(v, str) and v == v.strip() and "\n" not in v and "  " not in v
                   for v in [q.text, q.why, *q.options.values()]), name


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_each_notebook_asks_exactly_the_questions_its_file_holds(notebook):
    for folder in ("notebooks", "solutions"):
        asked = set(ASKED.findall((ROOT / folder / f"{notebook}.ipynb").read_text()))
        assert asked == set(prose.self_checks(notebook)), (folder, notebook)


def test_the_moved_constants_are_loaded_from_the_files_under_their_old_names():
    from pusht.nb import (actor, closing, closing_exercise, gap, gap_exercise, horizon, horizon_exercise,
                          horizon_words, reward, world_model)
    from pusht.stats import MIN_REWARD_EFFECT

    for module, notebook in [(world_model, "01_world_model"), (reward, "02_reward"), (actor, "03_imagination_actor"),
                             (gap, "04_imagination_gap"), (horizon, "05_horizon"), (closing, "06_closing_the_gap")]:
        assert isinstance(module.SELF_CHECKS, dict) and module.SELF_CHECKS == prose.self_checks(notebook)
    for options, letters in [(gap_exercise.EX1_OPTIONS, "abcd"), (horizon_exercise.EX2_OPTIONS, "abc"),
                             (closing_exercise.EX3_OPTIONS, "abcd")]:
        assert isinstance(options, dict) and list(options) == list(letters) and all(options.values())
    assert gap.EX1_OPTIONS is gap_exercise.EX1_OPTIONS and horizon.EX2_OPTIONS is horizon_exercise.EX2_OPTIONS
    assert closing.EX3_OPTIONS is closing_exercise.EX3_OPTIONS and closing.EX3_NOTE is closing_exercise.EX3_NOTE
    # the numbers are filled in from the constants, and no placeholder is left anywhere
    assert f"({MIN_REWARD_EFFECT:.3f} per step)" in horizon_exercise.EX2_OPTIONS["c"]
    assert f"**{MIN_REWARD_EFFECT:.3f} reward per step**" in horizon_exercise.EX2_RULE
    assert f"matters, {MIN_REWARD_EFFECT:.2f} reward per step" in closing_exercise.EX3_NOTE
    everything = json.dumps([horizon_exercise.EX2_RULE, closing_exercise.EX3_NOTE, horizon_words.ERROR_BAR_SCOPE,
                             gap_exercise.EX1_OPTIONS, horizon_exercise.EX2_OPTIONS, closing_exercise.EX3_OPTIONS])
    assert "{{" not in everything and "}}" not in everything


def write(tmp_path: Path, text: str, name: str = "nb.md") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


GOOD = """<!-- a comment
over two lines -->
# Self-check: q1
What is it?
- (a) One
- (b) Two
Answer: b
Why: Because.
"""

# (the file, the line the error must name, words the message must hold)
MALFORMED = {
    "unknown section": (GOOD + "# Quiz: q2\nText.\n", 9, "unknown section 'Quiz'"),
    "not a heading": (GOOD + "## Note: n\nText.\n", 9, "a heading is"),
    "option without a letter": (GOOD.replace("- (b) Two", "- Two"), 6, "option without a letter"),
    "option without text": (GOOD.replace("- (b) Two", "- (b)"), 6, "has no text"),
    "options out of order": (GOOD.replace("- (b) Two", "- (c) Two"), 6, "(b) comes next"),
    "missing Answer": (GOOD.replace("Answer: b\nWhy: Because.\n", ""), 3, "no Answer: line"),
    "missing Why": (GOOD.replace("Why: Because.\n", ""), 3, "no Why: line"),
    "answer not among options": (GOOD.replace("Answer: b", "Answer: c"), 7, "not among the options"),
    "answer not a letter": (GOOD.replace("Answer: b", "Answer: (b)"), 7, "one letter"),
    "duplicate ids": (GOOD + "\n" + GOOD.split("-->\n", 1)[1], 10, "duplicate section"),
    "one option": (GOOD.replace("- (b) Two\n", "").replace("Answer: b", "Answer: a"), 3, "fewer than two"),
    "text before any section": ("Hello.\n" + GOOD, 1, "before the first section"),
    "option in a note": ("# Note: n\nText.\n- (a) One\n", 3, "one paragraph"),
    "text in options": ("# Options: ex\nText.\n- (a) One\n- (b) Two\n", 2, "holds only options"),
    "answer in options": ("# Options: ex\n- (a) One\n- (b) Two\nAnswer: a\n", 4, "belongs to a Self-check"),
    "a second paragraph": ("# Note: n\nText.\n\nMore text.\n", 4, "text outside a field"),
    "unclosed comment": (GOOD + "<!-- never closed\n", 9, "never closed"),
}


@pytest.mark.parametrize("case", MALFORMED, ids=list(MALFORMED))
def test_a_malformed_file_raises_naming_its_file_and_line(tmp_path, case):
    text, line, words = MALFORMED[case]
    path = write(tmp_path, text)
    with pytest.raises(ValueError) as err:
        prose.parse(path)
    assert str(err.value).startswith(f"{path}:{line}: ") and words in str(err.value), str(err.value)


def test_placeholders_take_exactly_the_values_given(tmp_path):
    path = write(tmp_path, "# Options: ex\n- (a) At least {{x}} per step\n- (b) Less\n\n# Note: n\nA {{x}}, {{y}}.\n")
    assert prose.options("nb", "ex", path=path, x="0.020") == {"a": "At least 0.020 per step", "b": "Less"}
    assert prose.note("nb", "n", path=path, x="1", y="2") == "A 1, 2."
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}:6: \{{\{{y\}}\}} has no value"):
        prose.note("nb", "n", path=path, x="1")
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}:1: .* no placeholder for \['z'\]"):
        prose.options("nb", "ex", path=path, x="1", z="2")
    with pytest.raises(ValueError, match="no section '# Note: missing'"):
        prose.note("nb", "missing", path=path)
    with pytest.raises(ValueError, match=":4: .*has no value"):          # a self-check is given no values
        prose.self_checks("nb", path=write(tmp_path, GOOD.replace("What is it?", "What is {{x}}?"), "q.md"))


def rewrap(rng: random.Random, text: str, first: str, indent: str) -> list[str]:
    """``text`` broken at random spaces; a continuation line indented at random, and always where it
    would begin with a marker (or, for an option, where ``indent`` asks for it)."""
    head, *rest = text.split(" ")
    lines = [first + head]
    for w in rest:
        if rng.random() < 0.3:
            pad = indent or " " * rng.choice([0, 0, 1, 2, 4])
            lines.append((pad or (" " if w.startswith(MARKERS) else "")) + w)
        else:
            lines[-1] += " " + w
    return lines


def words(sections: dict) -> dict:
    """A parsed file's words, line numbers left out."""
    return {key: (s.text and s.text[0], {k: v[0] for k, v in s.options.items()}, s.answer and s.answer[0],
                  s.why and s.why[0]) for key, s in sections.items()}


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_a_paragraph_reads_the_same_however_it_is_wrapped(tmp_path, notebook):
    """Property: every real question, option, reason and note of the file, wrapped at random, parses
    back to the very same string (20 random wrappings of the whole file per notebook)."""
    sections = prose.parse(prose.TEXT / f"{notebook}.md")
    for seed in range(20):
        rng = random.Random(f"{notebook}/{seed}")
        lines = []
        for (kind, name), s in sections.items():
            lines += [f"# {kind}: {name}", *(rewrap(rng, s.text[0], "", "") if s.text else [])]
            for k, (v, _) in s.options.items():
                lines += rewrap(rng, v, f"- ({k}) ", rng.choice(["", "  ", "    ", "\t"]))
            if s.answer:
                lines += [f"Answer: {s.answer[0]}", *rewrap(rng, s.why[0], "Why: ", "")]
            lines += [""] * rng.choice([0, 1, 2])
        path = write(tmp_path, "\n".join(lines) + "\n", f"{seed}.md")
        assert words(prose.parse(path)) == words(sections), seed
    assert prose.self_checks(notebook, path=path) == prose.self_checks(notebook)


def test_a_wrapped_line_that_would_start_a_field_must_be_indented(tmp_path):
    # the rule the property above relies on: unindented, such a line starts a new field
    text = "# Note: n\nA gap of\n- (a) is not an option here.\n"
    with pytest.raises(ValueError, match=":3: a Note holds one paragraph"):
        prose.parse(write(tmp_path, text))
    assert prose.note("nb", "n", path=write(tmp_path, text.replace("\n- (a)", "\n  - (a)"), "ok.md")) == \
        "A gap of - (a) is not an option here."
