"""``pusht.nb.setup`` (module ``pusht.nb.session``): the one call of every notebook's set-up cell (config, folders, ``show``)."""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pytest

from pusht.config import make_config
from pusht.nb import GRADING_ENV, Session, setup

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def not_grading(monkeypatch):
    monkeypatch.delenv(GRADING_ENV, raising=False)


@pytest.fixture
def grading(monkeypatch):
    monkeypatch.setenv(GRADING_ENV, "autograde")


def test_config_and_folders_as_the_notebooks_had_them(tmp_path, not_grading):
    out = tmp_path / "out"
    s = setup(3, False, "cpu", str(out))                 # OUT is a string in the parameters cell
    assert isinstance(s, Session)
    assert s.cfg == make_config(smoke=False, seed=3, device="cpu", out=out)
    assert (s.cfg.seed, s.cfg.smoke, s.cfg.device, s.cfg.out) == (3, False, "cpu", out)
    assert s.grading is False
    assert s.cache == out / "cache" and not s.cache.exists()          # run_many and the stages make it
    assert s.figs == out / "figures" and s.figs.is_dir()
    assert s.metrics is None and not (out / "metrics").exists()


def test_metrics_folder_is_made_under_out(tmp_path, not_grading):
    s = setup(0, True, "cpu", tmp_path, metrics="metrics/closing")
    assert s.metrics == tmp_path / "metrics" / "closing" and s.metrics.is_dir()
    assert s.cfg.smoke
    setup(0, True, "cpu", tmp_path, metrics="metrics/closing")        # again: the folders may exist


def test_unpacks_into_the_names_the_notebooks_use(tmp_path, not_grading):
    cfg, GRADING, CACHE, FIGS, METRICS, show = setup(0, True, "cpu", tmp_path, metrics="metrics")
    assert (GRADING, CACHE, FIGS, METRICS) == (False, tmp_path / "cache", tmp_path / "figures",
                                               tmp_path / "metrics")
    assert cfg.seed == 0 and callable(show)


def test_grading_runs_the_reduced_config(tmp_path, grading):
    s = setup(1, False, "cpu", tmp_path)
    assert s.grading is True
    assert s.cfg == make_config(smoke=True, seed=1, device="cpu", out=tmp_path)


def test_show_saves_under_figs_and_shows(tmp_path, not_grading, monkeypatch):
    shown = []
    monkeypatch.setattr(plt, "show", lambda *a, **k: shown.append(True))
    s = setup(0, True, "cpu", tmp_path)
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    s.show(fig, "00_test.png")
    assert (s.figs / "00_test.png").read_bytes().startswith(b"\x89PNG")
    assert shown == [True]
    plt.close(fig)


def test_show_while_grading_only_closes(tmp_path, grading, monkeypatch):
    shown, saved = [], []
    monkeypatch.setattr(plt, "show", lambda *a, **k: shown.append(True))
    s = setup(0, True, "cpu", tmp_path)
    fig, _ = plt.subplots()
    monkeypatch.setattr(fig, "savefig", lambda *a, **k: saved.append(a))
    s.show(fig, "00_test.png")
    assert fig.number not in plt.get_fignums()            # closed
    assert not shown and not saved and list(s.figs.iterdir()) == []
    s.show(None, "00_none.png")      # a pusht.nb.figure function returns None while grading
    assert not shown and list(s.figs.iterdir()) == []


def test_every_notebook_sets_up_with_one_call():
    """The set-up cell (the one after the parameters cell) calls ``setup`` and no longer defines
    the boilerplate it replaces."""
    import nbformat

    for path in sorted((ROOT / "solutions").glob("0*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        p = next(i for i, c in enumerate(nb.cells) if "parameters" in c.metadata.get("tags", []))
        src = nb.cells[p + 1].source
        assert "cfg, GRADING, CACHE, FIGS, METRICS, show = setup(SEED, SMOKE, DEVICE, OUT" in src, path.name
        assert "def show" not in src and "make_config(" not in src, path.name


def test_the_module_is_reachable_under_its_own_name():
    assert sys.modules["pusht.nb.session"].setup is setup
