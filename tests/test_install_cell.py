"""The Colab install cell: one source (INSTALL_CELL in scripts/release.py) carried verbatim by all seven
instructor notebooks and their student release, and what it tells a learner in Colab.

The cell's logic runs here with a fake pip: ``subprocess.run`` is replaced by a function that writes
the JSON report pip would write (``pip install --report <path>``) at the path the cell asks for,
and ``importlib.metadata.version`` by the versions Colab came with. Both branches: nothing of
Colab's changed (it says what it installed), torch or numpy changed (it says so, asks for a
restart, and stops). `make colab-check` runs the same cell with the real pip on Colab's stack.
"""

from __future__ import annotations

import importlib.metadata
import json
import subprocess
import sys
import tempfile
import types
import zipfile
from pathlib import Path

import nbformat
import pytest

from scripts import release

ROOT = Path(__file__).resolve().parents[1]

SOLUTIONS = sorted((ROOT / "solutions").glob("*.ipynb"))
RELEASED = sorted((ROOT / "notebooks").glob("*.ipynb"))
COLAB = {"torch": "2.11.0", "numpy": "2.1.3"}       # what the fake Colab came with


def test_seven_notebooks_and_their_release():
    assert len(SOLUTIONS) == 7
    assert [p.name for p in RELEASED] == [p.name for p in SOLUTIONS]


@pytest.mark.parametrize("path", SOLUTIONS + RELEASED, ids=[f"{p.parent.name}/{p.stem}" for p in SOLUTIONS + RELEASED])
def test_notebook_carries_exactly_the_rendered_install_cell(path):
    code = [c for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"]
    assert code[0].source == release.install_cell(), (
        f"{path.relative_to(ROOT)}: its first code cell is not INSTALL_CELL of scripts/release.py; "
        "edit the template there, then run make release and make pair")
    assert sum("google.colab" in c.source for c in code) == 1, "one install cell per notebook"


def test_the_rendered_cell_installs_course_yaml_address_and_compiles():
    cell = release.install_cell()
    assert f'"pusht-dreamer @ {release.install_url()}"' in cell
    assert "$" not in cell, "a template placeholder was left unrendered"
    compile(cell, "install-cell", "exec")
    # what tests/test_notebooks.py asks of every pip cell, and the learner's way out
    assert 'if "google.colab" in sys.modules:' in cell and '"-m", "pip"' in cell
    assert "Runtime > Restart session" in cell


def run_cell(monkeypatch, tmp_path, installs, in_colab=True):
    """Execute the install cell with a fake pip whose report lists ``installs`` ((name, version)
    pairs). Returns (pip commands run, printed text, the exception raised or None)."""
    calls = []

    def fake_run(cmd, check=False, **kwargs):
        calls.append(list(cmd))
        report = Path(cmd[cmd.index("--report") + 1])
        assert report.parent == tmp_path, "the report goes to the temporary folder"
        report.write_text(json.dumps({"version": "1", "pip_version": "24.1.2", "install": [
            {"download_info": {"url": "https://example.invalid"}, "is_direct": name == "pusht-dreamer",
             "requested": name == "pusht-dreamer", "metadata": {"name": name, "version": version}}
            for name, version in installs]}))
        return subprocess.CompletedProcess(cmd, 0)

    monkeypatch.setattr(subprocess, "run", fake_run)
    monkeypatch.setattr(importlib.metadata, "version", lambda name: COLAB[name])
    monkeypatch.setattr(tempfile, "gettempdir", lambda: str(tmp_path))
    if in_colab:
        monkeypatch.setitem(sys.modules, "google.colab", types.ModuleType("google.colab"))
    else:
        monkeypatch.delitem(sys.modules, "google.colab", raising=False)
    out, error = [], None
    monkeypatch.setattr("builtins.print", lambda *a, **k: out.append(" ".join(map(str, a))))
    try:
        exec(compile(release.install_cell(), "install-cell", "exec"), {"__name__": "__main__"})
    except RuntimeError as e:
        error = e
    monkeypatch.undo()
    return calls, "\n".join(out), error


def test_outside_colab_the_cell_does_nothing(monkeypatch, tmp_path):
    calls, said, error = run_cell(monkeypatch, tmp_path, [("pusht-dreamer", "0.1.0")], in_colab=False)
    assert calls == [] and said == "" and error is None


def test_colab_unchanged_says_what_it_installed(monkeypatch, tmp_path):
    calls, said, error = run_cell(monkeypatch, tmp_path, [("pusht-dreamer", "0.1.0"), ("pymunk", "7.3.1")])
    assert error is None
    assert len(calls) == 1
    cmd = calls[0]
    assert cmd[:4] == [sys.executable, "-m", "pip", "install"] and cmd[-1] == f"pusht-dreamer @ {release.install_url()}"
    assert f"Installing pusht-dreamer @ {release.install_url()}" in said
    assert "Installed: pusht-dreamer 0.1.0, pymunk 7.3.1" in said
    assert "Colab's torch 2.11.0 and numpy 2.1.3 are unchanged." in said
    assert "Restart" not in said


def test_colab_after_a_restart_nothing_new(monkeypatch, tmp_path):
    _, said, error = run_cell(monkeypatch, tmp_path, [])
    assert error is None
    assert "Installed: nothing new" in said and "are unchanged" in said


def test_colab_same_version_reinstalled_is_not_a_change(monkeypatch, tmp_path):
    _, said, error = run_cell(monkeypatch, tmp_path, [("pusht-dreamer", "0.1.0"), ("numpy", "2.1.3")])
    assert error is None and "Restart" not in said


@pytest.mark.parametrize("name, new", [("numpy", "2.3.5"), ("torch", "2.13.0")])
def test_colab_changed_tells_the_learner_to_restart(monkeypatch, tmp_path, name, new):
    calls, said, error = run_cell(monkeypatch, tmp_path, [("pusht-dreamer", "0.1.0"), (name, new)])
    assert len(calls) == 1
    assert f"Installed: pusht-dreamer 0.1.0, {name} {new}" in said
    assert f"The install replaced Colab's {name} {COLAB[name]} -> {new}" in said
    assert "unchanged" not in said
    assert isinstance(error, RuntimeError), "the cell must stop a Run all"
    assert "Restart the runtime (Runtime > Restart session)" in str(error)


def test_pip_report_has_the_fields_the_cell_reads(tmp_path):
    """The real pip (this venv's) writes a report whose install entries carry metadata name and
    version, the two fields the cell reads: a dry run of a tiny local wheel, offline."""
    wheel = tmp_path / "colab_cell_probe-1.2.3-py3-none-any.whl"
    info = "colab_cell_probe-1.2.3.dist-info"
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr(f"{info}/METADATA", "Metadata-Version: 2.1\nName: colab-cell-probe\nVersion: 1.2.3\n")
        z.writestr(f"{info}/WHEEL", "Wheel-Version: 1.0\nGenerator: test\nRoot-Is-Purelib: true\nTag: py3-none-any\n")
        z.writestr(f"{info}/RECORD", "")
    report = tmp_path / "report.json"
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--dry-run", "--no-index", "--no-deps",
                           "--ignore-installed", "-q", "--report", str(report), str(wheel)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    entries = json.loads(report.read_text())["install"]
    assert [(e["metadata"]["name"].lower(), e["metadata"]["version"]) for e in entries] == [("colab-cell-probe", "1.2.3")]
