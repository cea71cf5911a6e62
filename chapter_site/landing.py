"""The landing page, in the chapter page's form: the two worlds, the curves, the scrubber, the
wall-clock table, the colophon and the Colab links.

Every number comes from a file a run wrote: the headline from ``meta.yaml`` (``make meta``), the
curves and the scrubber from ``scrubber.json`` (``make chapter``), the table from
``benchmarks/wallclock.csv`` (``make bench``). Everything but the scrubber's slider is static HTML
and SVG, so the page reads with JavaScript off; the slider swaps pre-drawn SVG attributes.
"""

from __future__ import annotations

import json
from html import escape
from pathlib import Path

from autograde.course import colab_url

from . import colophon, svg, wallclock

ROOT = Path(__file__).resolve().parents[1]

# (meta.yaml key under seeds[0], label, format) for the headline; the browser test reads them back.
HEADLINE = [
    ("imagined_return_per_step", "imagined reward per step, in the dream", "{:+.3f}"),
    ("real_return_per_step", "real reward per step, in true PushT", "{:+.3f}"),
    ("imagination_gap", "the imagination gap per step (imagined minus real)", "{:+.3f}"),
    ("real_success_rate", "real task success", "{:.0%}"),
    ("imagined_final_tee_dist", "dream: the block ends this far from the target (m)", "{:.3f}"),
    ("real_final_tee_dist", "reality: the block ends this far from the target (m)", "{:.3f}"),
]


def headline_html(meta: dict) -> str:
    seed0 = meta["seeds"][0]
    plat = meta["platform"]
    bars = svg.reward_bars(seed0["imagined_return_per_step"], seed0["real_return_per_step"],
                           "imagined against real reward per step, seed 0")
    items = "".join(f'<div class="stat"><span class="num" data-key="{k}">{fmt.format(seed0[k])}</span>'
                    f'<span class="label">{escape(label)}</span></div>' for k, label, fmt in HEADLINE)
    return (f'<section class="panel" id="two-worlds"><h2>The same policy, two worlds</h2>'
            f'<p class="meta">seed 0 · {escape(str(meta["config"]["device"]))} · '
            f'{seed0["eval_episodes"]} held-out starts · {seed0["eval_horizon"]}-step rollouts · '
            f'measured by <code>make meta</code> on {escape(plat["cpu_model"])}, torch {escape(plat["torch"])} '
            f'(<code>meta.yaml</code>)</p>'
            f'<div class="two-worlds">{bars}<div class="stats">{items}</div></div></section>')


def curves_html(data: dict) -> str:
    c = data["curves"]
    reward = svg.line_chart(
        [{"x": c["imagined_reward"]["x"], "y": c["imagined_reward"]["y"], "label": "imagined (training dreams)",
          "color": svg.DREAM},
         {"x": c["real_floor"]["x"], "y": c["real_floor"]["y"], "label": "real floor (true PushT)",
          "color": svg.REAL, "markers": True}],
        "actor training iteration", "reward per step", "imagined reward and the real floor over training",
        chart_id="curve-reward")
    losses = svg.line_chart(
        [{"x": c["wm_recon"]["x"], "y": c["wm_recon"]["y"], "label": "reconstruction", "color": svg.INK},
         {"x": c["wm_dyn"]["x"], "y": c["wm_dyn"]["y"], "label": "dynamics", "color": svg.MUTED, "dash": "5 3"}],
        "world-model update", "loss (MSE, log scale)", "the world model's losses (MSE in normalised units)",
        log_y=True, chart_id="curve-wm")
    return ('<section class="panel" id="curves"><h2>Training in the dream, measured in both worlds</h2>'
            f'<p class="meta">{provenance(data)}. The imagined curve is the mean reward per step of each '
            "training batch of dreams (averaged over blocks of iterations); the real floor is the same "
            f"policy in the real simulator on {data['monitor_starts']} fixed starts it never trains on.</p>"
            f'<div class="charts"><figure>{reward}</figure><figure>{losses}</figure></div></section>')


def provenance(data: dict) -> str:
    return (f"This build's run: seed {data['seed']}, {escape(data['config'])} config, "
            f"{escape(data['host'])}, commit {escape(data['commit'])}")


def _readout(frame: dict) -> dict:
    return {"iteration": str(frame["iteration"]),
            "dream-reward": f"{frame['dream']['reward_per_step']:+.3f}",
            "real-reward": f"{frame['real']['reward_per_step']:+.3f}",
            "dream-dist": f"{frame['dream']['final_block_to_target_m']:.3f}",
            "real-dist": f"{frame['real']['final_block_to_target_m']:.3f}"}


def scrubber_html(data: dict, size: int = 240) -> str:
    """Both worlds at the last iteration, drawn statically; the script moves them to any other."""
    frames = data["frames"]
    last = frames[-1]
    views, payload = [], []
    for world, name, color in (("dream", "in the dream", svg.DREAM), ("real", "in reality", svg.REAL)):
        view, _ = svg.world_view(last[world], name, color, size)
        views.append(f'<figure><figcaption><span class="swatch" style="background:{color}"></span>'
                     f"{name}</figcaption>{view}</figure>")
    scale = size / (2 * svg.ARENA_HALF)
    for f in frames:
        payload.append({"readout": _readout(f),
                        "dream": svg.frame_parts(f["dream"], scale, size),
                        "real": svg.frame_parts(f["real"], scale, size)})
    readout = _readout(last)
    numbers = (f'<p class="readout">iteration <b data-field="iteration">{readout["iteration"]}</b> of '
               f'{data["imag_iters"]}: on this start the dream pays <b data-field="dream-reward">'
               f'{readout["dream-reward"]}</b> per step and reality <b data-field="real-reward">'
               f'{readout["real-reward"]}</b>; the block ends <b data-field="dream-dist">{readout["dream-dist"]}'
               f'</b> m from the target in the dream and <b data-field="real-dist">{readout["real-dist"]}</b> m '
               "in reality.</p>")
    slider = (f'<div class="scrub-control" hidden><label for="scrub">actor training iteration</label>'
              f'<input type="range" id="scrub" min="0" max="{len(frames) - 1}" step="1" value="{len(frames) - 1}" '
              f'aria-valuetext="iteration {readout["iteration"]}"></div>'
              f'<noscript><p class="meta">The slider needs JavaScript; shown is the last iteration.</p></noscript>')
    data_tag = ('<script type="application/json" id="scrubber-data">'
                + json.dumps(payload, separators=(",", ":")).replace("</", "<\\/") + "</script>")
    return ('<section class="panel" id="scrubber"><h2>Scrub through training</h2>'
            f'<p class="meta">{provenance(data)}. One held-out start (seed {data["start_seed"]}), '
            f'{data["horizon"]} control steps of {data["control_dt_s"]:g} s; the same policy, as it was at each '
            "iteration, in both worlds. Filled T: where the block ends; faint line: its path; dashed "
            "line and dot: the pusher; dashed green T: the target.</p>"
            f'{slider}{numbers}<div class="worlds">{"".join(views)}</div>{data_tag}</section>')


def colab_html(notebooks: list[str]) -> str:
    rows = "".join(f'<li><a href="notebooks/{Path(n).stem}.html">{escape(title)}</a> · '
                   f'<a class="colab" href="{escape(colab_url(n))}">Open in Colab</a></li>'
                   for n, title in notebooks_titles(notebooks))
    return ('<section class="panel" id="open"><h2>Run it yourself</h2><p>Open a notebook in Colab, or run the '
            "chapter on your own machine (<code>make chapter</code>). The predict-then-run exercises "
            "also run from a terminal (<code>python -m pusht.exercise ex1</code>).</p>"
            f"<ol class=\"notebooks\">{rows}</ol></section>")


def notebooks_titles(notebooks: list[str]):
    for n in notebooks:
        yield n, Path(n).stem.replace("_", " ")


def colophon_html(commit: str, run_commit: str | None = None) -> str:
    rows = "".join(f"<tr><td>{escape(r.notebook)}</td><td><code>{escape(r.module)}</code></td>"
                   f"<td><code>{escape(r.qualname)}</code></td><td>{escape(r.lines)}</td>"
                   f'<td><code title="{r.sha256}">{r.sha256[:12]}…</code></td></tr>'
                   for r in colophon.regions())
    return ('<section class="panel" id="colophon"><h2>Colophon · provenance</h2>'
            "<p>The notebooks show the package's own code, not a copy of it: each region below is "
            "displayed with <code>inspect.getsource</code>. The fingerprint is the sha256 of the text shown, "
            f"at commit <code>{escape(commit)}</code>.{_mismatch(commit, run_commit)}</p>"
            "<div class=\"scroll\"><table class=\"colophon\">"
            "<thead><tr><th>notebook</th><th>module</th><th>function</th><th>lines</th><th>sha256</th></tr>"
            f"</thead><tbody>{rows}</tbody></table></div></section>")


def _mismatch(commit: str, run_commit: str | None) -> str:
    """A visible warning where the run that made the curves and the scrubber is not the build's
    commit, or either had uncommitted changes: then the fingerprints describe other code."""
    if run_commit is None or (run_commit == commit and not commit.endswith("-dirty")):
        return ""
    return (f' <strong class="warn">Note: the run shown above was made at <code>{escape(run_commit)}</code>, '
            f"the page built at <code>{escape(commit)}</code>; a commit ending in -dirty had uncommitted "
            "changes. Rebuild both from one clean commit (make site) to publish.</strong>")


def page(meta: dict, data: dict, notebooks: list[str], commit: str) -> str:
    """The landing page as MyST markdown (its panels as raw HTML)."""
    html = "\n".join([headline_html(meta), curves_html(data), scrubber_html(data), colab_html(notebooks),
                      '<section class="panel" id="wallclock"><h2>Wall-clock</h2>' + wallclock.table_html()
                      + "</section>", colophon_html(commit, data.get("commit"))])
    intro = (ROOT / "book" / "intro.md").read_text()
    return f"{intro}\n```{{raw}} html\n{html}\n```\n\nRead next: [the reading list](reading.md).\n"
