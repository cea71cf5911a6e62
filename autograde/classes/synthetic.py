"""A synthetic class of submissions that exercises every way a hand-in can go wrong.

    python -m autograde.classes.synthetic OUT.zip --executed DIR

``--executed`` is a folder of the solution notebooks already executed (smoke mode is enough), as a
student's downloaded notebooks would be: with outputs, prediction receipts included. The zip uses
the LMS naming ``<student_id>_<notebook>.ipynb``. Students:

* ``perfect``: every notebook, correct answers, predictions locked before the experiments;
* ``order``: ran Exercise 1's experiment before locking the prediction;
* ``badpred``: an invalid prediction ("z"), so the lock and the experiment both refused;
* ``wrong``: a wrong ``reward_from_obs`` (acos instead of atan2 for the yaw);
* ``raises``: a notebook whose set-up cell raises;
* ``loops``: a solution cell that never returns (the per-cell timeout interrupts it);
* ``tamper``: emptied a locked test cell in one notebook and deleted one in another;
* ``garbage``: a file that is not notebook JSON;
* ``colab``: a correct notebook saved by Colab (``executionInfo`` and ``colab`` metadata).
"""

from __future__ import annotations

import argparse
import copy
import json
import re
import zipfile
from pathlib import Path


def _load(executed: Path, name: str) -> dict:
    """An executed notebook as the student would download it (papermill's injected cell removed)."""
    nb = json.loads((executed / f"{name}.ipynb").read_text())
    nb["cells"] = [c for c in nb["cells"] if "injected-parameters" not in c["metadata"].get("tags", [])]
    return nb


def _cells(nb, pred):
    return [c for c in nb["cells"] if pred(c)]


def _grade_id(cell):
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")


def _src(cell) -> str:
    return "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]


def build(executed: Path) -> dict[str, bytes]:
    """{zip member name: bytes} for the whole synthetic class."""
    names = sorted(p.stem for p in executed.glob("[0-9][0-9]_*.ipynb"))
    files = {f"perfect_{n}.ipynb": json.dumps(_load(executed, n)).encode() for n in names}

    # order: the receipts show the experiment started before the prediction was locked.
    nb = _load(executed, "04_imagination_gap")
    for cell in nb["cells"]:
        for out in cell.get("outputs", []):
            text = "".join(out.get("text", []))
            if "[experiment started] ex1" in text:
                out["text"] = re.sub(r"\(prediction locked at (\S+)\)",
                                     "(prediction locked at 2099-01-01T00:00:00.000+00:00)", text)
            if "[prediction locked] ex1" in text:
                out["text"] = re.sub(r"\[prediction locked\] ex1: \((\w)\) at \S+",
                                     r"[prediction locked] ex1: (\1) at 2099-01-01T00:00:00.000+00:00", text)
    files["order_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    # badpred: the learner's own cell with an invalid choice; its outputs show the refusals.
    nb = _load(executed, "04_imagination_gap")
    for cell in _cells(nb, lambda c: _grade_id(c) == "ex1_prediction"):
        cell["source"] = re.sub(r'PREDICTION = "[a-d]"', 'PREDICTION = "z"', _src(cell))
    for cell in nb["cells"]:
        for out in cell.get("outputs", []):
            if "[prediction locked] ex1" in "".join(out.get("text", [])) or \
                    "[experiment started] ex1" in "".join(out.get("text", [])):
                out["text"] = "ValueError: choice must be one of a, b, c\n"
    files["badpred_04_imagination_gap.ipynb"] = json.dumps(nb).encode()

    # wrong: yaw read with acos (loses the sign and breaks off the unit circle).
    nb = _load(executed, "02_reward")
    for cell in _cells(nb, lambda c: _grade_id(c) == "reward_impl"):
        src = _src(cell)
        cell["source"] = src.replace("torch.atan2(obs[..., 4], obs[..., 5])", "torch.acos(obs[..., 5])")
        assert cell["source"] != src, "the reference reward_from_obs changed: update autograde/classes/synthetic.py"
    files["wrong_02_reward.ipynb"] = json.dumps(nb).encode()

    # raises: the set-up cell fails, so everything after it fails too.
    nb = _load(executed, "03_imagination_actor")
    setup = next(c for c in nb["cells"] if c["cell_type"] == "code" and "setup(SEED" in _src(c))
    setup["source"] = "raise RuntimeError('my notebook is broken')\n" + _src(setup)
    files["raises_03_imagination_actor.ipynb"] = json.dumps(nb).encode()

    # loops: the learner's function never returns.
    nb = _load(executed, "02_reward")
    for cell in _cells(nb, lambda c: _grade_id(c) == "reward_impl"):
        cell["source"] = _src(cell).replace("### BEGIN SOLUTION\n",
                                            "### BEGIN SOLUTION\n    while True:\n        pass\n", 1)
    files["loops_02_reward.ipynb"] = json.dumps(nb).encode()

    # tamper: a locked test cell emptied in one notebook, deleted in another.
    nb = _load(executed, "03_imagination_actor")
    for cell in _cells(nb, lambda c: _grade_id(c).endswith("_tests")):
        cell["source"] = "pass\n"
    files["tamper_03_imagination_actor.ipynb"] = json.dumps(nb).encode()
    nb = _load(executed, "02_reward")
    nb["cells"] = [c for c in nb["cells"] if not _grade_id(c).endswith("_tests")]
    files["tamper_02_reward.ipynb"] = json.dumps(nb).encode()

    files["garbage_04_imagination_gap.ipynb"] = b"{ this is not a notebook"

    # colab: the metadata Colab adds when you download a notebook.
    nb = copy.deepcopy(_load(executed, "02_reward"))
    nb["metadata"]["colab"] = {"provenance": [], "name": "02_reward.ipynb"}
    nb["metadata"]["accelerator"] = "GPU"
    for i, cell in enumerate(nb["cells"]):
        cell["metadata"]["id"] = f"cell{i:04d}"
        if cell["cell_type"] == "code":
            cell["metadata"]["executionInfo"] = {"status": "ok", "timestamp": 1760000000000 + i,
                                                 "user_tz": 0, "elapsed": 12}
            cell["metadata"]["colab"] = {"base_uri": "https://localhost:8080/"}
    files["colab_02_reward.ipynb"] = json.dumps(nb).encode()
    return files


def write_zip(out: Path, executed: Path) -> Path:
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in sorted(build(executed).items()):
            zf.writestr(name, data)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--executed", type=Path, required=True)
    args = p.parse_args(argv)
    print(f"wrote {write_zip(args.out, args.executed)}")


if __name__ == "__main__":
    main()
