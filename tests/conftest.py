"""Shared, expensive fixtures: each chapter notebook is executed once per test session."""

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
NOTEBOOKS = sorted((ROOT / "solutions").glob("*.ipynb"))


@pytest.fixture(scope="session")
def executed_notebooks(tmp_path_factory):
    """Run every instructor notebook headless in smoke mode, in order, sharing one OUT folder as
    `make chapter` does. Returns (folder of executed notebooks, {name: error message or None})."""
    import papermill as pm
    from chapter import execute

    out = tmp_path_factory.mktemp("executed")
    errors = {}
    for path in NOTEBOOKS:
        try:
            execute(path, out, smoke=True)
            errors[path.name] = None
        except pm.PapermillExecutionError as e:
            errors[path.name] = (f"{path.name}: cell {e.cell_index} (execution count {e.exec_count}) "
                                 f"raised {e.ename}: {e.evalue}")
    return out, errors
