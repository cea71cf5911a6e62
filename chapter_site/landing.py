"""The landing page, in the chapter page's form: the result in one sentence and the two worlds on
the first screen (a phone's too), then the chapter's objectives, the curves, the scrubber, the
Colab links, the wall-clock table and the colophon.

Every number comes from a file a run wrote: the headline from ``meta.yaml`` (``make meta``), the
curves and the scrubber from ``scrubber.json`` (``make chapter``), the table from
``benchmarks/wallclock.csv`` (``make bench``). Everything but the scrubber's slider is static HTML
and SVG, so the page reads with JavaScript off; the slider swaps pre-drawn SVG attributes.

The reward chart is the headline's own evaluation (the same held-out starts and horizon, both
worlds) at every kept iteration, so its last point is the headline's when the run and ``meta.yaml``
agree. Every sentence that compares (the headline's sentence, the reading under the chart, the
scrubber's "what to notice") is a predicate on the run's numbers with its true alternative written
out: :func:`verdict` (through :func:`gap_reading`), :func:`evaluation_case`, :func:`lessons`,
:func:`drift_text`, :func:`leaving_text`. (They are not entries of ``pusht.nb.claims``'s registry:
that registry is the notebooks' claims, each recorded on seeds 0-9 by ``make claims``; these read
``meta.yaml`` and the site's own run, and ``tests/test_site.py`` checks each alternative.)
"""

from __future__ import annotations

import json
from html import escape
from pathlib import Path

import numpy as np

from autograde.course import colab_url
from pusht.nb import stats

from . import colophon, svg, wallclock

ROOT = Path(__file__).resolve().parents[1]

# -- the first screen: the verdict in one sentence, then the two-worlds panel -------------------------

RESULT_MARK = "<!-- the result -->"      # book/intro.md: where the sentence and the panel go


def gap_reading(seed0: dict) -> tuple[str, float | None]:
    """How the recorded gap reads against its own noise: "up" (the dream pays more than reality,
    beyond ``k`` standard errors and the minimum effect that matters), "down" (the dream pays
    less), "small" (beyond the noise, smaller than the minimum effect), "same" (not told from 0)
    or "untested" (``meta.yaml`` holds no standard error for it). The one verdict of the
    notebooks (:func:`pusht.nb.stats.beyond`), with ``k`` Student's t over the evaluation's starts.
    Returns the reading and the standard error."""
    gap, se = seed0["imagination_gap"], seed0.get("imagination_gap_se_eval_horizon")
    if se is None or abs(seed0.get("imagination_gap_eval_horizon", gap) - gap) > 1e-9:
        return "untested", None
    k = stats.k_for(int(seed0["eval_episodes"]))
    if stats.beyond(gap, se, k, stats.MIN_REWARD_EFFECT):
        return ("up" if gap > 0 else "down"), se
    return ("small" if stats.beyond(gap, se, k) else "same"), se


def verdict(seed0: dict) -> str:
    """The chapter's result in one sentence, from ``meta.yaml``'s seed 0: both worlds' reward, the
    gap read against its noise (:func:`gap_reading`, each reading its own words) and the real
    success (none, or how much), with the scripted expert's on the same starts where recorded.
    HTML: the numbers are ``<strong>`` elements carrying ``data-verdict`` (the key they show)."""
    def num(key: str, text: str) -> str:
        return f'<strong class="num" data-verdict="{key}">{text}</strong>'

    n = int(seed0["eval_episodes"])
    reading, se = gap_reading(seed0)
    gap = num("imagination_gap", f"{seed0['imagination_gap']:+.3f}") + (f" ± {_num(se)}" if se is not None else "")
    gap_words = {
        "up": f"the dream pays more than reality by an imagination gap of {gap} per step",
        "down": f"the dream pays less than reality: an imagination gap of {gap} per step",
        "small": (f"an imagination gap of {gap} per step, beyond the noise but under the "
                  f"{stats.MIN_REWARD_EFFECT:.3f} that matters"),
        "same": f"an imagination gap of {gap} per step, which {n} starts cannot tell from none",
        "untested": f"an imagination gap of {gap} per step",
    }[reading]
    rate = seed0["real_success_rate"]
    success = num("real_success_rate", f"{rate:.0%}")
    success_words = (f"it solves {success} of the {n} held-out starts for real" if rate > 0 else
                     f"it solves none of the {n} held-out starts for real ({success})")
    expert = seed0.get("expert_real_success_rate")
    if expert is not None:
        success_words += f"; the scripted expert, from the same starts, solves {expert:.0%}"
    return (f"Trained only inside its learned world model, the policy earns "
            f"{num('imagined_return_per_step', format(seed0['imagined_return_per_step'], '+.3f'))} reward per step "
            f"in the dream and {num('real_return_per_step', format(seed0['real_return_per_step'], '+.3f'))} in "
            f"true PushT: {gap_words}, and {success_words}.")


def verdict_html(meta: dict) -> str:
    return f'<p class="verdict" id="verdict">{verdict(meta["seeds"][0])}</p>'


# (meta.yaml key under seeds[0], label, format) for the headline; the browser test reads them back.
# The order is the panel's: on a phone, two to a row, the gap and the success make the second row.
HEADLINE = [
    ("imagined_return_per_step", "imagined reward per step, in the dream", "{:+.3f}"),
    ("real_return_per_step", "real reward per step, in true PushT", "{:+.3f}"),
    ("imagination_gap", "the imagination gap per step (imagined minus real)", "{:+.3f}"),
    ("real_success_rate", "real task success", "{:.0%}"),
    ("imagined_final_tee_dist", "dream: the block ends this far from the target (m)", "{:.3f}"),
    ("real_final_tee_dist", "reality: the block ends this far from the target (m)", "{:.3f}"),
]
BOTH = ("imagined_return_per_step", "real_return_per_step", "imagination_gap", "real_success_rate")


def headline_html(meta: dict, data: dict | None = None, notebooks: list[str] = ()) -> str:
    """The two-worlds panel: ``meta.yaml``'s seed 0 (the numbers, then the bars), and, given this
    build's run (``data``, scrubber.json), both measurements side by side with why they differ
    (:func:`sources_html`)."""
    seed0 = meta["seeds"][0]
    plat = meta["platform"]
    bars = svg.reward_bars(seed0["imagined_return_per_step"], seed0["real_return_per_step"],
                           "imagined against real reward per step, seed 0, with the gap between them")
    items = "".join(f'<div class="stat"><span class="num" data-key="{k}">{fmt.format(seed0[k])}</span>'
                    f'<span class="label">{escape(label)}</span></div>' for k, label, fmt in HEADLINE)
    return (f'<section class="panel" id="two-worlds"><h2>The same policy, two worlds</h2>'
            f'<div class="two-worlds"><div class="stats">{items}</div>{bars}</div>'
            f'<p class="meta">seed 0 · {escape(str(meta["config"]["device"]))} · '
            f'{seed0["eval_episodes"]} held-out starts · {seed0["eval_horizon"]}-step rollouts · '
            f'measured by <code>make meta</code> on {escape(plat["cpu_model"])}, torch {escape(plat["torch"])} '
            f'(<code>meta.yaml</code>)</p>'
            + (sources_html(meta, data, notebooks) if data is not None else "") + "</section>")


def sources_html(meta: dict, data: dict, notebooks: list[str] = ()) -> str:
    """The headline's two measurements side by side: ``meta.yaml``'s record (this panel) and this
    build's run (notebook 04's headline, the curves' last point), each labelled with its config,
    starts and host, and one sentence on why they differ (:func:`evaluation_case`)."""
    seed0, last = meta["seeds"][0], data["frames"][-1]["eval"]
    nb04 = next((Path(n).stem for n in notebooks if n.startswith("04")), None)
    where = (f'<a href="notebooks/{nb04}.html#same-policy-two-worlds">notebook 04\'s headline</a> and the '
             "curves below" if nb04 else "the curves below")
    fmt = {k: f for k, _, f in HEADLINE}

    def rows(label: str, values: dict, cls: str) -> str:
        """One measurement: its label on a row of its own (a phone has no room beside four numbers),
        then its numbers."""
        return (f'<tbody class="{cls}"><tr><th colspan="{len(BOTH)}" scope="rowgroup">{label}</th></tr><tr>'
                + "".join(f"<td>{fmt[k].format(values[k])}</td>" for k in BOTH) + "</tr></tbody>")

    plat = meta["platform"]
    recorded = (f"recorded (<code>meta.yaml</code>, the headline): {'smoke' if seed0['smoke'] else 'default'} "
                f"config, {seed0['eval_episodes']} starts × {seed0['eval_horizon']} steps, {escape(plat['cpu_model'])}")
    built = (f"this build's run ({where}): {escape(data['config'])} config, {data['eval_starts']} starts × "
             f"{data['horizon']} steps, {escape(data['host'])}")
    case = evaluation_case(data, seed0)
    why = {"same": "The same evaluation, and the same numbers: this build reproduced the record.",
           "differs": ("The same evaluation, other numbers: the record was measured by make meta at another commit "
                       "or on another host, and this page shows it; notebook 04 shows what this build measured."),
           "other": (f"Two different evaluations: this build ran the {escape(data['config'])} config, "
                     f"{data['eval_starts']} starts of {data['horizon']} steps, a quick check of the pipeline, not "
                     f"the record's {seed0['eval_episodes']} starts of {seed0['eval_horizon']}; the headline is "
                     "the record's.")}[case]
    return (f'<table class="sources" data-case="{case}"><caption>Seed 0, measured twice</caption>'
            '<thead><tr><th scope="col">dream</th><th scope="col">real</th><th scope="col">gap</th>'
            '<th scope="col">real success</th></tr></thead>'
            f"{rows(recorded, seed0, 'recorded')}{rows(built, last, 'this-build')}</table>"
            f'<p class="meta why">{why}</p>')


def _eval_curve(data: dict, key: str) -> tuple[list[int], list[float]]:
    frames = data["frames"]
    return [f["iteration"] for f in frames], [f["eval"][key] for f in frames]


def curves_html(data: dict, meta: dict) -> str:
    """The headline's evaluation over training (with the reading under it), and the world model's
    losses. ``meta``: meta.yaml, whose seed 0 the headline panel shows."""
    x, dream = _eval_curve(data, "imagined_return_per_step")
    _, real = _eval_curve(data, "real_return_per_step")
    _, gap = _eval_curve(data, "imagination_gap")
    brackets = [{"x": x[i], "y0": real[i], "y1": dream[i], "label": f"gap {gap[i]:+.3f}"} for i in (0, -1)]
    reward = svg.line_chart(
        [{"x": x, "y": dream, "label": "imagined: in the dream", "color": svg.DREAM, "markers": True},
         {"x": x, "y": real, "label": "real: in true PushT", "color": svg.REAL, "markers": True}],
        "actor training iteration", f"reward per step ({data['control_dt_s']:g} s)",
        "the headline's evaluation at every kept training iteration: imagined and real reward per step",
        chart_id="curve-reward", band=(0, 1), brackets=brackets)
    losses = svg.line_chart(
        [{"x": c["x"], "y": c["y"], **style} for c, style in (
            (data["curves"]["wm_recon"], {"label": "reconstruction", "color": svg.INK}),
            (data["curves"]["wm_dyn"], {"label": "dynamics", "color": svg.INK, "dash": "7 4"}))],
        "world-model update", "loss (MSE, log scale)", "the world model's losses (MSE in normalised units)",
        log_y=True, chart_id="curve-wm")
    n, h, dt = data["eval_starts"], data["horizon"], data["control_dt_s"]
    return ('<section class="panel" id="curves"><h2>Training in the dream, measured in both worlds</h2>'
            f'<p class="meta">{provenance(data)}. The reward chart is the headline\'s evaluation, run on the policy as it '
            f"was at each kept iteration: the same {n} held-out starts, {h} steps ({h * dt:g} s) in the dream and "
            f"in true PushT, mean reward per step; shaded: the gap. (The actor's own training dreams, "
            f"{data['imag_horizon']}-step dreams from training starts, and the real-floor monitor are notebook 03's "
            "figure.) Changes are tested start by start: "
            f"{stats.LEVEL:.0%} t-tests over the {n} starts, minimum effect that matters "
            f"{stats.MIN_REWARD_EFFECT:.3f} per step.</p>"
            f'<div class="charts"><figure>{reward}</figure><figure>{losses}</figure></div>'
            f"{reading_html(data, meta)}</section>")


# -- the reading under the chart: every comparison is computed, with its true alternative ------------

def evaluation_case(data: dict, seed0: dict) -> str:
    """How the chart's last point stands to the headline panel (meta.yaml's seed 0): "same" (the
    same evaluation, and it shows the same three numbers), "differs" (the same evaluation, other
    numbers: another commit or host measured the headline) or "other" (another evaluation: a
    different config, e.g. this build's smoke run)."""
    same_eval = (data["seed"] == seed0["seed"] and bool(seed0["smoke"]) == (data["config"] == "smoke")
                 and data["eval_starts"] == seed0["eval_episodes"] and data["horizon"] == seed0["eval_horizon"]
                 and data["imag_iters"] == seed0["imag_iters"])
    if not same_eval:
        return "other"
    last = data["frames"][-1]["eval"]
    shown = [k for k, _, _ in HEADLINE if k in ("imagined_return_per_step", "real_return_per_step",
                                                  "imagination_gap", "real_success_rate")]
    fmt = {k: f for k, _, f in HEADLINE}
    return "same" if all(fmt[k].format(last[k]) == fmt[k].format(seed0[k]) for k in shown) else "differs"


def reconcile_sentence(data: dict, seed0: dict) -> str:
    """One sentence: which evaluation the chart is, and whether its last point is the headline's."""
    last = data["frames"][-1]["eval"]
    point = (f"dream {last['imagined_return_per_step']:+.3f}, real {last['real_return_per_step']:+.3f}, "
             f"gap {last['imagination_gap']:+.3f}")
    case = evaluation_case(data, seed0)
    if case == "same":
        return (f"Both curves are the headline's two worlds: its last point (iteration {data['imag_iters']}, "
                f"the trained policy) is the headline above, {point}.")
    if case == "differs":
        return (f"Both curves are the headline's evaluation, but this build's run ends at {point}, not at the "
                f"headline's gap of {seed0['imagination_gap']:+.3f}: the headline was measured by make meta at "
                "another commit or on another host.")
    return (f"These curves are this build's {escape(data['config'])} run, {data['eval_starts']} starts of "
            f"{data['horizon']} steps, so its last point ({point}) is not the headline's "
            f"{seed0['eval_episodes']}-start, {seed0['eval_horizon']}-step evaluation (gap "
            f"{seed0['imagination_gap']:+.3f}).")


def _change_test(values) -> "stats.Test | None":
    """The start-by-start test of a change (a one-sample t-test with the minimum effect); None with
    a single start, which gives no standard error."""
    values = np.asarray(values, dtype=float)
    return stats.sign_test(values, min_effect=stats.MIN_REWARD_EFFECT) if values.size > 1 else None


def _num(x: float) -> str:
    """A standard error: 3 decimals, or 2 significant figures when smaller."""
    return f"{x:.3f}" if x == 0 or abs(x) >= 0.001 else f"{x:.1e}"


def _change_words(test, diff: float) -> str:
    if test is None:
        return f"changed by {diff:+.3f} (one start: not tested)"
    pm = f"{abs(test.diff):.3f} ± {_num(test.se)}"
    signed = f"{test.diff:+.3f} ± {_num(test.se)}"
    if test.outcome == "same":
        return (f"changed by less than the minimum effect ({signed})" if test.detected
                else f"could not be told from no change ({signed})")
    return {"up": f"rose by {pm}", "down": f"fell by {pm}"}[test.outcome]


def lessons(data: dict) -> list[str]:
    """The chart's two lessons, one line each, from the run's numbers: the gap before any training
    (iteration 0, the untrained policy), and what training changed in each world."""
    first, last = data["frames"][0], data["frames"][-1]
    e0, e1 = first["eval"], last["eval"]
    d0, r0 = np.asarray(e0["imagined_per_start"]), np.asarray(e0["real_per_start"])
    d1, r1 = np.asarray(e1["imagined_per_start"]), np.asarray(e1["real_per_start"])
    g0 = _change_test(d0 - r0)
    before = (f"Before any update (iteration {first['iteration']}) the untrained policy gets "
              f"{e0['imagined_return_per_step']:+.3f} per step in the dream and {e0['real_return_per_step']:+.3f} "
              f"in reality, a gap of {e0['imagination_gap']:+.3f}" + (f" ± {_num(g0.se)}" if g0 else ""))
    g = e0["imagination_gap"]
    outcome = g0.outcome if g0 else ("up" if g > 0 else "down" if g < 0 else "same")
    if outcome == "same" and g0 is not None and g0.detected:
        outcome = "small"
    before += {"up": ": the dream is rosier before the actor has learned anything, so that much of the gap "
                     "comes from the model, not from what the actor learned.",
               "down": ": the dream is gloomier than reality before the actor has learned anything.",
               "small": ": before training the two worlds differ by less than the minimum effect.",
               "same": ": before training the two worlds cannot be told apart."}[outcome]
    best = max(data["frames"], key=lambda f: f["eval"]["real_success_rate"])
    success = ("real success was 0% at every kept iteration" if best["eval"]["real_success_rate"] == 0 else
               f"real success reached {best['eval']['real_success_rate']:.0%} (iteration {best['iteration']})")
    def words(a, _, key):
        return _change_words(_change_test(a), e1[key] - e0[key])

    during = (f"Over training (iteration {first['iteration']} to {last['iteration']}) the dream's reward per step "
              f"{words(d1 - d0, None, 'imagined_return_per_step')}, reality's "
              f"{words(r1 - r0, None, 'real_return_per_step')}, and the gap "
              f"{words((d1 - r1) - (d0 - r0), None, 'imagination_gap')}; {success}.")
    return [before, during]


def reading_html(data: dict, meta: dict) -> str:
    seed0 = meta["seeds"][0]
    items = "".join(f"<li>{escape(line)}</li>" for line in lessons(data))
    return (f'<p class="reading" data-case="{evaluation_case(data, seed0)}">'
            f"{escape(reconcile_sentence(data, seed0))}</p><ul class=\"lessons\">{items}</ul>")


def provenance(data: dict) -> str:
    return (f"This build's run: seed {data['seed']}, {escape(data['config'])} config, "
            f"{escape(data['host'])}, commit {escape(data['commit'])}")


def _who(frame: dict, data: dict) -> str:
    it = frame["iteration"]
    return ("the untrained policy" if it == 0 else "the trained policy" if it == data["imag_iters"]
            else f"the policy at iteration {it}")


def drift_text(frame: dict, data: dict) -> str:
    """What to notice in the dream: did the block move from its spawn pose (the ghost) without the
    pusher reaching it? From the frame's own numbers; a move is at least the success tolerance,
    a touch the pusher's rim within ``touch_tol_m`` of the T (in a dream it may even pass into it)."""
    d, r = frame["dream"], frame["real"]
    moved, gap = d["block_moved_m"], d["pusher_min_gap_m"]
    nearer = d["block_nearer_target_m"]
    way = f"{abs(nearer):.3f} m {'nearer' if nearer > 0 else 'farther from'} the target" if nearer else "no nearer"
    if moved >= data["moved_tol_m"] and gap > data["touch_tol_m"]:
        s = (f"Drift: with {_who(frame, data)}, the dreamed block slid {moved:.3f} m from its spawn pose (faint T), "
             f"{way}, though the pusher never came within {gap:.3f} m of it")
    elif moved >= data["moved_tol_m"]:
        s = (f"With {_who(frame, data)}, the dreamed pusher reached the block, which ended {moved:.3f} m from its "
             f"spawn pose (faint T), {way}")
    else:
        s = (f"With {_who(frame, data)}, the dreamed block stayed within {data['moved_tol_m'] * 100:g} cm of its "
             f"spawn pose (faint T)")
    return s + f"; in reality the block moved {r['block_moved_m']:.3f} m."


def leaving_text(frame: dict, data: dict) -> str:
    """What to notice in reality: does the pusher go where the expert data (the model's training
    set) never went? The share of steps it spends pinned against a wall, against the data's own,
    compared as shown (whole percent)."""
    share, expert = frame["real"]["pusher_at_wall_share"], data["expert_pusher_at_wall_share"]
    who = _who(frame, data)
    if round(share * 100) > round(expert * 100):
        return (f"Leaving the data: in reality the pusher of {who} spends {share:.0%} of its steps pinned against "
                f"a wall, where the expert data the model learned from spends {expert:.0%}.")
    return (f"In reality the pusher of {who} spends {share:.0%} of its steps against a wall, no more than the "
            f"expert data the model learned from ({expert:.0%}).")


def _readout(frame: dict, data: dict) -> dict:
    return {"iteration": str(frame["iteration"]),
            "dream-reward": f"{frame['dream']['reward_per_step']:+.3f}",
            "real-reward": f"{frame['real']['reward_per_step']:+.3f}",
            "dream-dist": f"{frame['dream']['final_block_to_target_m']:.3f}",
            "real-dist": f"{frame['real']['final_block_to_target_m']:.3f}",
            "drift": drift_text(frame, data), "leaving": leaving_text(frame, data)}


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
        payload.append({"readout": _readout(f, data),
                        "dream": svg.frame_parts(f["dream"], scale, size),
                        "real": svg.frame_parts(f["real"], scale, size)})
    readout = _readout(last, data)
    numbers = (f'<p class="readout">iteration <b data-field="iteration">{readout["iteration"]}</b> of '
               f'{data["imag_iters"]}: on this start the dream pays <b data-field="dream-reward">'
               f'{readout["dream-reward"]}</b> per step and reality <b data-field="real-reward">'
               f'{readout["real-reward"]}</b>; the block ends <b data-field="dream-dist">{readout["dream-dist"]}'
               f'</b> m from the target in the dream and <b data-field="real-dist">{readout["real-dist"]}</b> m '
               "in reality.</p>")
    notice = ('<p class="readout">What to notice (slide to iteration 0, then back to the last):</p>'
              f'<ul class="notice"><li data-field="drift">{escape(readout["drift"])}</li>'
              f'<li data-field="leaving">{escape(readout["leaving"])}</li></ul>')
    slider = (f'<div class="scrub-control" hidden><label for="scrub">actor training iteration</label>'
              f'<input type="range" id="scrub" min="0" max="{len(frames) - 1}" step="1" value="{len(frames) - 1}" '
              f'aria-valuetext="iteration {readout["iteration"]}"></div>'
              f'<noscript><p class="meta">The slider needs JavaScript; shown is the last iteration.</p></noscript>')
    data_tag = ('<script type="application/json" id="scrubber-data">'
                + json.dumps(payload, separators=(",", ":")).replace("</", "<\\/") + "</script>")
    return ('<section class="panel" id="scrubber"><h2>Scrub through training</h2>'
            f'<p class="meta">{provenance(data)}. One of the headline\'s held-out starts (seed {data["start_seed"]}), '
            f'{data["horizon"]} control steps of {data["control_dt_s"]:g} s; the same policy, as it was at each '
            "iteration, in both worlds. Faint dashed T: where the block spawned; filled T: where it ends; faint "
            "line: its path; dashed line and dot: the pusher; dashed green T: the target.</p>"
            f'{slider}{numbers}{notice}<div class="worlds">{"".join(views)}</div>{data_tag}</section>')


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


# where each number on the page comes from, and the command that makes it: the colophon's first line
SOURCES = ("The numbers on this page come from runs, never from prose: the headline sentence and the two-worlds "
           "panel from <code>meta.yaml</code> (<code>make meta</code>), the curves and the scrubber from this "
           "build's own run (<code>make chapter</code>), the wall-clock table from "
           "<code>benchmarks/wallclock.csv</code> (<code>make bench</code>).")


def colophon_html(commit: str, run_commit: str | None = None) -> str:
    rows = "".join(f"<tr><td>{escape(r.notebook)}</td><td><code>{escape(r.module)}</code></td>"
                   f"<td><code>{escape(r.qualname)}</code></td><td>{escape(r.lines)}</td>"
                   f'<td><code title="{r.sha256}">{r.sha256[:12]}…</code></td></tr>'
                   for r in colophon.regions())
    return ('<section class="panel" id="colophon"><h2>Colophon · provenance</h2>'
            f"<p>{SOURCES}</p>"
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
    """The landing page as MyST markdown (its panels as raw HTML). The first screen is the title,
    the result in one sentence (:func:`verdict`) and the two-worlds panel, put where
    ``book/intro.md`` marks :data:`RESULT_MARK`; then the chapter's method and objectives, the
    curves, the scrubber, the notebooks, the wall-clock table and the colophon."""
    intro = (ROOT / "book" / "intro.md").read_text()
    head, mark, rest = intro.partition(RESULT_MARK)
    if not mark:
        raise ValueError(f"book/intro.md has no {RESULT_MARK!r}: where the headline goes")
    top = "\n".join([verdict_html(meta), headline_html(meta, data, notebooks)])
    html = "\n".join([curves_html(data, meta), scrubber_html(data), colab_html(notebooks),
                      '<section class="panel" id="wallclock"><h2>Wall-clock</h2>' + wallclock.table_html()
                      + "</section>", colophon_html(commit, data.get("commit"))])
    return (f"{head.rstrip()}\n\n```{{raw}} html\n{top}\n```\n\n{rest.strip()}\n\n```{{raw}} html\n{html}\n```\n\n"
            "Read next: [the reading list](reading.md).\n")
