"""The chapter site's parts, without a browser (tests/test_site_browser.py opens the built site).

* the scrubber's export trains the chapter's own actor again and its last frame is that actor;
* its evaluation over training is the headline's: the last kept iteration gives the run's own
  imagined and real reward per step, the first the untrained controls';
* the reading under the chart and the scrubber's "what to notice" lines are computed from the run's
  numbers, each with its true alternative;
* the colophon finds every region the notebooks show and fingerprints exactly the shown text;
* the wall-clock table says "pending" for a tier never measured and never invents a figure;
* a published notebook page carries the student release's code, never a solution, and no run paths;
* the landing page's numbers are meta.yaml's and scrubber.json's.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import re
from pathlib import Path

import nbformat
import numpy as np
import pytest
import yaml

from chapter_site import colophon, landing, wallclock
from chapter_site.book import publishable
from chapter_site.scrubber import FRAMES, export

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    return out, json.loads(export(out, smoke=True, log=None).read_text())


@pytest.fixture(scope="module")
def smoke_export(smoke_run):
    return smoke_run[1]


def test_scrubber_export_is_the_chapters_actor_at_every_kept_iteration(smoke_export):
    d = smoke_export
    iters = [f["iteration"] for f in d["frames"]]
    assert iters[0] == 0 and iters[-1] == d["imag_iters"] and iters == sorted(iters)
    assert len(iters) <= FRAMES + 1
    assert d["same_as_chapter_agent"] is True      # export() raises where the retrained actor differs
    for f in d["frames"]:
        for world in ("dream", "real"):
            w = f[world]
            assert len(w["pusher_mm"]) == len(w["block_mm_deg"]) == d["horizon"] + 1
            assert all(abs(v) <= 2000 for xy in w["pusher_mm"] for v in xy)    # millimetres, on or near the table
    assert d["curves"]["real_floor"]["x"] == iters
    assert d["config"] == "smoke" and d["seed"] == 0
    for f in d["frames"]:
        e = f["eval"]
        assert len(e["imagined_per_start"]) == len(e["real_per_start"]) == d["eval_starts"]
        assert e["imagined_return_per_step"] == pytest.approx(np.mean(e["imagined_per_start"]), abs=1e-5)
        assert e["imagination_gap"] == pytest.approx(e["imagined_return_per_step"] - e["real_return_per_step"], abs=2e-6)
        # the scrubber's start is the first of the evaluation's starts, from the same rollout
        assert f["real"]["reward_per_step"] == e["real_per_start"][0]
        for world in ("dream", "real"):
            w = f[world]
            moved = np.linalg.norm(np.subtract(w["block_mm_deg"][-1][:2], w["block_mm_deg"][0][:2])) / 1000
            assert w["block_moved_m"] == pytest.approx(moved, abs=0.0015)     # mm rounding of both ends
            assert 0 <= w["pusher_at_wall_share"] <= 1


def test_evaluation_over_training_is_the_headline_evaluation(smoke_run):
    """The chart's last point is the run's own two-world evaluation (what the headline shows), and
    its first is that evaluation's untrained control: the same starts, horizon and calls."""
    from pusht.config import make_config
    from pusht.dreamer import run

    out, d = smoke_run
    m = run(make_config(smoke=True, seed=0, out=out), cache_dir=out / "cache", model_cache=out / "cache",
            log=None).metrics
    first, last = d["frames"][0]["eval"], d["frames"][-1]["eval"]
    assert d["eval_starts"] == m["eval_episodes"] and d["horizon"] == m["eval_horizon"]
    assert last["imagined_return_per_step"] == pytest.approx(m["imagined_return_per_step"], abs=1e-6)
    assert last["real_return_per_step"] == pytest.approx(m["real_return_per_step"], abs=1e-6)
    assert last["real_success_rate"] == m["real_success_rate"]
    assert first["imagined_return_per_step"] == pytest.approx(m["untrained_actor_dream_return_per_step"], abs=1e-6)
    assert first["real_return_per_step"] == pytest.approx(m["untrained_real_return_per_step_eval_horizon"], abs=1e-6)


def test_scrubber_export_refuses_another_policy(tmp_path, monkeypatch):
    """A watched training that ends anywhere but at the notebooks' actor is an error, not a page."""
    import chapter_site.scrubber as scrubber

    monkeypatch.setattr(scrubber, "_same_weights", lambda a, b: False)
    with pytest.raises(RuntimeError, match="differs from the one the notebooks trained"):
        scrubber.export(tmp_path, smoke=True, log=None)


def test_colophon_covers_every_shown_region_and_hashes_the_shown_text():
    regions = colophon.regions()
    calls = sum(len(re.findall(r"inspect\.getsource\(", "".join(c["source"])))
                for nb in sorted((ROOT / "solutions").glob("*.ipynb"))
                for c in json.loads(nb.read_text())["cells"] if c["cell_type"] == "code")
    assert len(regions) == calls >= 10
    import importlib
    for r in regions:
        obj = importlib.import_module(r.module)
        for part in r.qualname.split("."):
            obj = getattr(obj, part)
        assert hashlib.sha256(inspect.getsource(obj).encode()).hexdigest() == r.sha256


def test_colophon_names_what_it_cannot_resolve(tmp_path):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import inspect\ninspect.getsource(nowhere)")])
    nbformat.write(nb, tmp_path / "x.ipynb")
    with pytest.raises(ValueError, match="'nowhere'.*not imported"):
        colophon.regions(tmp_path)


def test_wallclock_pending_for_tiers_never_measured(tmp_path):
    csv = tmp_path / "w.csv"
    header = "measured_at,tier,machine,figure,value,unit,notes,commit\n"
    csv.write_text(header
                   + '2026-01-01T00:00:00+00:00,cpu,"old box",pipeline_cold_wall,20.0,s,median of 5,aaa\n'
                   + '2026-02-01T00:00:00+00:00,cpu,"new box",pipeline_cold_wall,6.0,s,median of 5,bbb\n'
                   + '2026-02-01T00:00:00+00:00,t4,"a T4",startup,1.0,s,not the figure,ccc\n')
    html = wallclock.table_html(csv)
    rows = dict(re.findall(r'data-tier="([^"]+)">(.*?)</tr>', html))
    assert set(rows) == set(wallclock.TIERS)
    assert "6.0 s" in rows["cpu"] and "new box" in rows["cpu"] and "20.0" not in rows["cpu"]
    for tier in ("t4", "mps", "4090"):
        assert "pending" in rows[tier] and not re.search(r"\d+\.\d+ s", rows[tier])


def test_the_real_wallclock_csv_renders():
    html = wallclock.table_html()
    assert 'data-tier="cpu"' in html and "pending" in html


def test_published_pages_show_the_student_code_and_no_solution(tmp_path):
    for nb_path in sorted((ROOT / "solutions").glob("*.ipynb")):
        nb = nbformat.read(nb_path, 4)
        nb.cells.insert(1, nbformat.v4.new_code_cell('OUT = "/home/someone/runs"',
                                                     metadata={"tags": ["injected-parameters"]}))
        nbformat.write(nb, tmp_path / nb_path.name)
        page = publishable(tmp_path / nb_path.name, ROOT / "notebooks" / nb_path.name)
        text = json.dumps(page.cells)
        for marker in ("BEGIN SOLUTION", "END SOLUTION", "BEGIN HIDDEN TESTS", "/home/someone"):
            assert marker not in text, (nb_path.name, marker)
        student = {c.metadata["nbgrader"]["grade_id"]: c.source
                   for c in nbformat.read(ROOT / "notebooks" / nb_path.name, 4).cells
                   if c.get("metadata", {}).get("nbgrader", {}).get("grade_id")}
        shown = {c.metadata["nbgrader"]["grade_id"]: c.source for c in page.cells
                 if c.get("metadata", {}).get("nbgrader", {}).get("grade_id")}
        assert shown == student
        assert landing.colab_url(nb_path.name) in text


def test_published_pages_show_no_plumbing(tmp_path):
    """Issue 42, item 4: on every notebook's page the Colab install cell is removed and each cell
    that only calls a helper to show something (display(Markdown(...)), reconcile(...)) has its
    code folded, its output kept; a cell with code being taught is left as it is."""
    from chapter_site.book import is_helper_cell

    for nb_path in sorted((ROOT / "solutions").glob("*.ipynb")):
        page = publishable(nb_path, ROOT / "notebooks" / nb_path.name)
        code = [c for c in page.cells if c.cell_type == "code"]
        install = [c for c in code if "google.colab" in c.source]
        assert len(install) == 1 and "remove-cell" in install[0].metadata["tags"], nb_path.name
        folded = [c for c in code if "hide-input" in c.metadata.get("tags", [])]
        assert folded, f"{nb_path.name}: no helper cell folded"
        assert all(is_helper_cell(c) and not c.metadata.get("nbgrader") for c in folded)
        for c in code:
            if "display(Markdown(" in c.source and c.source.lstrip().startswith("display(") and "\n" not in c.source.strip():
                assert "hide-input" in c.metadata["tags"], (nb_path.name, c.source)
            if "def " in c.source or "raise NotImplementedError" in c.source:
                assert "hide-input" not in c.metadata.get("tags", []), (nb_path.name, c.source[:60])


def test_helper_cells_are_told_from_code_being_taught():
    from chapter_site.book import is_helper_cell

    def cell(src):
        return nbformat.v4.new_code_cell(src)
    assert is_helper_cell(cell('display(Markdown(nb04.exploitation_text(m)))'))
    assert is_helper_cell(cell('from pusht.nb.timing import time_note\n\ntime_note("04")  # how long'))
    assert is_helper_cell(cell('display(Code(inspect.getsource(f)))\nreconcile("ex3", *nb06.ex3_reconciliation(r))'))
    assert not is_helper_cell(cell('fig = nb01.fig_starts()\nshow(fig, "01.png")\ndisplay(Markdown(t))'))
    assert not is_helper_cell(cell('import torch'))                 # an import alone shows nothing
    assert not is_helper_cell(cell('%time display(x)'))             # a magic: not plain Python
    assert not is_helper_cell(cell('nb.display(x)'))                # someone else's display


def test_figures_link_to_their_full_size_and_no_button_is_dead_without_script():
    from chapter_site.sphinx_ext import NEEDS_SCRIPT, enlargeable_figures, no_dead_buttons

    img = '<img alt="../_images/ab12.png" src="../_images/ab12.png" />'
    out = enlargeable_figures(f"<div class=\"cell_output\">{img}</div>")
    assert f'<a class="figure-full" href="../_images/ab12.png" title="Open the figure at full size">{img}</a>' in out
    page = "<noscript><style>.pst-js-only { display: none !important; }</style></noscript>"
    assert all(sel in no_dead_buttons(page) for sel in NEEDS_SCRIPT)


def test_landing_numbers_come_from_meta_and_the_run(smoke_export):
    meta = yaml.safe_load((ROOT / "meta.yaml").read_text())
    html = landing.headline_html(meta)
    for key, _, fmt in landing.HEADLINE:
        assert f'data-key="{key}">{fmt.format(meta["seeds"][0][key])}<' in html
    scrub = landing.scrubber_html(smoke_export)
    last = smoke_export["frames"][-1]
    assert f'data-field="real-reward">{last["real"]["reward_per_step"]:+.3f}<' in scrub
    payload = json.loads(re.search(r'id="scrubber-data">(.*?)</script>', scrub).group(1))
    assert len(payload) == len(smoke_export["frames"])
    assert "</script" not in re.search(r'id="scrubber-data">(.*?)</script>', scrub).group(1)


# -- the reading under the chart ------------------------------------------------------------------

def _run(first, last, success=(0.0, 0.0), config="default", starts=None, horizon=100):
    """A scrubber.json with two kept iterations whose per-start rewards are given as
    (imagined, real) lists."""
    frames = []
    for it, (dream, real), ok in zip((0, 400), (first, last), success):
        d, r = np.asarray(dream, float), np.asarray(real, float)
        frames.append({"iteration": it, "eval": {
            "imagined_return_per_step": float(d.mean()), "real_return_per_step": float(r.mean()),
            "imagination_gap": float(d.mean() - r.mean()), "real_success_rate": ok,
            "imagined_per_start": d.tolist(), "real_per_start": r.tolist()}})
    return {"seed": 0, "config": config, "eval_starts": starts or len(first[0]), "horizon": horizon,
            "imag_iters": 400, "frames": frames}


def _seed0(data, **change):
    last = data["frames"][-1]["eval"]
    return {"seed": 0, "smoke": False, "eval_episodes": data["eval_starts"], "eval_horizon": data["horizon"],
            "imag_iters": 400, **{k: last[k] for k in ("imagined_return_per_step", "real_return_per_step",
                                                       "imagination_gap", "real_success_rate")}, **change}


NOISE = np.array([0.01, -0.012, 0.004, -0.003, 0.006, -0.005])


def test_reading_says_whether_the_last_point_is_the_headline():
    data = _run(([-0.16] * 6 + NOISE, [-0.40] * 6 + NOISE / 2), ([-0.22] * 6 + NOISE, [-0.40] * 6 - NOISE / 3))
    same = _seed0(data)
    assert landing.evaluation_case(data, same) == "same"
    text = landing.reconcile_sentence(data, same)
    last = data["frames"][-1]["eval"]
    assert "is the headline above" in text
    for k in ("imagined_return_per_step", "real_return_per_step", "imagination_gap"):
        assert f"{last[k]:+.3f}" in text
    other_host = _seed0(data, imagination_gap=last["imagination_gap"] + 0.01)
    assert landing.evaluation_case(data, other_host) == "differs"
    assert "not at the headline's gap of" in landing.reconcile_sentence(data, other_host)
    smoke = _run(*[[d[:4], r[:4]] for d, r in (([-0.16] * 6 + NOISE, [-0.4] * 6), ([-0.2] * 6, [-0.4] * 6))],
                 config="smoke", horizon=20)
    assert landing.evaluation_case(smoke, same) == "other"
    text = landing.reconcile_sentence(smoke, same)
    assert "smoke run, 4 starts of 20 steps" in text and "not the headline's 6-start, 100-step" in text


def test_lessons_are_computed_with_their_true_alternatives():
    # the headline's pattern: a gap before training; the dream falls, reality stays, no success
    data = _run(([-0.16] * 6 + NOISE, [-0.40] * 6 + NOISE / 2), ([-0.22] * 6 + NOISE, [-0.40] * 6 - NOISE / 3))
    before, during = landing.lessons(data)
    assert "a gap of +0.240" in before and "rosier before the actor has learned anything" in before
    assert "the dream's reward per step fell by 0.060" in during
    assert "reality's could not be told from no change" in during
    assert "real success was 0% at every kept iteration" in during
    assert "the gap fell by 0.060" in during
    # no gap before training, a dream that rises and a real success
    data = _run(([-0.40] * 6 + NOISE, [-0.40] * 6 - NOISE), ([-0.30] * 6 + NOISE, [-0.35] * 6 + NOISE),
                success=(0.0, 1 / 6))
    before, during = landing.lessons(data)
    assert "cannot be told apart" in before
    assert "the dream's reward per step rose by 0.100" in during and "reality's rose by 0.050" in during
    assert "real success reached 17% (iteration 400)" in during
    # a dream gloomier than reality before training
    before, _ = landing.lessons(_run(([-0.5] * 6 + NOISE, [-0.4] * 6), ([-0.5] * 6, [-0.4] * 6)))
    assert "gloomier than reality" in before
    # beyond the noise but smaller than the minimum effect: not read as a change
    tiny = NOISE / 100
    before, during = landing.lessons(_run(([-0.395] * 6 + tiny, [-0.4] * 6), ([-0.39] * 6 + tiny, [-0.4] * 6)))
    assert "differ by less than the minimum effect" in before
    assert "the dream's reward per step changed by less than the minimum effect (+0.005" in during


def test_curves_panel_draws_the_evaluation_with_labelled_axes(smoke_export):
    meta = yaml.safe_load((ROOT / "meta.yaml").read_text())
    html = landing.curves_html(smoke_export, meta)
    chart = re.search(r'<svg[^>]*id="curve-reward".*?</svg>', html).group(0)
    for label in ("actor training iteration", "reward per step (0.1 s)", "imagined: in the dream",
                  "real: in true PushT"):
        assert label in chart
    first, last = smoke_export["frames"][0]["eval"], smoke_export["frames"][-1]["eval"]
    assert f"gap {first['imagination_gap']:+.3f}" in chart and f"gap {last['imagination_gap']:+.3f}" in chart
    assert 'class="band"' in chart
    assert 'data-case="other"' in html          # the smoke run is not meta.yaml's default evaluation
    assert html.count("<li>") == 2


# -- what to notice in the scrubber ----------------------------------------------------------------

def _frame(it, moved, gap, share, nearer=0.05):
    world = {"block_moved_m": moved, "block_nearer_target_m": nearer, "pusher_min_gap_m": gap,
             "pusher_at_wall_share": share}
    return {"iteration": it, "dream": dict(world), "real": dict(world, block_moved_m=0.0)}


NOTICE = {"imag_iters": 400, "moved_tol_m": 0.02, "touch_tol_m": 0.003, "expert_pusher_at_wall_share": 0.0}


def test_drift_and_leaving_lines_follow_the_frame():
    drift = landing.drift_text(_frame(0, 0.226, 0.086, 0.26, nearer=0.112), NOTICE)
    assert drift.startswith("Drift: with the untrained policy") and "slid 0.226 m" in drift
    assert "0.112 m nearer the target" in drift and "never came within 0.086 m" in drift
    touched = landing.drift_text(_frame(400, 0.1, -0.01, 0.9), NOTICE)
    assert "the trained policy" in touched and "reached the block" in touched and "Drift" not in touched
    still = landing.drift_text(_frame(200, 0.01, 0.1, 0.9), NOTICE)
    assert "stayed within 2 cm" in still and "the policy at iteration 200" in still
    leaving = landing.leaving_text(_frame(400, 0.1, 0.1, 0.94), NOTICE)
    assert leaving.startswith("Leaving the data") and "94%" in leaving and "spends 0%" in leaving
    staying = landing.leaving_text(_frame(0, 0.1, 0.1, 0.004), NOTICE)
    assert "no more than the expert data" in staying and "Leaving" not in staying


def test_scrubber_draws_the_spawn_ghost_and_the_notice_lines(smoke_export):
    from chapter_site import svg

    html = landing.scrubber_html(smoke_export)
    last = smoke_export["frames"][-1]
    scale = 240 / (2 * svg.ARENA_HALF)
    for world in ("dream", "real"):
        ghost = svg.tee_points(*last[world]["block_mm_deg"][0], scale, 240)
        assert f'class="ghost0" points="{ghost[0]}"' in html and f'class="ghost1" points="{ghost[1]}"' in html
    from html import escape
    assert f'data-field="drift">{escape(landing.drift_text(last, smoke_export))}<' in html
    assert f'data-field="leaving">{escape(landing.leaving_text(last, smoke_export))}<' in html
    payload = json.loads(re.search(r'id="scrubber-data">(.*?)</script>', html).group(1).replace("<\\/", "</"))
    for f, p in zip(smoke_export["frames"], payload):
        assert p["readout"]["drift"] == landing.drift_text(f, smoke_export)
        assert p["readout"]["leaving"] == landing.leaving_text(f, smoke_export)
        assert p["dream"]["ghost"] == svg.tee_points(*f["dream"]["block_mm_deg"][0], scale, 240)


# -- the landing page at first sight (issue 42) -------------------------------------------------------

def _headline(gap=0.169, se=0.013, n=100, rate=0.0, **change):
    """meta.yaml's seed 0, as much of it as the sentence reads."""
    return {"imagined_return_per_step": -0.237, "real_return_per_step": -0.237 - gap, "imagination_gap": gap,
            "imagination_gap_eval_horizon": gap, "imagination_gap_se_eval_horizon": se, "eval_episodes": n,
            "real_success_rate": rate, "expert_real_success_rate": 1.0, **change}


def test_the_sentence_reads_the_gap_against_its_noise_with_its_true_alternatives():
    said = landing.verdict(_headline())
    assert "the dream pays more than reality by an imagination gap of" in said
    assert 'data-verdict="imagination_gap">+0.169</strong> ± 0.013 per step' in said
    assert 'solves none of the 100 held-out starts for real (<strong class="num" data-verdict="real_success_rate">0%' in said
    assert "the scripted expert, from the same starts, solves 100%" in said
    assert "the dream pays less than reality" in landing.verdict(_headline(gap=-0.169))
    # beyond the noise (k = 1.98 standard errors over 100 starts) but under the minimum effect
    assert "beyond the noise but under the 0.020 that matters" in landing.verdict(_headline(gap=0.012, se=0.001))
    assert "which 100 starts cannot tell from none" in landing.verdict(_headline(gap=0.03, se=0.02))
    untested = landing.verdict(_headline(imagination_gap_se_eval_horizon=None))
    assert "an imagination gap of" in untested and "±" not in untested
    some = landing.verdict(_headline(rate=0.12))
    assert 'solves <strong class="num" data-verdict="real_success_rate">12%</strong> of the 100' in some
    no_expert = _headline()
    del no_expert["expert_real_success_rate"]
    assert "scripted expert" not in landing.verdict(no_expert)
    # the recorded headline: a gap that matters, and no real success
    seed0 = yaml.safe_load((ROOT / "meta.yaml").read_text())["seeds"][0]
    assert landing.gap_reading(seed0)[0] == "up" and "solves none" in landing.verdict(seed0)


def test_the_first_screen_is_the_title_the_result_and_the_panel_then_the_objectives(smoke_export):
    meta = yaml.safe_load((ROOT / "meta.yaml").read_text())
    notebooks = sorted(p.name for p in (ROOT / "solutions").glob("*.ipynb"))
    text = landing.page(meta, smoke_export, notebooks, "abc1234")
    order = [text.index(s) for s in ("# World Models II", 'id="verdict"', 'id="two-worlds"', "A small world model",
                                     "By the end you can", 'id="curves"', 'id="scrubber"', 'id="colophon"')]
    assert order == sorted(order)
    assert text.count(landing.SOURCES) == 1 and text.index(landing.SOURCES) > text.index('id="colophon"')
    assert "make bench" not in (ROOT / "book" / "intro.md").read_text()      # the developers' line is the colophon's
    for key in ("imagination_gap", "real_success_rate"):
        value = meta["seeds"][0][key]
        shown = f"{value:.0%}" if key == "real_success_rate" else f"{value:+.3f}"
        assert f'data-verdict="{key}">{shown}<' in text


def test_both_measurements_of_the_headline_side_by_side_with_why_they_differ():
    data = dict(_run(([-0.16] * 6 + NOISE, [-0.40] * 6 + NOISE / 2), ([-0.22] * 6 + NOISE, [-0.40] * 6 - NOISE / 3)),
                host="a laptop")
    last = data["frames"][-1]["eval"]

    def html(seed0, run=data):
        return landing.sources_html({"platform": {"cpu_model": "the recording CPU"}, "seeds": {0: seed0}}, run,
                                    ["01_world_model.ipynb", "04_imagination_gap.ipynb"])

    same = html(_seed0(data))
    assert 'data-case="same"' in same and "this build reproduced the record" in same
    assert 'href="notebooks/04_imagination_gap.html#same-policy-two-worlds"' in same
    recorded, built = re.findall(r"<tbody.*?</tbody>", same)
    assert "meta.yaml" in recorded and "the recording CPU" in recorded and "a laptop" in built
    assert f"<td>{last['imagination_gap']:+.3f}</td>" in built and f"<td>{last['real_success_rate']:.0%}</td>" in built
    differs = html(_seed0(data, imagination_gap=last["imagination_gap"] + 0.01))
    assert 'data-case="differs"' in differs and "another commit or on another host" in differs
    other = html(_seed0(data, smoke=True))
    assert 'data-case="other"' in other and "Two different evaluations" in other


def test_charts_draw_in_the_themes_colour_and_the_worlds_in_the_palette(smoke_export):
    from chapter_site import svg
    from pusht import palette

    meta = yaml.safe_load((ROOT / "meta.yaml").read_text())
    html = landing.headline_html(meta) + landing.curves_html(smoke_export, meta) + landing.scrubber_html(smoke_export)
    # text, axes, grid and the pusher follow the page's text colour (light or dark); only the worlds
    # and the target are named colours, one each
    assert set(re.findall(r'(?:fill|stroke)="([^"]+)"', html)) <= {"currentColor", "none", palette.DREAM,
                                                                      palette.REAL, palette.TARGET}
    assert all('fill="currentColor"' in t for t in re.findall(r"<text[^>]*>", html))
    # the dashed line's legend key is dashed as the line is
    wm = re.search(r'<svg[^>]*id="curve-wm".*?</svg>', html).group(0)
    assert (re.findall(r'<polyline class="series"[^>]*stroke-dasharray="([^"]+)"', wm)
            == re.findall(r'<line class="legend-key"[^>]*stroke-dasharray="([^"]+)"', wm) == ["7 4"])
    # the bars hang from 0: no tick above it, and the gap is marked between them
    bars = re.search(r'<svg class="bars".*?</svg>', html).group(0)
    ticks = [float(v) for v in re.findall(r'class="tick" fill="currentColor">(-?[\d.]+)<', bars)]
    assert max(ticks) == 0 and f"{meta['seeds'][0]['imagination_gap']:+.3f}" in bars and 'class="bracket"' in bars
    assert svg.TICK >= 13                 # 10 px and more where a 400-unit chart is drawn 310 px wide or wider


def test_one_colour_per_world_in_the_notebooks_figures_the_recording_and_the_site():
    from matplotlib.colors import to_hex

    from chapter_site import svg
    from pusht import palette, record
    from pusht.nb import closing, gap, horizon

    assert gap.COLORS == horizon.WORLD_COLORS == closing.WORLD_COLORS == palette.WORLD
    assert (svg.DREAM, svg.REAL, svg.TARGET) == (palette.DREAM, palette.REAL, palette.TARGET)
    assert {w: record.COLORS[w] for w in ("dream", "real")} == {w: palette.rgb(c) for w, c in palette.WORLD.items()}
    # the notebooks drew tab:purple and tab:orange before: their figures look as they did
    assert (to_hex("tab:purple"), to_hex("tab:orange"), to_hex("tab:green")) == (palette.DREAM, palette.REAL,
                                                                                   palette.TARGET)


def test_the_font_awesome_script_leaves_every_page_and_the_build(tmp_path):
    from chapter_site.sphinx_ext import drop_fontawesome_script

    scripts = tmp_path / "_static" / "scripts"
    scripts.mkdir(parents=True)
    for name in ("fontawesome.js", "fontawesome.js.map", "fontawesome.js.LICENSE.txt", "bootstrap.js"):
        (scripts / name).write_text("//")
    head = ('<head>\n  <script defer src="{0}_static/scripts/fontawesome.js?digest=55c2"></script>\n'
            '  <script defer src="{0}_static/scripts/bootstrap.js?digest=55c2"></script>\n</head>')
    (tmp_path / "notebooks").mkdir()
    (tmp_path / "index.html").write_text(head.format(""))
    (tmp_path / "notebooks" / "01.html").write_text(head.format("../"))
    assert drop_fontawesome_script(tmp_path) == 2
    for page in (tmp_path / "index.html", tmp_path / "notebooks" / "01.html"):
        text = page.read_text()
        assert "fontawesome" not in text and "bootstrap.js" in text
    assert [p.name for p in scripts.iterdir()] == ["bootstrap.js"]
