"""Small static SVG figures for the landing page: they read with JavaScript off and weigh little.

Each function returns one ``<svg>`` element as text. Numbers are escaped as text; nothing here
takes markup from outside. Labels carry units; every chart has labelled axes.

**Colours.** The two worlds are drawn in the chapter's one colour each (:mod:`pusht.palette`, the
notebooks' figures' colours too). Everything else (text, axes, grid, the pusher) is drawn in
``currentColor``, and the page's stylesheet (``book/_static/chapter.css``) sets each chart's
``color`` and its text's ``fill`` from the theme's own variables, so a dark page gets light text
and lines: nothing here names a colour for light or dark.

**Sizes.** A chart is laid out in its own units (``viewBox``) for a phone: the stylesheet draws it
at most :data:`MAX_SCALE` times that wide on a desktop and about 0.85 times on a 390 px phone, so
the smallest text (:data:`TICK`, 13 units) stays at or above 10 px on both. The margins are computed
from the labels' estimated widths, so an axis title never overprints the tick labels beside it
(``tests/test_site_browser.py`` measures both in a browser).
"""

from __future__ import annotations

import math
from html import escape

import numpy as np

from pusht.palette import DREAM, REAL, TARGET

INK = "currentColor"               # text, axes and the pusher: the theme's text colour
TICK, AXIS, LEGEND, NOTE = 13, 14, 14, 13     # font sizes in chart units (book/_static/chapter.css agrees)
MAX_SCALE = 1.2                   # a chart is drawn at most this many px per unit (chapter.css's max-width)
CHAR = 0.62                       # a character's width in em, a safe estimate for the theme's sans-serif
DIGIT = 0.64                      # a digit's (tabular) width in em


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About ``n`` round tick values covering [lo, hi]."""
    if hi <= lo:
        hi = lo + 1.0
    raw = (hi - lo) / max(n - 1, 1)
    mag = 10 ** math.floor(math.log10(raw))
    step = min((s * mag for s in (1, 2, 2.5, 5, 10) if s * mag >= raw), default=10 * mag)
    start = math.floor(lo / step) * step
    return [round(start + i * step, 10) for i in range(int(math.ceil((hi - start) / step)) + 1)]


def _fmt(v: float) -> str:
    return f"{v:g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.1e}"


def text_width(text: str, size: float, em: float = CHAR) -> float:
    """The estimated width of ``text`` at font ``size`` (chart units)."""
    return len(text) * em * size


def _swatch(x: float, y: float, s: dict) -> str:
    """A legend's sample of series ``s``: a short stretch of its line, dashed as the line is, with a
    marker where the line has them."""
    dash = f' stroke-dasharray="{s["dash"]}"' if s.get("dash") else ""
    out = (f'<line class="legend-key" x1="{x:.1f}" x2="{x + 24:.1f}" y1="{y:.1f}" y2="{y:.1f}" stroke="{s["color"]}" '
           f'stroke-width="2.5"{dash}/>')
    if s.get("markers"):
        out += f'<circle cx="{x + 12:.1f}" cy="{y:.1f}" r="3" fill="{s["color"]}"/>'
    return out


def _legend(series: list[dict], x0: float, x1: float) -> tuple[list[str], float]:
    """The legend on top, items wrapped onto as many rows as the width needs. Returns its
    elements and the height it takes."""
    row_h = LEGEND * 1.45
    out, x, row = [], x0, 0
    for s in series:
        w = 24 + 6 + text_width(s["label"], LEGEND)
        if x > x0 and x + w > x1:
            x, row = x0, row + 1
        y = 6 + row * row_h + LEGEND * 0.5
        out.append(_swatch(x, y, s) + f'<text x="{x + 30:.1f}" y="{y + LEGEND * 0.35:.1f}" class="legend" '
                   f'fill="{INK}">{escape(s["label"])}</text>')
        x += w + 18
    return out, 6 + (row + 1) * row_h


def line_chart(series: list[dict], xlabel: str, ylabel: str, title: str, width: int = 400,
               height: int = 300, log_y: bool = False, chart_id: str = "", band: tuple[int, int] | None = None,
               brackets: list[dict] = ()) -> str:
    """A line chart. ``series``: dicts with ``x``, ``y``, ``label``, ``color`` and optionally
    ``markers`` (draw points) and ``dash``. Axes labelled, a legend on top whose samples are drawn
    as the lines are (dashed where a line is). ``band`` (i, j) shades the area between series i and
    j (which share their x), in series i's colour; each of ``brackets`` (dicts ``x``, ``y0``,
    ``y1``, ``label``) is a vertical bracket from y0 to y1 at x, labelled beside it, inwards."""
    xs = np.concatenate([np.asarray(s["x"], float) for s in series])
    ys = np.concatenate([np.asarray(s["y"], float) for s in series])
    if log_y:
        ys = np.log10(np.clip(ys, 1e-12, None))
    x0, x1 = float(xs.min()), float(xs.max())
    pad = 0.06 * (float(ys.max() - ys.min()) or 1.0)
    y0, y1 = float(ys.min()) - pad, float(ys.max()) + pad
    yt = _ticks(y0, y1)
    y0, y1 = min(y0, yt[0]), max(y1, yt[-1])
    xt = _ticks(x0, x1)
    xt = [t for t in xt if x0 <= t <= x1] or [x0, x1]
    ylabels = [_fmt(10 ** t) if log_y else _fmt(t) for t in yt]

    # margins from what they hold: the y title (rotated), a gap, the widest tick label, a gap
    title_x = 4 + 0.8 * AXIS                                    # the rotated title's baseline
    left = math.ceil(title_x + 0.3 * AXIS + 8 + max(text_width(s, TICK, DIGIT) for s in ylabels) + 6)
    right = math.ceil(text_width(_fmt(xt[-1]), TICK, DIGIT) / 2) + 6   # the last x tick label, centred
    legend, top = _legend(series, left, width - right)
    top = math.ceil(top + 10)
    tick_y = TICK * 1.15 + 6                                   # an x tick label's baseline below the axis
    bottom = math.ceil(tick_y + TICK * 0.3 + 8 + AXIS * 1.05)
    pw, ph = width - left - right, height - top - bottom

    def px(x):
        return left + (x - x0) / ((x1 - x0) or 1) * pw

    def py(y):
        return top + (1 - (y - y0) / ((y1 - y0) or 1)) * ph

    out = [f'<svg class="chart" viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}"'
           + (f' id="{chart_id}"' if chart_id else "") + ' xmlns="http://www.w3.org/2000/svg">',
           f"<title>{escape(title)}</title>"]
    for t, label in zip(yt, ylabels):
        out.append(f'<line class="grid" x1="{left}" x2="{left + pw}" y1="{py(t):.1f}" y2="{py(t):.1f}" '
                   f'stroke="{INK}" stroke-opacity="0.15"/>'
                   f'<text x="{left - 6}" y="{py(t) + TICK * 0.35:.1f}" text-anchor="end" class="tick" '
                   f'fill="{INK}">{label}</text>')
    for t in xt:
        out.append(f'<line class="axis-line" x1="{px(t):.1f}" x2="{px(t):.1f}" y1="{top + ph}" y2="{top + ph + 4}" '
                   f'stroke="{INK}" stroke-opacity="0.6"/>'
                   f'<text x="{px(t):.1f}" y="{top + ph + tick_y:.1f}" text-anchor="middle" class="tick" '
                   f'fill="{INK}">{_fmt(t)}</text>')
    out.append(f'<line class="axis-line" x1="{left}" x2="{left + pw}" y1="{top + ph}" y2="{top + ph}" '
               f'stroke="{INK}" stroke-opacity="0.6"/>'
               f'<line class="axis-line" x1="{left}" x2="{left}" y1="{top}" y2="{top + ph}" stroke="{INK}" '
               'stroke-opacity="0.6"/>')
    out.append(f'<text x="{left + pw / 2:.1f}" y="{height - 4 - AXIS * 0.25:.1f}" text-anchor="middle" class="axis" '
               f'fill="{INK}">{escape(xlabel)}</text>'
               f'<text transform="translate({title_x:.1f} {top + ph / 2:.1f}) rotate(-90)" text-anchor="middle" '
               f'class="axis" fill="{INK}">{escape(ylabel)}</text>')
    if band is not None:
        a, b = (series[k] for k in band)
        upper = [f"{px(x):.1f},{py(y):.1f}" for x, y in zip(np.asarray(a["x"], float), np.asarray(a["y"], float))]
        lower = [f"{px(x):.1f},{py(y):.1f}" for x, y in zip(np.asarray(b["x"], float), np.asarray(b["y"], float))]
        out.append(f'<polygon class="band" points="{" ".join(upper + lower[::-1])}" fill="{a["color"]}" '
                   'fill-opacity="0.14" stroke="none"/>')
    for s in series:
        y = np.asarray(s["y"], float)
        y = np.log10(np.clip(y, 1e-12, None)) if log_y else y
        pts = " ".join(f"{px(a):.1f},{py(b):.1f}" for a, b in zip(np.asarray(s["x"], float), y))
        dash = f' stroke-dasharray="{s["dash"]}"' if s.get("dash") else ""
        out.append(f'<polyline class="series" fill="none" stroke="{s["color"]}" stroke-width="2.5"{dash} '
                   f'points="{pts}"/>')
        if s.get("markers"):
            out.extend(f'<circle cx="{p.split(",")[0]}" cy="{p.split(",")[1]}" r="3" fill="{s["color"]}"/>'
                       for p in pts.split())
    for br in brackets:
        x, ya, yb = px(float(br["x"])), py(float(br["y0"])), py(float(br["y1"]))
        inward = 1 if x < left + pw / 2 else -1
        x += 7 * inward                                  # clear of the lines' end markers
        tick = 5 * inward
        out.append(f'<path class="bracket" d="M{x + tick:.1f},{ya:.1f} H{x:.1f} V{yb:.1f} H{x + tick:.1f}" '
                   f'fill="none" stroke="{INK}" stroke-width="1.5"/>'
                   f'<text x="{x + 9 * inward:.1f}" y="{(ya + yb) / 2 + NOTE * 0.35:.1f}" '
                   f'text-anchor="{"start" if inward > 0 else "end"}" class="note" fill="{INK}">'
                   f'{escape(br["label"])}</text>')
    out.extend(legend)
    out.append("</svg>")
    return "".join(out)


def reward_bars(imagined: float, real: float, title: str, width: int = 320, height: int = 250) -> str:
    """The two-worlds headline: imagined and real reward per step as bars hanging from 0 (each
    value above its bar), and the gap between them marked: a dashed line from the imagined bar's
    end to a bracket beside the real bar, labelled. Rewards here are never positive (the best is 0)."""
    lo = min(imagined, real, -0.05)
    yt = [t for t in _ticks(lo, 0.0) if t <= 0]          # the bars hang from 0: no tick above it
    lo = min(lo, yt[0])
    labels = [_fmt(t) for t in yt]
    title_x = 4 + 0.8 * AXIS
    left = math.ceil(title_x + 0.3 * AXIS + 8 + max(text_width(s, TICK, DIGIT) for s in labels) + 6)
    top, bottom = 26, 44
    ph = height - top - bottom

    def py(y):
        return top + (0 - y) / (0 - lo) * ph

    out = [f'<svg class="bars" viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}" '
           'xmlns="http://www.w3.org/2000/svg">', f"<title>{escape(title)}</title>"]
    for t, label in zip(yt, labels):
        out.append(f'<line class="grid" x1="{left}" x2="{width - 8}" y1="{py(t):.1f}" y2="{py(t):.1f}" '
                   f'stroke="{INK}" stroke-opacity="0.15"/>'
                   f'<text x="{left - 6}" y="{py(t) + TICK * 0.35:.1f}" text-anchor="end" class="tick" '
                   f'fill="{INK}">{label}</text>')
    out.append(f'<text transform="translate({title_x:.1f} {top + ph / 2:.1f}) rotate(-90)" text-anchor="middle" '
               f'class="axis" fill="{INK}">reward per step</text>')
    bw, between = 62, 34
    xs = [left + 14, left + 14 + bw + between]
    for x, v, name, where, color in zip(xs, (imagined, real), ("imagined", "real"), ("in the dream", "true PushT"),
                                        (DREAM, REAL)):
        out.append(f'<rect class="bar" x="{x}" y="{py(0):.1f}" width="{bw}" height="{py(v) - py(0):.1f}" '
                   f'fill="{color}"/>'
                   f'<text x="{x + bw / 2}" y="{py(0) - 7:.1f}" text-anchor="middle" class="val" '
                   f'fill="{INK}">{v:+.3f}</text>'
                   f'<text x="{x + bw / 2}" y="{height - 26}" text-anchor="middle" class="legend" '
                   f'fill="{INK}">{name}</text>'
                   f'<text x="{x + bw / 2}" y="{height - 8}" text-anchor="middle" class="tick" '
                   f'fill="{INK}">{where}</text>')
    ya, yb = py(imagined), py(real)
    bx = xs[1] + bw + 7
    out.append(f'<line class="gap-line" x1="{xs[0] + bw}" x2="{bx}" y1="{ya:.1f}" y2="{ya:.1f}" stroke="{INK}" '
               'stroke-width="1.2" stroke-dasharray="4 3"/>'
               f'<path class="bracket" d="M{bx - 4},{ya:.1f} H{bx} V{yb:.1f} H{bx - 4}" fill="none" stroke="{INK}" '
               'stroke-width="1.5"/>'
               f'<text x="{bx + 6}" y="{(ya + yb) / 2 - 3:.1f}" class="note" fill="{INK}">gap</text>'
               f'<text x="{bx + 6}" y="{(ya + yb) / 2 + NOTE + 1:.1f}" class="note" fill="{INK}">'
               f"{imagined - real:+.3f}</text>")
    out.append("</svg>")
    return "".join(out)


from pusht.env import ARENA_HALF  # noqa: E402  (m: the table's walls)


def tee_points(x_mm: float, y_mm: float, yaw_deg: float, scale: float, size: int) -> list[str]:
    """SVG point lists of the T's two boxes at a pose in mm/degrees, in a ``size`` px square
    showing the table (y up)."""
    from pusht.env import tee_outline

    polys = []
    for corners in tee_outline((x_mm / 1000, y_mm / 1000, math.radians(yaw_deg))):
        polys.append(" ".join(f"{(cx + ARENA_HALF) * scale:.1f},{size - (cy + ARENA_HALF) * scale:.1f}"
                              for cx, cy in corners))
    return polys


def path_points(xy_mm, scale: float, size: int) -> str:
    return " ".join(f"{(x / 1000 + ARENA_HALF) * scale:.1f},{size - (y / 1000 + ARENA_HALF) * scale:.1f}"
                    for x, y in xy_mm)


def world_view(world: dict, name: str, color: str, size: int = 240) -> tuple[str, dict]:
    """One world of one scrubber frame: the table, the target T, the block's spawn pose (a faint
    ghost), its path and final pose, the pusher's path and final position. Returns the SVG and its
    variable parts (the attributes the scrubber's script swaps)."""
    scale = size / (2 * ARENA_HALF)
    parts = frame_parts(world, scale, size)
    target = "".join(f'<polygon class="target" points="{p}" fill="none" stroke="{TARGET}" stroke-width="1.5" '
                     'stroke-dasharray="4 3"/>'
                     for p in tee_points(0, 0, 0, scale, size))
    px, py = parts["pusher"].split(",")
    svg = (f'<svg class="world" viewBox="0 0 {size} {size}" role="img" aria-label="{escape(name)}" '
           f'data-world="{escape(name)}" xmlns="http://www.w3.org/2000/svg"><title>{escape(name)}</title>'
           f'<rect class="table" x="0.5" y="0.5" width="{size - 1}" height="{size - 1}" fill="{INK}" fill-opacity="0.04" '
           f'stroke="{INK}" stroke-opacity="0.5"/>'
           f"{target}"
           f'<polygon class="ghost0" points="{parts["ghost"][0]}" fill="{color}" fill-opacity="0.08" '
           f'stroke="{color}" stroke-opacity="0.5" stroke-dasharray="2 2"/>'
           f'<polygon class="ghost1" points="{parts["ghost"][1]}" fill="{color}" fill-opacity="0.08" '
           f'stroke="{color}" stroke-opacity="0.5" stroke-dasharray="2 2"/>'
           f'<polyline class="block-path" fill="none" stroke="{color}" stroke-opacity="0.45" '
           f'points="{parts["block_path"]}"/>'
           f'<polygon class="tee0" points="{parts["tee"][0]}" fill="{color}" fill-opacity="0.55" stroke="{color}"/>'
           f'<polygon class="tee1" points="{parts["tee"][1]}" fill="{color}" fill-opacity="0.55" stroke="{color}"/>'
           f'<polyline class="pusher-path" fill="none" stroke="{INK}" stroke-width="1" stroke-dasharray="2 2" '
           f'points="{parts["pusher_path"]}"/>'
           f'<circle class="pusher" cx="{px}" cy="{py}" r="{0.03 * scale:.1f}" fill="{INK}" fill-opacity="0.8"/>'
           "</svg>")
    return svg, parts


def frame_parts(world: dict, scale: float, size: int) -> dict:
    """The drawn parts of one world at one iteration, as SVG attribute strings: the block's final
    pose (``tee``) and its spawn pose (``ghost``), its path, the pusher's path and final position."""
    block = world["block_mm_deg"]
    x, y, yaw = block[-1]
    return {"tee": tee_points(x, y, yaw, scale, size), "ghost": tee_points(*block[0], scale, size),
            "block_path": path_points([b[:2] for b in block], scale, size),
            "pusher_path": path_points(world["pusher_mm"], scale, size),
            "pusher": path_points([world["pusher_mm"][-1]], scale, size)}
