"""The notebook runner behind `make chapter` and the notebook tests."""

import os

import nbformat
import pytest
from scripts.chapter import execute


def _notebook(path, source):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(source)]
    nb.metadata["kernelspec"] = {"name": "python3", "language": "python", "display_name": "Python 3"}
    nbformat.write(nb, path)
    return path


@pytest.mark.slow                  # each of these three executes a notebook in a kernel
@pytest.mark.skipif(os.name != "posix", reason="Unix sockets are used on Linux and macOS only")
def test_kernel_runs_over_private_sockets_without_the_tcp_warning(tmp_path, capfd):
    nb = _notebook(tmp_path / "tiny.ipynb", "print(SMOKE, OUT)")
    out = tmp_path / "out"
    out.mkdir()
    execute(nb, out, smoke=True)
    printed = nbformat.read(out / "tiny.ipynb", 4).cells[-1].outputs[0]["text"]
    assert printed.strip() == f"True {out}"          # parameters reached the kernel
    assert "without encryption" not in capfd.readouterr().err
    assert not [p for p in os.listdir(out) if "ipc" in p or p.startswith("k-")]


@pytest.mark.slow
def test_a_failing_cell_is_reported_by_index(tmp_path):
    import papermill as pm

    nb = _notebook(tmp_path / "bad.ipynb", "raise ValueError('broken on purpose')")
    with pytest.raises(pm.PapermillExecutionError) as info:
        execute(nb, tmp_path, smoke=True)
    assert info.value.ename == "ValueError" and "broken on purpose" in info.value.evalue


# ---- peak kernel memory (issue 10: every notebook under 1.5 GB for Binder's 2 GB) ----

needs_proc = pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="reads /proc (Linux)")


@needs_proc
def test_peak_memory_reads_the_high_water_mark_of_the_matching_child_only():
    import subprocess
    import sys

    from scripts.chapter import PeakMemory

    # 200 MB written (so resident) and freed again before a pause: only the high-water mark keeps it
    code = "import time; b = b'x' * 200_000_000; del b; time.sleep(0.6)  # ALLOC_MARKER"
    other = "import time; b = b'y' * 50_000_000; time.sleep(0.6)"
    with PeakMemory(match=lambda cmd: "ALLOC_MARKER" in " ".join(cmd), interval=0.05) as mem:
        procs = [subprocess.Popen([sys.executable, "-c", c]) for c in (code, other)]
        for p in procs:
            p.wait()
    r = mem.result()
    assert r["measured"] and r["processes"] == 1, r
    assert 200 <= r["peak_rss_mb"] < 200 + 60, r            # the allocation plus the interpreter
    assert r["with_children_peak_rss_mb"] >= r["peak_rss_mb"] and r["child_processes"] == 0


def test_peak_memory_says_so_where_it_cannot_measure(monkeypatch):
    from scripts import chapter

    monkeypatch.setattr(chapter, "memory_measurable", lambda: (False, "not measured: no /proc here"))
    with chapter.PeakMemory() as mem:
        pass
    assert mem.result() == {"measured": False, "reason": "not measured: no /proc here"}


@needs_proc
@pytest.mark.slow
def test_run_notebook_measures_the_kernel_and_cleans_its_progress_bars(tmp_path):
    from scripts.chapter import run_notebook

    src = ("import numpy as np\nfrom tqdm.auto import tqdm\n"
           "for _ in tqdm(range(3)):\n    a = np.ones(300_000_000 // 8)\n    del a\nprint('done')")
    nb = _notebook(tmp_path / "alloc.ipynb", src)
    out = tmp_path / "out"
    out.mkdir()
    r = run_notebook(nb, out, smoke=True)
    # the kernel (python + ipykernel + numpy, ~60-120 MB) plus the 300 MB array; papermill's
    # parent process (this pytest) never held the array
    assert r["measured"] and r["processes"] == 1 and r["status"] == "ok", r
    assert 300 <= r["peak_rss_mb"] < 300 + 250, r
    assert r["progress_bar_outputs_removed"] >= 1
    saved = nbformat.read(out / "alloc.ipynb", 4)
    assert [o.get("text") for o in saved.cells[-1].outputs] == ["done\n"]
    assert "widgets" not in saved.metadata


# ---- frozen progress bars are removed from saved notebooks, nothing else ----

WIDGET = "application/vnd.jupyter.widget-view+json"


def _widget_view(model_id, text):
    return nbformat.v4.new_output("display_data", data={
        WIDGET: {"model_id": model_id, "version_major": 2, "version_minor": 0}, "text/plain": text})


def _model(name, **state):
    return {"model_module": "@jupyter-widgets/controls", "model_module_version": "2.0.0",
            "model_name": name, "state": state}


def _synthetic_executed_notebook():
    """What papermill writes for tqdm.auto here: a widget view whose text/plain fallback is the
    frozen 0% bar (its state under metadata.widgets), or, without ipywidgets, \\r-separated bar
    updates on stderr, one output per update, the last newline sharing an output with a warning."""
    stream = lambda name, text: nbformat.v4.new_output("stream", name=name, text=text)  # noqa: E731
    nb = nbformat.v4.new_notebook()
    widget_cell = nbformat.v4.new_code_cell("for _ in tqdm(range(400)): ...")
    widget_cell.outputs = [
        _widget_view("bar1", "world model:   0%|          | 0/400 [00:00<?, ?it/s]"),
        stream("stdout", "trained\n"),
        _widget_view("slider", "IntSlider(value=3)"),                      # not a bar: kept
        _widget_view("bar2", "HBox(children=(HTML(value=''), FloatProgress(value=0.0)))"),
    ]
    text_cell = nbformat.v4.new_code_cell("for _ in tqdm(range(20)): ...")
    text_cell.outputs = [
        stream("stderr", "\r  0%|          | 0/20 [00:00<?, ?it/s]"),
        stream("stderr", "\r 50%|█████     | 10/20 [00:00<00:00, 49.16it/s]"),
        stream("stderr", "\r100%|██████████| 20/20 [00:00<00:00, 48.90it/s]"),
        stream("stderr", "\n/tmp/ipykernel_1/2.py:5: UserWarning: a real warning\n"
                         "  warnings.warn('a real warning')\n"),
        stream("stderr", "\r0it [00:00, ?it/s]\r3it [00:00, 38362.54it/s]\n"),
        stream("stdout", "epoch: 5 [00:10, loss]\n"),                   # looks like one, is not
        nbformat.v4.new_output("execute_result", data={"text/plain": "42"}, execution_count=2),
    ]
    plain_cell = nbformat.v4.new_code_cell("warnings.warn('kept')")
    plain_cell.outputs = [stream("stderr", "UserWarning: kept\r\n"), stream("stderr", "more 10%|x|\n"),
                          nbformat.v4.new_output("error", ename="ValueError", evalue="v", traceback=["tb"])]
    nb.cells = [nbformat.v4.new_markdown_cell("# title"), widget_cell, text_cell, plain_cell]
    state = {
        "bar1": _model("HBoxModel", children=["IPY_MODEL_h1", "IPY_MODEL_p1", "IPY_MODEL_h2"],
                       layout="IPY_MODEL_l1"),
        "h1": _model("HTMLModel", value="world model: 100%", style="IPY_MODEL_s1"),
        "p1": _model("FloatProgressModel", value=400.0, max=400.0), "h2": _model("HTMLModel", value=""),
        "l1": _model("LayoutModel"), "s1": _model("HTMLStyleModel"),
        "bar2": _model("HBoxModel", children=["IPY_MODEL_h3", "IPY_MODEL_p2"]),
        "h3": _model("HTMLModel", value=""), "p2": _model("IntProgressModel", value=1),
        "slider": _model("IntSliderModel", value=3, layout="IPY_MODEL_l2"), "l2": _model("LayoutModel"),
    }
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {
        "state": state, "version_major": 2, "version_minor": 0}}
    return nb


def test_progress_bars_are_stripped_and_every_other_output_kept():
    from scripts.chapter import strip_progress_bars

    nb = _synthetic_executed_notebook()
    plain_before = [dict(o) for o in nb.cells[3].outputs]
    assert strip_progress_bars(nb) == 2 + 5
    nbformat.validate(nb)
    widget_cell, text_cell, plain_cell = nb.cells[1:]
    assert [o.get("text") or o["data"]["text/plain"] for o in widget_cell.outputs] == [
        "trained\n", "IntSlider(value=3)"]
    assert [(o["output_type"], o.get("name"), o.get("text")) for o in text_cell.outputs] == [
        ("stream", "stderr", "/tmp/ipykernel_1/2.py:5: UserWarning: a real warning\n"
                             "  warnings.warn('a real warning')\n"),
        ("stream", "stdout", "epoch: 5 [00:10, loss]\n"),
        ("execute_result", None, None)]
    assert [dict(o) for o in plain_cell.outputs] == plain_before    # no bar: not even merged
    state = nb.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]["state"]
    assert sorted(state) == ["l2", "slider"]                        # the bars' models went too


def test_a_notebook_of_only_bars_loses_its_widget_state_and_stays_valid(tmp_path):
    from scripts.chapter import clean_saved_notebook, strip_progress_bars

    nb = _synthetic_executed_notebook()
    nb.cells[1].outputs = [nb.cells[1].outputs[i] for i in (0, 3)]           # the two bars only
    for mid in ("slider", "l2"):
        del nb.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]["state"][mid]
    nbformat.write(nb, tmp_path / "x.ipynb")
    assert clean_saved_notebook(tmp_path / "x.ipynb") == 2 + 5
    cleaned = nbformat.read(tmp_path / "x.ipynb", 4)
    assert "widgets" not in cleaned.metadata and cleaned.cells[1].outputs == []
    assert strip_progress_bars(cleaned) == 0                        # idempotent
