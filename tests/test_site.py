"""The chapter site's parts, without a browser (tests/test_site_browser.py opens the built site).

* the scrubber's export trains the chapter's own actor again and its last frame is that actor;
* its evaluation over training is the headline's: the last kept iteration gives the run's own
  imagined and real reward per step, the first the untrained controls';
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
