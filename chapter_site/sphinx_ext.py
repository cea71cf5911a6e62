"""A Sphinx extension for the chapter site's build (book/_config.yml lists it). Five fixes:

* Jupyter Book 1 always loads sphinx-thebe, whose start-up script then lands twice in every
  notebook page (the browser reports "Identifier 'THEBE_JS_URL' has already been declared"). The
  site has no live code (launch_buttons.thebe is false), so thebe's script injection is unhooked.
* Sphinx loads MathJax on a page when the page *or any page in its table of contents* has an
  equation, so the landing page, which has none, paid 1.2 MB of MathJax for the notebooks'. MathJax
  is left out of every page without an equation of its own.
* The theme loads Font Awesome twice: as a web font from its stylesheet (what shows the icons with
  JavaScript off) and as a 1.5 MB script that redraws each icon as SVG, 60% of the landing page's
  weight. Every icon the site uses is in the font, so the script's tag is taken out of every page
  and the script out of the build (:func:`drop_fontawesome_script`).
* A notebook's figures are PNGs of 1,000-2,000 px drawn about 360 px wide on a phone, where their
  text is 3 px. Each figure in a notebook's output is wrapped in a link to its own full-resolution
  file (:func:`enlargeable_figures`): a tap opens it, to be zoomed, with JavaScript off too.
* With JavaScript off, the theme hides what needs it (``.pst-js-only``, in a ``<noscript>`` style),
  but not its sidebar toggles, its full-screen button, its back-to-top pill or matplotlib's
  animation player, which are then dead buttons: the same rule hides them too (:data:`NEEDS_SCRIPT`).
"""

from __future__ import annotations

import re
from pathlib import Path

FONTAWESOME_JS = "_static/scripts/fontawesome.js"
# what does nothing without JavaScript, hidden with the theme's own rule when it is off
NEEDS_SCRIPT = (".sidebar-toggle", ".btn-fullscreen-button", "#pst-back-to-top", ".animation")
_NOSCRIPT_RULE = ".pst-js-only { display: none !important; }"
# an output figure as MyST-NB writes it: <img alt="../_images/<hash>.png" src="../_images/<hash>.png" />
_OUTPUT_IMAGE = re.compile(r'<img alt="([^"]*)" src="(\.\./_images/[^"]+)" />')
ENLARGE_TEXT = "Open the figure at full size"
_FONTAWESOME_TAG = re.compile(r'[ \t]*<script[^>]*src="[^"]*_static/scripts/fontawesome\.js[^"]*"[^>]*></script>\n?')


def _mathjax(js) -> bool:
    text = str(getattr(js, "filename", None) or js) + str(getattr(js, "attributes", {}).get("body", ""))
    return "mathjax" in text.lower()


def _no_mathjax_without_math(app, pagename, templatename, context, doctree):
    if app.env.get_domain("math").data.get("has_equations", {}).get(pagename):
        return
    scripts = context.get("script_files")
    if isinstance(scripts, list):
        scripts[:] = [js for js in scripts if not _mathjax(js)]


def drop_fontawesome_script(outdir: Path) -> int:
    """Take the theme's Font Awesome script out of every page under ``outdir`` and out of the build
    (the icons stay: the theme's stylesheet draws them with the font). Returns the pages changed."""
    changed = 0
    for page in Path(outdir).rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        new = _FONTAWESOME_TAG.sub("", text)
        if new != text:
            page.write_text(new, encoding="utf-8")
            changed += 1
    for f in Path(outdir).glob(FONTAWESOME_JS + "*"):       # the script, its licence and its map
        f.unlink()
    return changed


def enlargeable_figures(html: str) -> str:
    """Each notebook output figure in ``html`` wrapped in a link to its own file, titled so."""
    return _OUTPUT_IMAGE.sub(lambda m: f'<a class="figure-full" href="{m.group(2)}" title="{ENLARGE_TEXT}">'
                                       f'<img alt="{m.group(1)}" src="{m.group(2)}" /></a>', html)


def no_dead_buttons(html: str) -> str:
    """The theme's rule for JavaScript off (``.pst-js-only`` hidden) extended to :data:`NEEDS_SCRIPT`."""
    return html.replace(_NOSCRIPT_RULE, ", ".join((".pst-js-only",) + NEEDS_SCRIPT) + " { display: none !important; }")


def finish_pages(outdir: Path) -> int:
    """The edits made to every built page: figures enlargeable (notebook pages), no dead button
    with JavaScript off. Returns the pages changed."""
    changed = 0
    for page in Path(outdir).rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        new = no_dead_buttons(text)
        if page.parent.name == "notebooks":
            new = enlargeable_figures(new)
        if new != text:
            page.write_text(new, encoding="utf-8")
            changed += 1
    return changed


def _after_build(app, exception):
    if exception is None and app.builder.format == "html":
        drop_fontawesome_script(Path(app.outdir))
        finish_pages(Path(app.outdir))


def setup(app):
    for listener in list(app.events.listeners.get("env-before-read-docs", [])):
        if getattr(listener.handler, "__module__", "") == "sphinx_thebe":
            app.disconnect(listener.id)
    app.connect("html-page-context", _no_mathjax_without_math, priority=900)   # after sphinx.ext.mathjax's
    app.connect("build-finished", _after_build)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
