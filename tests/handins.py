"""Small hand-ins built from the release without executing anything: the student's 02_reward with the
solution's reward_from_obs typed in, and any cells added after its test cell. For tests that grade one
or two students quickly (tests/test_guarantees.py, tests/test_feedback_always.py)."""

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


# a plausible mistake: the reward read off the normalised observation, never put back into metres
FORGOT_TO_UNNORMALISE = ("obs = norm_obs * std + mean", "obs = norm_obs")


def reward_handin(extra_cells=(), source_padding: str = "", markdown: str = "", edit=None) -> dict:
    """02_reward as a student who solved it hands it in (outputs none: it was not run), with
    ``extra_cells`` (code) right after its test cell, ``source_padding`` (a comment) at the end of
    the solution cell, and ``markdown`` as a last markdown cell. ``edit``: an ``(old, new)`` pair
    replaced in the solution (``FORGOT_TO_UNNORMALISE``: a wrong answer)."""
    rel = json.loads((ROOT / "notebooks" / "02_reward.ipynb").read_text())
    sol = json.loads((ROOT / "solutions" / "02_reward.ipynb").read_text())

    def gid(c):
        return c["metadata"].get("nbgrader", {}).get("grade_id")

    src = next("".join(c["source"]) for c in sol["cells"] if gid(c) == "reward_impl")
    src = "".join(line for line in src.splitlines(keepends=True) if line.strip() not in ("### BEGIN SOLUTION", "### END SOLUTION"))
    if edit is not None:
        assert edit[0] in src, f"{edit[0]!r} is not in the solution"
        src = src.replace(edit[0], edit[1])
    at = next(i for i, c in enumerate(rel["cells"]) if gid(c) == "reward_impl_tests")
    for c in rel["cells"]:
        if gid(c) == "reward_impl":
            c["source"] = src + source_padding
    for k, code in enumerate(extra_cells):
        rel["cells"].insert(at + 1 + k, {"cell_type": "code", "id": f"extra-{k}", "metadata": {},
                                         "execution_count": None, "outputs": [], "source": code})
    if markdown:
        rel["cells"].append({"cell_type": "markdown", "id": "extra-md", "metadata": {}, "source": markdown})
    return rel


def unsolved_handin() -> dict:
    """02_reward handed in as released: nothing written, so every test fails (an incomplete hand-in)."""
    return json.loads((ROOT / "notebooks" / "02_reward.ipynb").read_text())


def write_class(folder: Path, students: dict) -> Path:
    """``folder`` holding ``<student>_02_reward.ipynb`` for each of ``students`` ({id: notebook})."""
    folder.mkdir(parents=True, exist_ok=True)
    for sid, nb in students.items():
        (folder / f"{sid}_02_reward.ipynb").write_text(json.dumps(nb))
    return folder
