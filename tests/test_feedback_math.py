"""Math on the feedback pages (autograde/feedback_math.py) and the page's summary (autograde/feedback.py):
LaTeX drawn as MathML when the page is made, written from an allow-list, so it needs no script and
carries nothing of the student's but text; the one line a student needs first on the page."""

import re

import nbformat
from nbformat.v4 import new_markdown_cell, new_notebook

from autograde.feedback import install_cell_index, summary_cell
from autograde.feedback_html import FeedbackHTMLExporter
from autograde.feedback_math import ATTRIBUTES, TAGS, Formulas, mathml


def test_a_formula_becomes_mathml_a_browser_draws():
    out = mathml(r"r = -\frac{1}{2}\left(\frac{d}{s_p} + \frac{|\theta|}{s_\theta}\right)", display=True)
    assert out.startswith('<math display="block">') and out.endswith("</math>")
    assert "<mfrac>" in out and "<msub>" in out and "θ" in out
    assert set(re.findall(r"<(\w+)", out)) <= TAGS
    assert set(re.findall(r'(\w+)="', out)) <= ATTRIBUTES


def test_nothing_but_presentation_gets_through():
    out = mathml(r"\href{javascript:alert(1)}{x} < y", display=False)     # latex2mathml writes href="javascript:..."
    assert out.startswith("<math") and "href" not in out and "javascript" not in out and "&lt;" in out
    out = mathml(r"x \text{<img src=x onerror=alert(1)>}", display=False)
    assert "<img" not in out and "&lt;img" in out
    assert "style" not in mathml(r"\style{color:red}{x}", display=False)
    assert mathml(r"\frac{1}{", display=False) == '<code class="tex">$\\frac{1}{$</code>'     # unreadable: as written
    assert mathml("x" * 3000, display=False).startswith('<code class="tex">$x')


def test_placeholders_need_the_pages_secret():
    a, b = Formulas(), Formulas()
    key = a.hold("x^2", display=False)
    assert a.secret != b.secret and a.secret in key
    assert "<msup>" in a.put_back(f"<p>{key}</p>") and b.put_back(f"<p>{key}</p>") == f"<p>{key}</p>"


def test_a_page_shows_math_without_dollars():
    nb = nbformat.from_dict(new_notebook(cells=[new_markdown_cell(
        "The reward $r = -d$, and\n\n$$\\sum_t \\gamma^t r_t$$\n\n`$code$` stays code.")]))
    page, _ = FeedbackHTMLExporter().from_notebook_node(nb)
    body = page[page.find("<body"):]
    assert body.count("<math") == 2 and "$r" not in body and "$$" not in body and "<code>$code$</code>" in body
    assert "MATHML" not in body                                  # every placeholder put back


def test_the_summary_names_each_test_and_puts_the_hint_first():
    cell = summary_cell([("reward_impl_tests", 0, 4, "check 1: de-normalise first (your function raised "
                                                      "ValueError: *bad* `x` $y$)"),
                         ("ex1_prediction", 1, 1, "in order")])
    page, _ = FeedbackHTMLExporter().from_notebook_node(nbformat.from_dict(new_notebook(cells=[cell])))
    body = page[page.find("<body"):]
    assert '<a href="#reward_impl_tests">reward_impl_tests</a>' in body and "0 of 4 points" in body
    assert "de-normalise first (your function raised ValueError: *bad* `x` $y$)" in body   # shown as written
    assert "<math" not in body and "<em>" not in body
    assert '<a href="#ex1_prediction">ex1_prediction</a>' in body and "in order" not in body  # full points: no hint


def test_the_install_cell_is_found_as_the_release_writes_it():
    nb = nbformat.read("notebooks/02_reward.ipynb", as_version=4)
    i = install_cell_index(nb.cells)
    assert i is not None and "google.colab" in nb.cells[i].source
    assert install_cell_index([new_markdown_cell("google.colab")]) is None


def test_the_chapters_math_is_drawn():
    """Notebook 03's lambda-return (the cell a student with a wrong answer reads) and any other
    notebook's math: MathML on the page, no ``$$`` left."""
    from pathlib import Path

    shown = 0
    for path in sorted(Path("solutions").glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        nb.cells = [c for c in nb.cells if c.cell_type == "markdown"]
        page, _ = FeedbackHTMLExporter().from_notebook_node(nb)
        body = page[page.find("<body"):]
        assert "$$" not in body and "MATHML" not in body, path.name
        shown += body.count("<math")
    assert shown >= 1
