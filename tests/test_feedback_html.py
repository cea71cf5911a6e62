"""The feedback pages' exporter (autograde/feedback_html.py): nbconvert's HTMLExporter's document,
made without its BeautifulSoup round trip, less what could run or fetch (its scripts; the page is
sanitised and carries a Content-Security-Policy: tests/test_feedback_browser.py checks that no
student's markup runs)."""

import re
from pathlib import Path

import nbformat
import pytest
from bs4 import BeautifulSoup, Comment, Doctype
from nbconvert.exporters import HTMLExporter
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook, new_output
from traitlets.config import Config

from autograde.feedback_html import ALT_TEXT, CSP, PHONE_CSS, FeedbackHTMLExporter, _edit_tags

PHONE_STYLE = PHONE_CSS.split(">", 1)[1].rsplit("</style>", 1)[0].strip()

ROOT = Path(__file__).resolve().parents[1]


PNG = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==")
IMG = f"data:image/png;base64,{PNG}"


def notebook():
    """Images with and without alt text, HTML outputs with the classes nbconvert edits, and the same
    markup inside a comment and a script, where no edit belongs (the sanitiser then drops both); a
    remote badge, IPython's highlighted code and an ANSI-coloured traceback."""
    return new_notebook(cells=[
        new_markdown_cell(f"# A title\n\n<img src='{IMG}'> and <IMG SRC={IMG} alt=''/> and <img src=\"{IMG}\" />\n\n"
                          "[![Open In Colab](https://colab.research.google.com/assets/colab-badge.svg)](https://colab.research.google.com/)"),
        new_code_cell("print('hi')", outputs=[new_output("stream", name="stdout", text="hi <img>\n")]),
        new_code_cell("display(x)", outputs=[
            new_output("display_data", data={"image/png": PNG, "text/plain": "<Figure>"}),
            new_output("display_data", data={"text/html": (
                '<div class="jp-OutputArea-output extra" tabindex="-1">student html</div>'
                "<!-- <img src=commented.png> --><script>var s = '<img src=x.png>';</script>"
                "<div class='jp-Cell-inputWrapper'>x</div>")}),
            new_output("display_data", data={"text/html": (      # IPython's Code display
                "<style>pre { line-height: 125%; } .output_html .kn { color: #008000 }</style>"
                '<div class="highlight"><pre><span class="kn">import</span> <span class="nn">os</span></pre></div>')}),
        ]),
        new_code_cell("1 / 0", outputs=[new_output("error", ename="ZeroDivisionError", evalue="division by zero",
                                                   traceback=["\x1b[0;31mZeroDivisionError\x1b[0m: division by zero",
                                                              "\x1b[38;5;208mcolour 208\x1b[0m \x1b[1;32mbold\x1b[0m"])]),
    ], metadata={"language_info": {"name": "python", "pygments_lexer": "ipython3"}})


def exporter_config(template: str):
    """nbconvert's lab or classic template, or nbgrader's feedback template configured as
    nbgrader's GenerateFeedback configures the exporter."""
    if template == "feedback":
        from nbgrader.converters import GenerateFeedback
        from nbgrader.coursedir import CourseDirectory

        return GenerateFeedback(coursedir=CourseDirectory(root=str(ROOT))).config
    config = Config()
    config.HTMLExporter.template_name = template
    return config


def resources(template: str) -> dict:
    # what nbgrader's converter and GetGrades give the feedback template
    return {"nbgrader": {"notebook": "02_reward", "score": 1.0, "max_score": 2.0, "late_penalty": 0}} \
        if template == "feedback" else {}


def comparable(page: str, ours: bool) -> BeautifulSoup:
    """The page as a document, less what a feedback page leaves out: scripts, comments, style
    sheets in the body (a student's CSS; the one IPython's ``Code`` display brings repeats the
    template's own highlighting), images that are not embedded (the Colab and Binder badges; the
    policy would block them), the whitespace between elements and in ``style`` attributes, what the
    head's sheets would fetch (``url(...)``, ``none`` in ours);
    a second ``<body>`` (nbgrader's template nests nbconvert's body in its own, which a browser
    merges into the first) is unwrapped. Ours must start its head with the policy, which goes too,
    and may add a viewport and the phone's sheet (``phone_page``), which go too; the image that is
    not embedded shows as its alternative text in ours, and so it is made in theirs."""
    soup = BeautifulSoup(page, "html.parser")
    if ours:
        policy = soup.head.find(True)
        assert (policy.name, policy.get("http-equiv"), policy.get("content")) == \
            ("meta", "Content-Security-Policy", CSP), policy
        policy.extract()
        for style in soup.head.find_all("style"):
            if style.string and style.string.strip() == PHONE_STYLE:
                style.extract()
    for meta in soup.head.find_all("meta", attrs={"name": "viewport"}):
        meta.extract()
    for body in soup.find_all("body")[1:]:
        body.unwrap()
    for element in soup.find_all(["script", "style"]):
        if element.name == "script" or element.find_parent("head") is None:
            element.extract()
    for img in soup.find_all("img"):
        if not img.get("src", "").startswith("data:image/"):
            alt = soup.new_tag("span", attrs={"class": "image-alt"})
            alt.string = img.get("alt") or "an image"
            img.replace_with(alt)
    for text in soup.find_all(string=True):
        if isinstance(text, Comment) or (not isinstance(text, Doctype) and not text.strip()):
            text.extract()
    for style in soup.head.find_all("style"):
        style.string = re.sub(r"url\([^)]*\)|\bnone\b", "", style.string or "")
    for a in soup.find_all("a", href=True):          # ours names each test in nbgrader's summary
        if ours and a.code and a.get_text().split(":")[0] in SUMMARY_LABELS:
            a.string = a.get_text().split(":")[0]
    for element in soup.find_all(style=True):        # the sanitiser writes declarations without spaces
        element["style"] = re.sub(r"\s+", "", element["style"]).rstrip(";")
    return soup


def same_document_made_safe(ours: str, theirs: str) -> bool:
    """``ours`` (FeedbackHTMLExporter's page) is ``theirs`` (nbconvert's HTMLExporter's, on the
    same honest notebook and configuration) less its scripts and what else :func:`comparable`
    leaves out, under a Content-Security-Policy."""
    return comparable(ours, True) == comparable(theirs, False)


@pytest.mark.parametrize("template", ["lab", "classic", "feedback"])   # nbgrader's own: tests/test_grading.py
def test_the_page_is_nbconverts_document_made_safe(template):
    config = exporter_config(template)
    nb = notebook()
    theirs, _ = HTMLExporter(config=config).from_notebook_node(nbformat.from_dict(nb), resources=resources(template))
    ours, _ = FeedbackHTMLExporter(config=config).from_notebook_node(nbformat.from_dict(nb),
                                                                     resources=resources(template))
    assert same_document_made_safe(ours, theirs)
    assert ALT_TEXT in ours
    assert "<script" in theirs and "<script" not in ours and "<!--" not in ours
    assert '<span class="kn">import</span>' in ours and "colab-badge.svg" not in ours and "Open In Colab" in ours
    assert re.search(r'<span style="color: ?rgb\(255, ?135, ?0\)">colour 208</span>', ours)   # ANSI colour 208


SUMMARY_LABELS = {"Test cell", "Coding free-response", "Written response", "Task"}


def test_the_chapters_own_notebooks_give_nbconverts_documents_made_safe(monkeypatch):
    """Every markdown cell and answer of the notebooks, through nbgrader's template (their graded
    cells given a score and a comment, as GetGrades gives them). Their math is compared as
    nbconvert leaves it (``$...$``): ours draws it as MathML (tests/test_feedback_math.py)."""
    from nbconvert.filters.markdown_mistune import IPythonRenderer

    from autograde.feedback_html import _MathMLRenderer
    for name in ("block_math", "inline_math", "latex_environment"):
        monkeypatch.setattr(_MathMLRenderer, name, getattr(IPythonRenderer, name))
    config = exporter_config("feedback")
    for path in sorted((ROOT / "solutions").glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        for cell in nb.cells:
            meta = cell.metadata.get("nbgrader", {})
            if meta.get("grade") or meta.get("task"):
                meta.update(score=0.5, points=meta.get("points", 1), comment="Good, *but* see `x`.")
        theirs, _ = HTMLExporter(config=config).from_notebook_node(nb, resources=resources("feedback"))
        ours, _ = FeedbackHTMLExporter(config=config).from_notebook_node(nb, resources=resources("feedback"))
        assert same_document_made_safe(ours, theirs), path.name


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
