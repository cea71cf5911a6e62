"""Math on the feedback pages, drawn when the page is made: LaTeX becomes MathML, which the browser
draws itself, so the page needs no script (its policy allows none) and shows no ``$...$`` source.

The LaTeX is the notebook's, and so may be the student's: the converter (`latex2mathml
<https://pypi.org/project/latex2mathml/>`_) writes MathML, which is parsed here as XML and written
out again with only the presentation elements and attributes an equation needs, each attribute's
value a short plain word or length, and every text escaped (``\\href{javascript:...}`` becomes an
``href`` attribute in latex2mathml's output: it never reaches the page). What cannot be converted
shows as its LaTeX source, as text.

The sanitiser of the page (:mod:`autograde.feedback_html`) drops every ``<math>`` it is given, the
student's included. So the exporter's markdown renderer leaves a placeholder for each formula,
named with a secret drawn for the page (:class:`Formulas`), and the MathML replaces the
placeholders once the page is sanitised: a student cannot write a placeholder they cannot name.
"""

from __future__ import annotations

import html
import re
import secrets
import xml.etree.ElementTree as ET

from latex2mathml.converter import convert

# MathML Core's presentation elements (no <maction>, no <semantics> annotations that embed markup)
TAGS = frozenset({"math", "mrow", "mi", "mn", "mo", "ms", "mtext", "mspace", "msub", "msup", "msubsup", "mfrac",
                  "msqrt", "mroot", "mstyle", "mover", "munder", "munderover", "mtable", "mtr", "mtd", "mpadded",
                  "mphantom", "menclose", "merror", "mmultiscripts", "mprescripts", "none"})
ATTRIBUTES = frozenset({"display", "mathvariant", "stretchy", "fence", "form", "separator", "accent", "accentunder",
                        "lspace", "rspace", "largeop", "movablelimits", "symmetric", "minsize", "maxsize",
                        "displaystyle", "scriptlevel", "linethickness", "columnalign", "rowalign",
                        "columnspacing", "rowspacing", "columnlines", "rowlines", "frame", "width", "height",
                        "depth", "notation", "voffset", "rowspan", "columnspan"})
_VALUE = re.compile(r"[A-Za-z0-9 .%+-]{0,64}")
MAX_LATEX = 2_000          # characters of one formula converted; a longer one shows as its source


def _write(element, out: list[str]) -> None:
    tag = element.tag.rsplit("}", 1)[-1]
    keep = tag in TAGS
    if keep:
        attrs = "".join(f' {name}="{value}"' for name, value in sorted(element.attrib.items())
                        if name in ATTRIBUTES and _VALUE.fullmatch(value))
        out.append(f"<{tag}{attrs}>")
    if element.text:
        out.append(html.escape(element.text, quote=False))
    for child in element:
        _write(child, out)
        if child.tail:
            out.append(html.escape(child.tail, quote=False))
    if keep:
        out.append(f"</{tag}>")


def mathml(latex: str, display: bool) -> str:
    """``latex`` as MathML written from the allow-list above; its source as text if it cannot be."""
    source = f"$${latex}$$" if display else f"${latex}$"
    try:
        if len(latex) > MAX_LATEX:
            raise ValueError("too long")
        root = ET.fromstring(convert(latex, display="block" if display else "inline"))
    except Exception:  # noqa: BLE001 - any LaTeX the converter cannot read shows as written
        return f'<code class="tex">{html.escape(source, quote=False)}</code>'
    out: list[str] = []
    _write(root, out)
    return "".join(out)


class Formulas:
    """The formulas of one page: a placeholder for each, named with a secret of the page."""

    def __init__(self):
        self.secret = secrets.token_hex(8)
        self.found: dict[str, str] = {}

    def hold(self, latex: str, display: bool) -> str:
        """The placeholder that stands for ``latex`` until :meth:`put_back`."""
        key = f"MATHML{self.secret}N{len(self.found)}E"
        self.found[key] = mathml(latex, display)
        return key

    def put_back(self, page: str) -> str:
        """``page`` with each placeholder replaced by its formula's MathML."""
        if not self.found:
            return page
        return re.sub(rf"MATHML{self.secret}N\d+E", lambda m: self.found.get(m.group(0), ""), page)
