"""The feedback pages' exporter: the same document as nbconvert's HTMLExporter, made without its
BeautifulSoup round trip (autograde/feedback_html.py)."""

import sys
from pathlib import Path

import nbformat
import pytest
from bs4 import BeautifulSoup
from nbconvert.exporters import HTMLExporter
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook, new_output
from traitlets.config import Config

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "autograde"))

from feedback_html import ALT_TEXT, FeedbackHTMLExporter, _edit_tags  # noqa: E402

PNG = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==")


def notebook():
    """Images with and without alt text, HTML outputs with the classes nbconvert edits, and the same
    markup inside a comment and a script, where no edit belongs."""
    return new_notebook(cells=[
        new_markdown_cell("# A title\n\n<img src='a.png'> and <IMG SRC=b.png alt=''/> and <img src=\"c.png\" />"),
        new_code_cell("print('hi')", outputs=[new_output("stream", name="stdout", text="hi <img>\n")]),
        new_code_cell("display(x)", outputs=[
            new_output("display_data", data={"image/png": PNG, "text/plain": "<Figure>"}),
            new_output("display_data", data={"text/html": (
                '<div class="jp-OutputArea-output extra" tabindex="-1">student html</div>'
                "<!-- <img src=commented.png> --><script>var s = '<img src=x.png>';</script>"
                "<div class='jp-Cell-inputWrapper'>x</div>")}),
        ]),
    ], metadata={"language_info": {"name": "python", "pygments_lexer": "ipython3"}})


def same_document(a: str, b: str) -> bool:
    return BeautifulSoup(a, "html.parser") == BeautifulSoup(b, "html.parser")


@pytest.mark.parametrize("template", ["lab", "classic"])   # nbgrader's own: tests/test_grading.py
def test_the_page_is_the_document_nbconverts_own_exporter_makes(template):
    config = Config()
    config.HTMLExporter.template_name = template
    nb = notebook()
    theirs, _ = HTMLExporter(config=config).from_notebook_node(nbformat.from_dict(nb))
    ours, _ = FeedbackHTMLExporter(config=config).from_notebook_node(nbformat.from_dict(nb))
    assert same_document(ours, theirs)
    assert ALT_TEXT in ours


def test_the_edits_where_nbconvert_makes_them_and_nowhere_else():
    page = ('<body class="jp-Notebook"><img src="a.png"><img alt="kept" src=b.png>'
            '<div class="jp-Cell-inputWrapper" tabindex=-1>in</div><div class="jp-OutputArea-output">out</div>'
            "<div class=other>x</div><!-- <img src=c.png> --><SCRIPT>'<img src=d.png>'</SCRIPT></body>")
    edited, missing = _edit_tags(page)
    assert missing == 1
    soup = BeautifulSoup(edited, "html.parser")
    assert [img.get("alt") for img in soup.find_all("img")] == [ALT_TEXT, "kept"]
    assert [d.get("tabindex") for d in soup.find_all("div")] == ["0", "0", None]
    assert "<!-- <img src=c.png> -->" in edited and "'<img src=d.png>'" in edited
    # outside .jp-Notebook no div is made focusable (nbconvert's rule)
    assert "tabindex" not in _edit_tags('<div class="jp-OutputArea-output">out</div>')[0]


def test_an_unclosed_comment_or_script_hides_the_rest_of_the_page_as_for_a_parser():
    """A student's output can be anything: an unclosed comment or script runs to the end of the page
    (no edit after it), and thousands of them are scanned once each, not to the end each time
    (20,000 took 13 s in the first version)."""
    head = '<body class="jp-Notebook"><img src=a.png>'
    for opener in ("<!--", "<script>", "<SCRIPT>"):
        page = head + (opener + '<img src=b.png>') * 20000
        edited, missing = _edit_tags(page)
        assert missing == 1 and edited == head.replace("<img src=a.png>", f'<img src=a.png alt="{ALT_TEXT}">') \
            + page[len(head):]
    closed = head + "<script>'<img src=c.png>'</script ><img src=d.png>"
    assert _edit_tags(closed)[1] == 2
