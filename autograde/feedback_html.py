"""The exporter of the feedback pages: nbconvert's HTMLExporter without its slowest pass.

``nbconvert.exporters.HTMLExporter`` renders its template and then parses the whole page with
BeautifulSoup (Python's ``html.parser``) and writes it out again, only to add two accessibility
attributes: ``alt`` text on every ``<img>`` that has none, and ``tabindex="0"`` on the input and
output areas of a JupyterLab-style page (``div.jp-Cell-inputWrapper`` and
``div.jp-OutputArea-output`` inside ``.jp-Notebook``). That parse and rewrite was about half of
nbgrader's ``generate_feedback`` time per student (``benchmarks/grading_wallclock.txt``).

:class:`FeedbackHTMLExporter` renders the same template with the same filters and makes the same
two edits directly on the start tags of the page, leaving every other byte as the template wrote
it, and never inside a comment, ``<script>``, ``<style>``, ``<textarea>`` or ``<title>`` (whose contents are
text, as an HTML parser reads them). ``tests/test_feedback_html.py`` checks that the page parses
to the same document as nbconvert's own.
"""

from __future__ import annotations

import re

from nbconvert.exporters import HTMLExporter, TemplateExporter
from nbconvert.filters.highlight import Highlight2HTML
from nbconvert.filters.widgetsdatatypefilter import WidgetsDataTypeFilter

ALT_TEXT = "No description has been provided for this image"   # nbconvert's own words

# comments and text-only elements: what they hold is never a tag. Only their start is matched by a
# pattern; their end is searched for from there, once, so a page full of unclosed ones (a student's
# output can be anything) stays linear to scan; an unclosed one runs to the end, as for an HTML parser.
_RAW_START = re.compile(r"<!--|<(script|style|textarea|title)\b", re.IGNORECASE)
_VALUE = r"""(?:"[^"]*"|'[^']*'|[^\s"'=<>`]+)"""
_ATTR = re.compile(rf"""([^\s"'>/=]+)(?:\s*=\s*({_VALUE}))?""")
_START = re.compile(rf"""<([a-zA-Z][a-zA-Z0-9]*)((?:\s+[^\s"'>/=]+(?:\s*=\s*{_VALUE})?)*)\s*(/?)>""")


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
        if raw.group(1) is None:
            close = html.find("-->", raw.end())
            end = len(html) if close < 0 else close + 3
        else:
            close = re.compile(rf"</{raw.group(1)}\s*>", re.IGNORECASE).search(html, raw.end())
            end = len(html) if close is None else close.end()
        out.append(_START.sub(edit, html[last:raw.start()]))
        out.append(html[raw.start():end])
        last = end
    out.append(_START.sub(edit, html[last:]))
    return "".join(out), missing_alt


class FeedbackHTMLExporter(HTMLExporter):
    """``HTMLExporter`` (same configuration, template and filters) whose accessibility edits are
    made on the rendered page's tags instead of through a BeautifulSoup round trip."""

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
        html, resources = TemplateExporter.from_notebook_node(self, nb, resources, **kw)
        html, missing_alt = _edit_tags(html)
        if missing_alt:
            self.log.warning("Alternative text is missing on %s image(s).", missing_alt)
        return html, resources
