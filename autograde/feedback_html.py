"""The exporter of the feedback pages: nbconvert's HTMLExporter, made safe to open, without its
slowest pass.

**Safe to open.** The pages show a student's notebook, and everything in it is the student's: any
markdown or raw cell, any output's MIME bundle, attachments, metadata, cell ids. Instructors and
students open the pages in a browser, so nothing from the notebook may run there. Two layers:

1. Sanitised, with `nh3 <https://nh3.readthedocs.io>`_ (Ammonia: an HTML5 parser and allow-list
   sanitiser that writes out only what it parsed and allowed). Before rendering, a JavaScript
   output (``application/javascript``) becomes a one-line note, an interactive widget's view too,
   the notebook's widget state is dropped (it only feeds widget scripts), and each HTML output and
   raw cell is sanitised on its own; each markdown cell and markdown output is sanitised as it is
   rendered. So one cell's markup stays inside that cell. The template then renders as nbconvert's
   does, and the page is rebuilt: its ``<head>`` (which nbconvert's and nbgrader's templates write,
   not the student) keeps only the charset and viewport metas, the title as escaped text and the
   template's ``<style>`` sheets, less what they would fetch; the template's ``<script>`` tags
   (require.js, MathJax, mermaid, widgets) are dropped, since they could not run anyway (layer 2).
   Everything from ``<body>`` on, where every cell and output lands, goes through the sanitiser
   again, whole. What it allows is what an honest page needs: no ``<script>``, ``<style>``,
   ``<iframe>``, ``<object>``, ``<embed>``, ``<svg>``, ``<math>``, ``<form>``, ``<input>``,
   ``<meta>``, ``<base>`` or ``<link>`` element, no ``on*`` attribute, links only to http(s),
   mailto or a ``#`` anchor on the page, images only from ``data:image/...`` URLs (an SVG drawn by
   an ``<img>`` runs no script), ``style`` attributes limited to a few properties and without
   ``url(...)``.
2. A Content-Security-Policy, the first element of ``<head>``, that allows no script, no frame,
   no plugin, no form, no ``<base>`` and no network fetch at all: only inline styles and
   ``data:`` images and fonts (:data:`CSP`). A page opened from disk has nothing else to load, so
   MathJax does not typeset LaTeX (it shows as its ``$...$`` source) and widgets are not drawn.

Not nbconvert's own ``HTMLExporter.sanitize_html`` (nbconvert 7.17): it passes markdown and HTML
outputs through bleach with a short list of tags, so an honest page's headings, paragraphs and
images show as escaped markup, while nbgrader's feedback template renders markdown cells and
comments without it, the widget and head scripts stay, and so do the routes the templates write
unescaped (an image's width from the output's metadata, a mermaid diagram).

``tests/test_feedback_html.py`` checks an honest page is nbconvert's document less its scripts;
``tests/test_feedback_browser.py`` renders a hostile notebook, checks its pages' markup, then opens
them in headless Chromium and checks that nothing ran.

**Without its slowest pass.** ``nbconvert.exporters.HTMLExporter`` renders its template and then
parses the whole page with BeautifulSoup (Python's ``html.parser``) and writes it out again, only
to add two accessibility attributes: ``alt`` text on every ``<img>`` that has none, and
``tabindex="0"`` on the input and output areas of a JupyterLab-style page
(``div.jp-Cell-inputWrapper`` and ``div.jp-OutputArea-output`` inside ``.jp-Notebook``). That parse
and rewrite was about half of nbgrader's ``generate_feedback`` time per student
(``benchmarks/grading_wallclock.txt``). :class:`FeedbackHTMLExporter` makes the same two edits
directly on the start tags of the (sanitised) page, leaving every other byte as it was, and never
inside a comment, ``<script>``, ``<style>``, ``<textarea>`` or ``<title>`` (whose contents are text,
as an HTML parser reads them).
"""

from __future__ import annotations

import html as _html
import re
from html.parser import HTMLParser

import nh3
from jinja2 import pass_context
from nbconvert.exporters import HTMLExporter, TemplateExporter
from nbconvert.filters.highlight import Highlight2HTML
from nbconvert.filters.markdown_mistune import IPythonRenderer, MarkdownWithMath
from nbconvert.filters.widgetsdatatypefilter import WidgetsDataTypeFilter

from .feedback_math import Formulas

ALT_TEXT = "No description has been provided for this image"   # nbconvert's own words

# --- layer 2: what the page may load or do ------------------------------------------------------
# A <meta> policy cannot carry frame-ancestors, sandbox or report-uri (browsers ignore them there),
# and no policy can stop a click on a link; the sanitiser lets links go only to http(s), mailto or
# an anchor on the page.
CSP = "; ".join([
    "default-src 'none'",            # no fetch, frame, worker, media, font or image unless listed
    "script-src 'none'",
    "object-src 'none'",
    "style-src 'unsafe-inline'",     # the template's <style> sheets and style="" attributes
    "img-src data:",                 # plots and images are embedded as data: URLs
    "font-src data:",                # a JupyterLab theme embeds its fonts as data: URLs
    "base-uri 'none'",
    "form-action 'none'",
])
CSP_META = f'<meta http-equiv="Content-Security-Policy" content="{CSP}">'

NOTE_JAVASCRIPT = "[a JavaScript output: feedback pages run no script, so it is not shown]"
NOTE_WIDGET = "[an interactive widget: feedback pages run no script, so it is not shown]"
_JAVASCRIPT = ("application/javascript", "text/javascript", "application/x-javascript", "text/ecmascript")
_WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"


# --- layer 1: what of the rendered page is kept -------------------------------------------------
# Ammonia's default tags (text, lists, tables, images, links, headings...) and those nbconvert's
# templates write besides; any other tag is dropped and its text kept (a markdown task list keeps its
# text, not its checkbox: no <input>), except these, whose content goes too (code, or text no
# honest page shows)
_TAGS = set(nh3.ALLOWED_TAGS) | {"main", "section"}
_DROP_WITH_CONTENT = {"script", "style", "template", "iframe", "frame", "frameset", "noscript", "noembed",
                      "noframes", "xmp", "textarea", "title", "svg", "math", "object", "embed", "applet"}
_ATTRIBUTES = {tag: set(attrs) for tag, attrs in nh3.ALLOWED_ATTRIBUTES.items()}
for _tag, _more in {"*": {"class", "id", "title", "lang", "dir", "style", "tabindex", "align"},
                    "a": {"href", "name"}, "img": {"src", "alt", "width", "height"},
                    "table": {"border"}, "ol": {"start", "type"}, "li": {"value"}}.items():
    _ATTRIBUTES.setdefault(_tag, set()).update(_more)
_STYLE_PROPERTIES = {
    "color", "background-color", "text-align", "vertical-align", "font-weight", "font-style", "font-size",
    "font-family", "font-variant", "text-decoration", "white-space", "word-break", "line-height",
    "letter-spacing", "text-indent", "text-transform", "list-style-type", "width", "height", "max-width",
    "min-width", "max-height", "min-height", "padding", "padding-left", "padding-right", "padding-top",
    "padding-bottom", "border", "border-collapse", "border-spacing", "border-color", "border-style",
    "border-width", "border-top", "border-bottom", "border-left", "border-right", "display", "overflow",
    "overflow-x", "overflow-y", "opacity",
}   # nothing that positions an element over the page's own header (position, margin, transform)
_URL_ATTRIBUTES = {"href", "src", "cite", "longdesc", "action", "formaction", "background", "poster", "data"}
# an image's data: URL; base64 that a browser could not decode goes too (it would only log an error)
_IMAGE_DATA_URL = re.compile(r"data:image/(?:png|jpeg|gif|webp|bmp|svg\+xml)(?:;[\w.+-]+=[\w.+-]+)*"
                             r"(?:;base64,[A-Za-z0-9+/\s]*=?\s*=?\s*|,.*)", re.IGNORECASE | re.DOTALL)
_STYLE_FETCHES = re.compile(r"url\s*\(|image-set|image\s*\(|expression|@import|\\|<|javascript:", re.IGNORECASE)


def _keep_attribute(tag: str, name: str, value: str) -> str | None:
    """nh3's last word on an attribute it allows (its URL scheme already checked): ``data:`` only
    as an image's source, and an image's source only ``data:`` (anything else would be a fetch,
    which the policy blocks anyway); no ``style`` that could fetch."""
    if name in _URL_ATTRIBUTES:
        data = value.strip().lower().startswith("data:")
        if tag == "img" and name == "src":
            return value if data and _IMAGE_DATA_URL.fullmatch(value.strip()) else None
        return None if data else value
    if name == "style" and _STYLE_FETCHES.search(value):
        return None
    return value


def _relative_url(url: str) -> str | None:
    """A relative URL is kept only as an anchor on the page itself (``#section``); a page opened
    from disk has nothing else beside it, and ``//host/path`` would reach out."""
    return url if url.startswith("#") else None


_CLEANER = nh3.Cleaner(
    tags=_TAGS, clean_content_tags=_DROP_WITH_CONTENT, attributes=_ATTRIBUTES,
    generic_attribute_prefixes={"data-", "aria-"},
    attribute_filter=_keep_attribute, url_schemes={"http", "https", "mailto", "data"},
    url_relative=_relative_url, filter_style_properties=_STYLE_PROPERTIES, strip_comments=True,
    link_rel=None,      # no target="_blank" survives, so rel=noopener has nothing to guard
)


def sanitize_fragment(fragment: str) -> str:
    """``fragment`` with nothing that can run script or fetch: the sanitiser of everything in a
    feedback page's ``<body>``."""
    return _CLEANER.clean(fragment)


class _Head(HTMLParser):
    """What the template's ``<head>`` holds that a page without scripts still uses."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.lang, self.metas, self.title, self.styles = None, [], None, []
        self._in = None

    def handle_starttag(self, tag, attrs):
        attrs = {k: v or "" for k, v in attrs}
        if tag == "html" and re.fullmatch(r"[A-Za-z]{1,8}(?:-[A-Za-z0-9]{1,8})*", attrs.get("lang", "")):
            self.lang = self.lang or attrs["lang"]
        elif tag == "meta" and re.fullmatch(r"[A-Za-z0-9_-]{1,40}", attrs.get("charset", "")):
            self.metas.append(f'<meta charset="{attrs["charset"]}" />')
        elif tag == "meta" and attrs.get("name", "").lower() == "viewport":
            self.metas.append(f'<meta name="viewport" content="{_html.escape(attrs.get("content", ""))}">')
        elif tag == "title" and self.title is None:
            self._in, self.title = "title", []
        elif tag == "style":
            css = attrs.get("type", "").lower() == "text/css"
            self._in = "style"
            self.styles.append(['<style type="text/css">' if css else "<style>"])

    def handle_endtag(self, tag):
        if tag == self._in:
            self._in = None

    def handle_data(self, data):
        if self._in == "title":
            self.title.append(data)
        elif self._in == "style":
            self.styles[-1].append(data)

    def page_head(self) -> str:
        title = "" if self.title is None else f"<title>{_html.escape(''.join(self.title), quote=False)}</title>\n"
        # a sheet's text is the template's; it still cannot close its element early, and what it
        # would fetch (the classic template's icon fonts, by paths that lead nowhere beside a
        # feedback page) becomes ``none``, an invalid value there: neither fetched nor blocked
        styles = "".join(s[0] + _FETCH_IN_CSS.sub("none", "".join(s[1:])).replace("</", "<\\/") + "</style>\n"
                         for s in self.styles)
        lang = f' lang="{self.lang}"' if self.lang else ""
        return (f"<!DOCTYPE html>\n<html{lang}>\n<head>\n{CSP_META}\n" + "".join(m + "\n" for m in self.metas)
                + title + styles + "</head>\n")


_FETCH_IN_CSS = re.compile(r"""url\(\s*(?!["']?\s*data:)(?:"[^"]*"|'[^']*'|[^)]*)\s*\)""", re.IGNORECASE)
_BODY_ATTRIBUTES = {"class", "data-jp-theme-light", "data-jp-theme-name"}


def _body_start(page: str) -> re.Match | None:
    """The page's ``<body ...>`` start tag as a browser finds it: the first outside a comment and
    outside the text of a ``<script>``, ``<style>``, ``<textarea>`` or ``<title>``."""
    last = 0
    while True:
        raw = _RAW_START.search(page, last)
        stop = len(page) if raw is None else raw.start()
        for m in _START.finditer(page, last, stop):
            if m.group(1).lower() == "body":
                return m
        if raw is None:
            return None
        last = _raw_end(page, raw)


def safe_page(page: str) -> str:
    """The rendered ``page`` rebuilt: the policy first in a head of the template's metas, title
    and sheets; the body through the sanitiser (layer 1 and 2 of the module's docstring)."""
    body = _body_start(page)
    head = _Head()
    head.feed(page[:body.start()] if body else "")
    head.close()
    if body:
        kept = "".join(f' {a}="{_html.escape(_unquote(v))}"' for a, v in _attrs(body.group(2))
                       if a in _BODY_ATTRIBUTES)
        start, rest = f"<body{kept}>", page[body.end():]
    else:
        start, rest = "<body>", page
    return f"{head.page_head()}{start}\n{sanitize_fragment(rest)}\n</body>\n</html>\n"


def neutralise_notebook(nb) -> None:
    """In place, before rendering: each JavaScript output and widget view becomes a one-line note,
    the widget state goes; each HTML output and raw cell is sanitised on its own, so that its markup
    stays inside its own cell (an unclosed ``<style>`` or a stray ``</div></main>`` in one output no
    longer swallows or breaks out of the cells after it), and a mermaid diagram's source shows as
    text. Markdown is sanitised the same way as it is rendered (:meth:`FeedbackHTMLExporter.markdown2html`).
    """
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "raw":
            cell["source"] = sanitize_fragment(_text(cell.get("source", "")))
        for output in cell.get("outputs", []) if isinstance(cell.get("outputs"), list) else []:
            data = output.get("data") if isinstance(output, dict) else None
            if not isinstance(data, dict):
                continue
            if any(k in data for k in _JAVASCRIPT):
                output["data"] = data = {"text/plain": NOTE_JAVASCRIPT}
            elif _WIDGET_VIEW in data:
                output["data"] = data = {"text/plain": NOTE_WIDGET}
            if "text/html" in data:
                data["text/html"] = sanitize_fragment(_text(data["text/html"]))
            if "text/vnd.mermaid" in data:
                data["text/vnd.mermaid"] = _html.escape(_text(data["text/vnd.mermaid"]), quote=False)
    if isinstance(nb.get("metadata"), dict):
        nb["metadata"].pop("widgets", None)


def _text(value) -> str:
    """A notebook's multi-line string, which nbformat may still hold as a list of lines."""
    return "".join(map(str, value)) if isinstance(value, list) else str(value)


# --- nbconvert's accessibility edits, on the start tags ------------------------------------------
# comments and text-only elements: what they hold is never a tag. Only their start is matched by a
# pattern; their end is searched for from there, once, so a page full of unclosed ones (a student's
# output can be anything) stays linear to scan; an unclosed one runs to the end, as for an HTML parser.
_RAW_START = re.compile(r"<!--|<(script|style|textarea|title)\b", re.IGNORECASE)
_VALUE = r"""(?:"[^"]*"|'[^']*'|[^\s"'=<>`]+)"""
_ATTR = re.compile(rf"""([^\s"'>/=]+)(?:\s*=\s*({_VALUE}))?""")
_START = re.compile(rf"""<([a-zA-Z][a-zA-Z0-9]*)((?:\s+[^\s"'>/=]+(?:\s*=\s*{_VALUE})?)*)\s*(/?)>""")


def _raw_end(html: str, raw: re.Match) -> int:
    """Where the comment or text-only element that starts at ``raw`` ends."""
    if raw.group(1) is None:
        close = html.find("-->", raw.end())
        return len(html) if close < 0 else close + 3
    close = re.compile(rf"</{raw.group(1)}\s*>", re.IGNORECASE).search(html, raw.end())
    return len(html) if close is None else close.end()


def _attrs(text: str) -> list[tuple[str, str | None]]:
    return [(m.group(1).lower(), m.group(2)) for m in _ATTR.finditer(text)]


def _unquote(value: str | None) -> str:
    if value is None:
        return ""
    return value[1:-1] if value[:1] in "\"'" and value[-1:] == value[:1] and len(value) > 1 else value


def _classes(attrs) -> set[str]:
    return {c for name, value in attrs if name == "class" for c in _unquote(value).split()}


def _edit_tags(html: str) -> tuple[str, int]:
    """The page with nbconvert's two accessibility edits made; and how many images lacked alt text.

    Which divs are inside ``.jp-Notebook`` is decided from the start of the first element that
    has that class onwards: in nbconvert's pages it is ``<body>`` or ``<main>``, which hold every
    cell (a page without one, such as nbgrader's feedback template, gets no tabindex, as with
    nbconvert)."""
    missing_alt = 0
    inside = False

    def edit(m: re.Match) -> str:
        nonlocal missing_alt, inside
        name = m.group(1).lower()
        attrs = _attrs(m.group(2))
        classes = _classes(attrs)
        if "jp-Notebook" in classes:
            inside = True
        if name == "img" and not any(a == "alt" for a, _ in attrs):
            missing_alt += 1
            return f'{m.group(0)[:m.start(3) - m.start(0)].rstrip()} alt="{ALT_TEXT}"{m.group(3)}>'
        if name == "div" and inside and classes & {"jp-Cell-inputWrapper", "jp-OutputArea-output"}:
            kept = "".join(f" {a}" if v is None else f" {a}={v}" for a, v in attrs if a != "tabindex")
            return f'<{m.group(1)}{kept} tabindex="0"{m.group(3)}>'
        return m.group(0)

    out, last = [], 0
    while (raw := _RAW_START.search(html, last)) is not None:
        end = _raw_end(html, raw)
        out.append(_START.sub(edit, html[last:raw.start()]))
        out.append(html[raw.start():end])
        last = end
    out.append(_START.sub(edit, html[last:]))
    return "".join(out), missing_alt


class _MathMLRenderer(IPythonRenderer):
    """nbconvert's markdown renderer, each formula held for MathML instead of left as ``$...$``."""

    def __init__(self, formulas: Formulas, **kw):
        super().__init__(**kw)
        self.formulas = formulas

    def block_math(self, body: str) -> str:
        return self.formulas.hold(body, display=True)

    def inline_math(self, body: str) -> str:
        return self.formulas.hold(body, display=False)

    def latex_environment(self, name: str, body: str) -> str:
        return self.formulas.hold(f"\\begin{{{name}}}{body}\\end{{{name}}}", display=True)


# --- a page a student reads on a phone (issue 42) -------------------------------------------------
# The template (nbgrader's, on nbconvert's classic) sets no viewport, so a phone lays it out 980 px
# wide and shrinks it; its prompts take 21ex of a 390 px screen; its <pre> never wraps, so the
# grader's hint ran off the screen. These rules come after the template's sheets.
VIEWPORT = '<meta name="viewport" content="width=device-width, initial-scale=1">'
PHONE_CSS = """<style type="text/css">
body { font-size: 16px; line-height: 1.5; }
.container { max-width: 100%; }
div.output_area pre, div.output_subarea pre, div.output_text pre { white-space: pre-wrap; overflow-wrap: anywhere; }
div.input_area pre, div.highlight pre { overflow-x: auto; }
img { max-width: 100%; height: auto; }
math[display="block"] { overflow-x: auto; overflow-y: hidden; padding: 0.2em 0; }
.image-alt { font-style: italic; }
@media (max-width: 767px) {
  .container { padding-left: 6px; padding-right: 6px; }
  div.prompt { display: none; }
  div.inner_cell, div.output_subarea { max-width: 100%; }
  div.input, div.output_area { flex-direction: column; }
  div.nbgrader_cell .panel-heading { height: auto; }
  .panel-body { padding: 6px; }
}
</style>
"""
# nbgrader's summary names a test "Test cell" (the label of every test): its name is its grade id,
# which the same link carries
_SUMMARY_LABEL = re.compile(r'<a href="#([^"<>]+)">(Test cell|Coding free-response|Written response|Task)</a>')
_IMG = re.compile(r"<img\b([^>]*)>")


def phone_page(page: str) -> str:
    """The sanitised ``page`` made to read on a phone: a viewport and :data:`PHONE_CSS` in its head,
    each test named in the summary, and an image with no source left (a remote one: Colab's and
    Binder's badges) shown as its alternative text, so a badge link reads as a text link."""
    head_end = page.find("</head>")
    if head_end >= 0:
        extra = ("" if 'name="viewport"' in page[:head_end] else VIEWPORT + "\n") + PHONE_CSS
        page = page[:head_end] + extra + page[head_end:]

    def named(m):
        name = _html.escape(_html.unescape(m.group(1)))
        return f'<a href="#{m.group(1)}">{m.group(2)}: <code>{name}</code></a>'

    def image(m):
        attrs = dict(_attrs(m.group(1)))
        if "src" in attrs:
            return m.group(0)
        alt = _html.escape(_html.unescape(_unquote(attrs.get("alt"))), quote=False) or "an image"
        return f'<span class="image-alt">{alt}</span>'
    body = page.find("<body")
    return page[:body] + _IMG.sub(image, _SUMMARY_LABEL.sub(named, page[body:]))


class FeedbackHTMLExporter(HTMLExporter):
    """``HTMLExporter`` (same configuration, template and filters) whose page runs no script: the
    notebook's JavaScript and widgets become notes, the page is sanitised and carries a policy that
    forbids scripts (:func:`safe_page`); its accessibility edits are made on the page's tags instead
    of through a BeautifulSoup round trip."""

    _formulas: Formulas | None = None

    @pass_context
    def markdown2html(self, context, source):
        """Markdown rendered as nbconvert renders it (its raw HTML included), its math held as
        placeholders for MathML (:mod:`autograde.feedback_math`), then sanitised on its own: a
        cell's markup stays inside the cell."""
        cell = context.get("cell", {})
        renderer = _MathMLRenderer(
            self._formulas if self._formulas is not None else Formulas(),
            escape=False, attachments=cell.get("attachments", {}), embed_images=self.embed_images,
            path=context.get("resources", {}).get("metadata", {}).get("path", ""),
            anchor_link_text=self.anchor_link_text, exclude_anchor_links=self.exclude_anchor_links,
            **self.lexer_options)
        return sanitize_fragment(MarkdownWithMath(renderer=renderer).render(source))

    def _preprocess(self, nb, resources):
        # after nbconvert's own copy and the configured preprocessors (nbgrader's GetGrades...)
        nb, resources = super()._preprocess(nb, resources)
        neutralise_notebook(nb)
        return nb, resources

    def from_notebook_node(self, nb, resources=None, **kw):
        langinfo = nb.metadata.get("language_info", {})
        lexer = langinfo.get("pygments_lexer", langinfo.get("name", None))
        resources = self._init_resources(resources)
        # the two filters HTMLExporter registers before it renders
        self.register_filter("highlight_code",
                             self.filters.get("highlight_code", Highlight2HTML(pygments_lexer=lexer, parent=self)))
        self.register_filter("filter_data_type",
                             WidgetsDataTypeFilter(notebook_metadata=self._nb_metadata, parent=self,
                                                   resources=resources))
        self._formulas = Formulas()                 # a new secret for each page
        try:
            html, resources = TemplateExporter.from_notebook_node(self, nb, resources, **kw)
            html, missing_alt = _edit_tags(phone_page(safe_page(html)))
            html = self._formulas.put_back(html)
        finally:
            self._formulas = None
        if missing_alt:
            self.log.warning("Alternative text is missing on %s image(s).", missing_alt)
        return html, resources
