"""One colour for each world, everywhere the chapter draws: the notebooks' matplotlib figures, the
optional Rerun recording and the chapter site's SVG charts (``chapter_site/svg.py``).

The dream is purple and reality orange (matplotlib's ``tab:purple`` and ``tab:orange``, the
notebooks' colours from the start, so their figures look as they always did); the target is
green. The same colours work on a light and a dark page: the site draws its text, axes and grid
from the theme's own colours, never from here.
"""

from __future__ import annotations

DREAM = "#9467bd"      # matplotlib's tab:purple
REAL = "#ff7f0e"       # matplotlib's tab:orange
TARGET = "#2ca02c"     # matplotlib's tab:green

WORLD = {"dream": DREAM, "real": REAL}


def rgb(color: str) -> tuple[int, int, int]:
    """``"#9467bd"`` -> ``(148, 103, 189)``: the form Rerun takes."""
    h = color.lstrip("#")
    return int(h[0:2], 16), int(h[2:4], 16), int(h[4:6], 16)
