"""The chapter as a static site (``make site``): a landing page in the chapter page's form, one page
per executed notebook and the reading list, built with Jupyter Book 1.x from a ``make chapter`` run.

Rooms: ``scrubber`` (the iteration scrubber's data, exported by ``make chapter``), ``svg`` (the
static figures), ``wallclock`` (the tier table), ``colophon`` (fingerprints of the shown code),
``landing`` (the landing page), ``provenance`` (commit and host), ``book`` (assemble and build),
``sphinx_ext`` (a fix to the build).
"""
