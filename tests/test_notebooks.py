"""Every chapter notebook runs headless, top to bottom, in a fresh kernel (smoke config).

These run the instructor notebooks in solutions/ with papermill, exactly as CI and `make chapter`
do; a failing cell fails the test with the notebook and the cell named.
"""

import re
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "solutions").glob("*.ipynb"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_headless_in_smoke_mode(path, executed_notebooks):
    out, errors = executed_notebooks
    if errors[path.name]:
        pytest.fail(errors[path.name], pytrace=False)
    nb = nbformat.read(out / path.name, as_version=4)
    images = sum("image/png" in o.get("data", {}) for c in nb.cells for o in c.get("outputs", []))
    assert images >= 1, f"{path.name} produced no figure"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_has_one_parameters_cell_and_a_colab_only_install(path):
    nb = nbformat.read(path, as_version=4)
    tagged = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
    assert len(tagged) == 1
    for name in ("SEED", "SMOKE", "DEVICE", "OUT"):
        assert re.search(rf"^{name} = ", tagged[0].source, re.M), f"{name} missing from parameters"
    install = [c for c in nb.cells if c.cell_type == "code" and '"-m", "pip"' in c.source]
    assert install and all('if "google.colab" in sys.modules:' in c.source for c in install)


def test_student_release_is_in_sync_and_leaks_nothing():
    proc = subprocess.run([sys.executable, "-m", "scripts.release", "--check"], cwd=ROOT,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_release_badges_point_at_the_committed_notebooks():
    import yaml

    course = yaml.safe_load((ROOT / "course.yaml").read_text())
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        first = nbformat.read(path, as_version=4).cells[0].source
        assert (f"https://colab.research.google.com/github/{course['repository']}/blob/"
                f"{course['ref']}/notebooks/{path.name}") in first
        assert f"labpath=notebooks%2F{path.name}" in first
