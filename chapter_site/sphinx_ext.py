"""A Sphinx extension for the chapter site's build (book/_config.yml lists it). Two fixes:

* Jupyter Book 1 always loads sphinx-thebe, whose start-up script then lands twice in every
  notebook page (the browser reports "Identifier 'THEBE_JS_URL' has already been declared"). The
  site has no live code (launch_buttons.thebe is false), so thebe's script injection is unhooked.
* Sphinx loads MathJax on a page when the page *or any page in its table of contents* has an
  equation, so the landing page, which has none, paid 1.2 MB of MathJax for the notebooks'. MathJax
  is left out of every page without an equation of its own.
"""

from __future__ import annotations


def _mathjax(js) -> bool:
    text = str(getattr(js, "filename", None) or js) + str(getattr(js, "attributes", {}).get("body", ""))
    return "mathjax" in text.lower()


def _no_mathjax_without_math(app, pagename, templatename, context, doctree):
    if app.env.get_domain("math").data.get("has_equations", {}).get(pagename):
        return
    scripts = context.get("script_files")
    if isinstance(scripts, list):
        scripts[:] = [js for js in scripts if not _mathjax(js)]


def setup(app):
    for listener in list(app.events.listeners.get("env-before-read-docs", [])):
        if getattr(listener.handler, "__module__", "") == "sphinx_thebe":
            app.disconnect(listener.id)
    app.connect("html-page-context", _no_mathjax_without_math, priority=900)   # after sphinx.ext.mathjax's
    return {"parallel_read_safe": True, "parallel_write_safe": True}
