"""Small static SVG figures for the landing page: they read with JavaScript off and weigh little.

Each function returns one ``<svg>`` element as text. Numbers are escaped as text; nothing here
takes markup from outside. Labels carry units; every chart has labelled axes.
"""

from __future__ import annotations

import math
from html import escape

import numpy as np

INK, MUTED, GRID = "#1f2328", "#59636e", "#d8dee4"
DREAM, REAL, TARGET = "#8250df", "#0969da", "#1a7f37"   # one colour per world, everywhere on the page


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


def line_chart(series: list[dict], xlabel: str, ylabel: str, title: str, width: int = 560,
               height: int = 300, log_y: bool = False, chart_id: str = "", band: tuple[int, int] | None = None,
               brackets: list[dict] = ()) -> str:
    """A line chart. ``series``: dicts with ``x``, ``y``, ``label``, ``color`` and optionally
    ``markers`` (draw points) and ``dash``. Axes labelled, a legend on top. ``band`` (i, j) shades
    the area between series i and j (which share their x), in series i's colour; each of
    ``brackets`` (dicts ``x``, ``y0``, ``y1``, ``label``) is a vertical bracket from y0 to y1 at x,
    labelled beside it, inwards."""
    left, right, top, bottom = 76, 14, 40, 56
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
    pw, ph = width - left - right, height - top - bottom

    def px(x):
        return left + (x - x0) / ((x1 - x0) or 1) * pw

    def py(y):
        return top + (1 - (y - y0) / ((y1 - y0) or 1)) * ph

    out = [f'<svg class="chart" viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}"'
           + (f' id="{chart_id}"' if chart_id else "") + ' xmlns="http://www.w3.org/2000/svg">',
           f"<title>{escape(title)}</title>"]
    for t in yt:
        label = _fmt(10 ** t) if log_y else _fmt(t)
        out.append(f'<line x1="{left}" x2="{left + pw}" y1="{py(t):.1f}" y2="{py(t):.1f}" stroke="{GRID}"/>'
                   f'<text x="{left - 6}" y="{py(t) + 5:.1f}" text-anchor="end" class="tick">{label}</text>')
    for t in xt:
        out.append(f'<line x1="{px(t):.1f}" x2="{px(t):.1f}" y1="{top + ph}" y2="{top + ph + 4}" stroke="{MUTED}"/>'
                   f'<text x="{px(t):.1f}" y="{top + ph + 20}" text-anchor="middle" class="tick">{_fmt(t)}</text>')
    out.append(f'<line x1="{left}" x2="{left + pw}" y1="{top + ph}" y2="{top + ph}" stroke="{MUTED}"/>'
               f'<line x1="{left}" x2="{left}" y1="{top}" y2="{top + ph}" stroke="{MUTED}"/>')
    out.append(f'<text x="{left + pw / 2:.1f}" y="{height - 8}" text-anchor="middle" class="axis">{escape(xlabel)}</text>'
               f'<text transform="translate(18 {top + ph / 2:.1f}) rotate(-90)" text-anchor="middle" '
               f'class="axis">{escape(ylabel)}</text>')
    if band is not None:
        a, b = (series[k] for k in band)
        upper = [f"{px(x):.1f},{py(y):.1f}" for x, y in zip(np.asarray(a["x"], float), np.asarray(a["y"], float))]
        lower = [f"{px(x):.1f},{py(y):.1f}" for x, y in zip(np.asarray(b["x"], float), np.asarray(b["y"], float))]
        out.append(f'<polygon class="band" points="{" ".join(upper + lower[::-1])}" fill="{a["color"]}" '
                   'fill-opacity="0.12" stroke="none"/>')
    for br in brackets:
        x, ya, yb = px(float(br["x"])), py(float(br["y0"])), py(float(br["y1"]))
        inward = 1 if x < left + pw / 2 else -1
        x += 7 * inward                                  # clear of the lines' end markers
        tick = 5 * inward
        out.append(f'<path class="bracket" d="M{x + tick:.1f},{ya:.1f} H{x:.1f} V{yb:.1f} H{x + tick:.1f}" '
                   f'fill="none" stroke="{INK}" stroke-width="1.2"/>'
                   f'<text x="{x + 9 * inward:.1f}" y="{(ya + yb) / 2 + 5:.1f}" '
                   f'text-anchor="{"start" if inward > 0 else "end"}" class="note">{escape(br["label"])}</text>')
    lx = left
    for s in series:
        y = np.asarray(s["y"], float)
        y = np.log10(np.clip(y, 1e-12, None)) if log_y else y
        pts = " ".join(f"{px(a):.1f},{py(b):.1f}" for a, b in zip(np.asarray(s["x"], float), y))
        dash = f' stroke-dasharray="{s["dash"]}"' if s.get("dash") else ""
        out.append(f'<polyline fill="none" stroke="{s["color"]}" stroke-width="2"{dash} points="{pts}"/>')
        if s.get("markers"):
            out.extend(f'<circle cx="{p.split(",")[0]}" cy="{p.split(",")[1]}" r="3" fill="{s["color"]}"/>'
                       for p in pts.split())
        out.append(f'<rect x="{lx}" y="12" width="16" height="5" fill="{s["color"]}"/>'
                   f'<text x="{lx + 20}" y="20" class="legend">{escape(s["label"])}</text>')
        lx += 30 + 9 * len(s["label"])
    out.append("</svg>")
    return "".join(out)


def reward_bars(imagined: float, real: float, title: str, width: int = 320, height: int = 230) -> str:
    """The two-worlds headline: imagined and real reward per step as bars hanging from 0, with
    the gap between them marked. Rewards here are never positive (the best is 0)."""
    left, top, bottom = 64, 18, 44
    lo = min(imagined, real, -0.05)
    yt = _ticks(lo, 0.0)
    lo = min(lo, yt[0])
    ph = height - top - bottom

    def py(y):
        return top + (0 - y) / (0 - lo) * ph

    out = [f'<svg class="bars" viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}" '
           'xmlns="http://www.w3.org/2000/svg">', f"<title>{escape(title)}</title>"]
    for t in yt:
        out.append(f'<line x1="{left}" x2="{width - 10}" y1="{py(t):.1f}" y2="{py(t):.1f}" stroke="{GRID}"/>'
                   f'<text x="{left - 6}" y="{py(t) + 4:.1f}" text-anchor="end" class="tick">{_fmt(t)}</text>')
    out.append(f'<text transform="translate(14 {top + ph / 2:.1f}) rotate(-90)" text-anchor="middle" '
               'class="axis">reward per step</text>')
    bw = 70
    for i, (v, name, where, color) in enumerate([(imagined, "imagined", "in the dream", DREAM),
                                                  (real, "real", "true PushT", REAL)]):
        x = left + 24 + i * (bw + 60)
        out.append(f'<rect x="{x}" y="{py(0):.1f}" width="{bw}" height="{py(v) - py(0):.1f}" fill="{color}"/>'
                   f'<text x="{x + bw / 2}" y="{py(v) + 16:.1f}" text-anchor="middle" class="val">{v:+.3f}</text>'
                   f'<text x="{x + bw / 2}" y="{height - 22}" text-anchor="middle" class="legend">{name}</text>'
                   f'<text x="{x + bw / 2}" y="{height - 8}" text-anchor="middle" class="tick">{where}</text>')
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
    target = "".join(f'<polygon points="{p}" fill="none" stroke="{TARGET}" stroke-dasharray="4 3"/>'
                     for p in tee_points(0, 0, 0, scale, size))
    px, py = parts["pusher"].split(",")
    svg = (f'<svg class="world" viewBox="0 0 {size} {size}" role="img" aria-label="{escape(name)}" '
           f'data-world="{escape(name)}" xmlns="http://www.w3.org/2000/svg"><title>{escape(name)}</title>'
           f'<rect x="0.5" y="0.5" width="{size - 1}" height="{size - 1}" fill="#f6f8fa" stroke="{MUTED}"/>'
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
