"""A Sphinx extension for the chapter site's build (book/_config.yml lists it): Jupyter Book 1
always loads sphinx-thebe, whose start-up script then lands twice in every notebook page (the
browser reports "Identifier 'THEBE_JS_URL' has already been declared"). The site has no live
code (launch_buttons.thebe is false), so this unhooks thebe's script injection altogether."""

from __future__ import annotations


def setup(app):
    for event in ("env-before-read-docs",):
        for listener in list(app.events.listeners.get(event, [])):
            if getattr(listener.handler, "__module__", "") == "sphinx_thebe":
                app.disconnect(listener.id)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
