"""The instructor notebooks and their text twins (jupytext py:percent, jupytext.toml) agree.

A notebook edited without `make pair`, or a text file edited without syncing back, fails here with
the name of the pair and the first differing line."""

from __future__ import annotations

import difflib
from pathlib import Path

import jupytext
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "solutions").glob("*.ipynb"))
TEXT = ROOT / "text" / "solutions"


def test_pairing_is_configured_outside_the_nbgrader_source():
    assert 'formats = "solutions///ipynb,text/solutions///py:percent"' in (ROOT / "jupytext.toml").read_text()
    assert not list((ROOT / "solutions").glob("*.py")), "text twins must stay out of solutions/ (nbgrader's source)"
    assert not list((ROOT / "notebooks").glob("*.py")), "no text twin may reach the student release"


def test_every_text_twin_has_its_notebook():
    stray = {p.stem for p in TEXT.glob("*.py")} - {p.stem for p in NOTEBOOKS}
    assert not stray, f"text twins without a notebook: {sorted(stray)} (delete them, or run make pair)"


@pytest.mark.parametrize("nb", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_and_text_twin_agree(nb):
    twin = TEXT / f"{nb.stem}.py"
    assert twin.exists(), f"{twin.relative_to(ROOT)} is missing: run make pair"
    expected = jupytext.writes(jupytext.read(nb), fmt="py:percent")
    got = twin.read_text()
    if got != expected:
        diff = list(difflib.unified_diff(got.splitlines(), expected.splitlines(), "text twin", "notebook",
                                         n=1, lineterm=""))
        pytest.fail(f"{nb.name} and {twin.relative_to(ROOT)} drifted; run make pair (the newer file wins). "
                    "First differences:\n" + "\n".join(diff[:20]))
