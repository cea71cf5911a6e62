"""An honest class: hand-ins made the way learners really make them, every one worth full marks.

    python -m autograde.classes.honest OUT.zip --work DIR

Each student is a complete hand-in of every notebook, made from the instructor's answers, and each one
differs from the plain executed solutions in one way learners' hand-ins differ. The notebooks
are really executed (a Jupyter kernel per notebook, smoke config), in the order the learner ran
their cells, restarts included, so receipts, execution counts and outputs are what a kernel
printed, never typed in. ``STUDENTS`` says what each one is; every one must earn every point the
instructor's own solutions earn, completion points included (``tests/test_honest_class.py``).

The front-ends' save formats (JupyterLab 4, VS Code, Colab) are applied to an executed notebook
as those programs write it (their JSON layout and metadata), which is the only thing a save
changes.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import re
import tempfile
import uuid
import zipfile
from pathlib import Path

import nbformat
from ..cellcode import gid, source
from ..course import EXERCISES

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted(p.stem for p in (ROOT / "solutions").glob("*.ipynb"))
OLDER_RELEASE = ROOT / "tests" / "data" / "release_1ba340f"     # notebooks/ as released at 1ba340f
LOOKALIKE = ("victim2", "v\u0456ctim2")                          # the second with a Cyrillic i

STUDENTS = {
    "solutions": "the instructor's solutions, executed top to bottom (the reference hand-in)",
    "filled": "the student release with the answers typed into its cells, run top to bottom",
    "lab4": "'filled', saved by JupyterLab 4 (nbformat 4.5, language_info, timing metadata)",
    "vscode": "'filled', saved by VS Code (its metadata, one stream output per printed line)",
    "colab": "'filled', saved by Colab (nbformat 4.0 without cell ids, Colab metadata)",
    "restart": "locks each prediction, restarts the kernel, runs the rest without the lock cell",
    "relock": "runs each lock cell again after the experiment, to look at it",
    "scratch": "helper and scratch cells that compare each answer with the package's own",
    "duplicate": "answer cells duplicated while experimenting (a draft left above the answer)",
    "older": "notebooks 03-05 from an older release of the chapter (1ba340f)",
    "numeric": "answers in float64, numpy constants and plain Python loops",
    LOOKALIKE[0]: "the solutions, handed in under this id",
    LOOKALIKE[1]: "the solutions, under an id that looks the same (a Cyrillic i)",
}
EXERCISE_NOTEBOOKS = {stem: ex for ex, stem in EXERCISES.items()}     # {"04_imagination_gap": "ex1", ...}


# --- building notebooks ---------------------------------------------------------------------------
def _solution_region(src: str) -> str | None:
    m = re.search(r"^[ \t]*### BEGIN SOLUTION\n(.*?)^[ \t]*### END SOLUTION\n?", src, re.S | re.M)
    return m.group(1) if m else None


def fill(release_nb, solutions_nb):
    """The release with the instructor's answers typed where the learner types theirs: in place of
    ``# YOUR CODE HERE`` / ``raise NotImplementedError()`` and of ``YOUR ANSWER HERE``."""
    nb = copy.deepcopy(release_nb)
    answers = {gid(c): c for c in solutions_nb.cells if gid(c)}
    for cell in nb.cells:
        g = gid(cell)
        if not g or not cell.metadata["nbgrader"].get("solution") or g not in answers:
            continue
        answer = source(answers[g])
        if cell.cell_type == "markdown":
            cell.source = answer
            continue
        region = _solution_region(answer)
        cell.source = re.sub(r"^([ \t]*)# YOUR CODE HERE\n[ \t]*raise NotImplementedError\(\)\n?",
                             lambda _, region=region: region, source(cell), count=1, flags=re.M)
    return nb


def _code_cell(src: str):
    return nbformat.v4.new_code_cell(src)


def _index(nb, grade_id: str) -> int:
    return next(i for i, c in enumerate(nb.cells) if gid(c) == grade_id)


# --- executing notebooks the way a learner runs them ----------------------------------------------
class Session:
    """One notebook open in a Jupyter kernel: run cells in any order, restart, save.

    ``cwd`` is the learner's folder (the prediction store lives there); ``out`` is the shared
    folder for trained stages (the notebooks' ``OUT`` parameter), so later hand-ins load what
    earlier ones trained. The notebook runs its smoke config (``SMOKE = True``, as a learner may
    set it)."""

    def __init__(self, nb, cwd: Path, out: Path, timeout: int = 600):
        from nbclient import NotebookClient
        from traitlets.config import Config

        self.nb = nb
        self.saved: dict = {}           # what a plan saves along the way, by student
        params = next((c for c in nb.cells if "parameters" in c.metadata.get("tags", [])), None)
        if params is not None:
            params.source = re.sub(r"^SMOKE = False", "SMOKE = True", source(params), flags=re.M)
            params.source = re.sub(r'^OUT = "[^"]*"', f"OUT = {str(out)!r}", params.source, flags=re.M)
        self._sockets = tempfile.TemporaryDirectory(prefix="pusht-honest-")
        config = Config()
        config.KernelManager.transport = "ipc"
        config.KernelManager.ip = os.path.join(self._sockets.name, "k")
        self.client = NotebookClient(nb, timeout=timeout, kernel_name="python3", config=config,
                                     resources={"metadata": {"path": str(cwd)}}, allow_errors=False)
        self._ctx = None

    def start(self) -> None:
        self._ctx = self.client.setup_kernel()
        self._ctx.__enter__()

    def restart(self) -> None:
        """As the learner's Kernel > Restart: a new kernel; the outputs already shown stay."""
        self.stop()
        self.start()

    def run(self, *indices: int) -> None:
        for i in indices:
            if self.nb.cells[i].cell_type == "code":
                self.client.execute_cell(self.nb.cells[i], i)

    def stop(self) -> None:
        if self._ctx is not None:
            self._ctx.__exit__(None, None, None)
            self._ctx = None

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop()
        self._sockets.cleanup()


def _code(nb) -> list[int]:
    return [i for i, c in enumerate(nb.cells) if c.cell_type == "code"]


def execute(nb, cwd: Path, out: Path, plan=None) -> dict:
    """Run ``nb`` in a fresh kernel; ``plan(session)`` decides the order (default: top to bottom).
    Returns the notebook as the learner would save it, {None: notebook}, or what the plan saved
    along the way ({student: notebook})."""
    cwd.mkdir(parents=True, exist_ok=True)
    with Session(nb, cwd, out) as s:
        (plan or (lambda s: s.run(*_code(s.nb))))(s)
    return s.saved or {None: nb}


def plan_restart(exercise: str):
    """Run down to the lock, restart, then every other cell again, the lock cell not (the first
    lock is kept on disk, so the experiment finds it)."""
    def plan(s):
        lock = _index(s.nb, f"{exercise}_prediction")
        s.run(*[i for i in _code(s.nb) if i <= lock])
        s.restart()
        s.run(*[i for i in _code(s.nb) if i != lock])
    return plan


def plan_relock(exercise: str):
    """Top to bottom (saved then as "filled"), then the lock cell once more, to look at it (saved
    as "relock")."""
    def plan(s):
        s.run(*_code(s.nb))
        s.saved["filled"] = copy.deepcopy(s.nb)
        s.run(_index(s.nb, f"{exercise}_prediction"))
        s.saved["relock"] = s.nb
    return plan


# --- the front-ends' save formats -----------------------------------------------------------------
def _lines(text):
    return text if isinstance(text, list) else text.splitlines(keepends=True)


def _as_lists(d: dict) -> dict:
    for cell in d["cells"]:
        cell["source"] = _lines(cell["source"])
        for o in cell.get("outputs", []):
            if "text" in o:
                o["text"] = _lines(o["text"])
    return d


LANGUAGE_INFO = {"codemirror_mode": {"name": "ipython", "version": 3}, "file_extension": ".py",
                 "mimetype": "text/x-python", "name": "python", "nbconvert_exporter": "python",
                 "pygments_lexer": "ipython3", "version": "3.11.7"}


def save_lab4(nb) -> bytes:
    """JupyterLab 4 with "record timing" on: nbformat 4.5, cell ids, execution timing metadata."""
    d = _as_lists(json.loads(nbformat.writes(nb)))
    d["nbformat_minor"] = 5
    d["metadata"]["language_info"] = LANGUAGE_INFO
    for k, cell in enumerate(d["cells"]):
        if cell["cell_type"] == "code" and cell.get("execution_count"):
            t = f"2026-11-20T10:{k // 60:02d}:{k % 60:02d}.000000Z"
            cell["metadata"]["execution"] = {"iopub.execute_input": t, "iopub.status.busy": t,
                                             "iopub.status.idle": t, "shell.execute_reply": t}
    return json.dumps(d, indent=1, ensure_ascii=False).encode()


def save_vscode(nb) -> bytes:
    """VS Code's Jupyter extension: its notebook metadata, one stream output per printed line."""
    d = _as_lists(json.loads(nbformat.writes(nb)))
    d["metadata"]["vscode"] = {"interpreter": {"hash": "3c1d2a8b9e"}}
    d["metadata"]["language_info"] = LANGUAGE_INFO
    for cell in d["cells"]:
        outs = []
        for o in cell.get("outputs", []):
            if o.get("output_type") == "stream":
                outs += [{"output_type": "stream", "name": o["name"], "text": [line]} for line in o["text"]]
            else:
                outs.append(o)
        if cell["cell_type"] == "code":
            cell["outputs"] = outs
    return json.dumps(d, indent=1, ensure_ascii=False).encode()


def save_colab(nb) -> bytes:
    """Colab: nbformat 4.0 (no cell ids), its own notebook and cell metadata."""
    d = _as_lists(json.loads(nbformat.writes(nb)))
    d["nbformat_minor"] = 0
    d["metadata"] = {"colab": {"provenance": []}, "kernelspec": {"name": "python3", "display_name": "Python 3"},
                     "language_info": {"name": "python"}}
    for k, cell in enumerate(d["cells"]):
        cell.pop("id", None)
        cell["metadata"]["id"] = f"c{k:04d}aBcD"
        if cell["cell_type"] == "code":
            cell["metadata"]["colab"] = {"base_uri": "https://localhost:8080/"}
            cell["metadata"]["outputId"] = f"o{k:04d}"
            cell["metadata"]["executionInfo"] = {"status": "ok", "timestamp": 1763600000000 + k,
                                                 "user_tz": 0, "elapsed": 40}
    return json.dumps(d, indent=2, ensure_ascii=False).encode()


# --- the learners' own variations of the answers ---------------------------------------------------
SCRATCH = {
    "02_reward": ("reward_impl",
                  "class RewardCheck:\n"
                  "    \"\"\"My own checks; the method is named like the function it checks.\"\"\"\n"
                  "    def reward_from_obs(self, obs):\n"
                  "        return reward_from_obs(obs, torch.zeros(6), torch.ones(6))[0]\n\n\n"
                  "import pusht.reward\n"
                  "from pusht.reward import reward_from_obs as package_reward\n"
                  "_x = torch.randn(4, 6)\n"
                  "print('same as the package:', torch.allclose(RewardCheck().reward_from_obs(_x), "
                  "package_reward(_x, torch.zeros(6), torch.ones(6))[0]),\n"
                  "      torch.allclose(reward_from_obs(_x, 0, 1)[1], pusht.reward.reward_from_obs(_x, 0, 1)[1]))\n"),
    "03_imagination_actor": ("lambda_return_impl",
                             "from pusht.imagination import lambda_return as package_lambda_return\n"
                             "_r, _v = torch.randn(5, 3), torch.randn(6, 3)\n"
                             "print('same as the package:', torch.allclose(lambda_return(_r, _v, 0.9, 0.8), "
                             "package_lambda_return(_r, _v, 0.9, 0.8)))\n"),
    "04_imagination_gap": ("dream_impl",
                           "import pusht.evaluate as ev\n"
                           "from pusht.agent import ActorCritic as _AC\n"
                           "from pusht.world_model import WorldModel as _WM\n"
                           "torch.manual_seed(1)\n"
                           "_wm, _pol = _WM(6, 2, latent_dim=3, hidden_dim=5, embed_dim=4).eval(), policy_of(_AC(8, 2, 6))\n"
                           "with torch.no_grad():\n"
                           "    _mine, _theirs = dream(_wm, _pol, torch.randn(2, 6), 4), ev.dream(_wm, _pol, torch.randn(2, 6), 4)\n"
                           "print('shapes match the package:', _mine[0].shape == _theirs[0].shape)\n"),
    "06_closing_the_gap": ("block_disagreement_impl",
                           "from pusht import ensemble\n"
                           "_f = torch.randn(3, 5, 6)\n"
                           "print('same as the package:', torch.allclose(block_disagreement(_f, torch.ones(6)), "
                           "ensemble.block_disagreement(_f, torch.ones(6))))\n"),
    "07_planning": ("cem_update_impl",
                    "import pusht.plan as plan\n"
                    "_x, _s = torch.randn(2, 10, 3), torch.randn(2, 10)\n"
                    "print('same as the package:', all(torch.allclose(a, b) for a, b in "
                    "zip(cem_update(_x, _s, 4, 0.05), plan.cem_update(_x, _s, 4, 0.05))))\n"),
}

DRAFTS = {   # a first attempt left above the answer cell (a copy of it, metadata and all)
    "02_reward": ("reward_impl", "def reward_from_obs(norm_obs, mean, std):\n    # first try: forgot the yaw\n"
                  "    obs = norm_obs * std + mean\n    pos_err = torch.linalg.vector_norm(obs[..., 2:4], dim=-1)\n"
                  "    return -0.5 * pos_err / POS_SCALE, pos_err, 0 * pos_err\n"),
    "03_imagination_actor": ("lambda_return_impl", "def lambda_return(rewards, values, gamma, lam):\n"
                             "    raise NotImplementedError('draft')\n"),
    "06_closing_the_gap": ("ex3_prediction", None),      # the prediction cell twice: the copy runs again
    "07_planning": ("cem_update_impl", "def cem_update(samples, scores, elites, min_std=0.0):\n"
                    "    # first try: the lowest scores, and no floor\n"
                    "    idx = scores.argsort(dim=1)[:, :elites]\n"
                    "    best = torch.stack([samples[b, idx[b]] for b in range(len(samples))])\n"
                    "    return best.mean(1), best.std(1)\n"),
}

NUMERIC = {
    "02_reward": ("reward_impl", "    ### BEGIN SOLUTION\n",
                  "    ### BEGIN SOLUTION\n"
                  "    obs = norm_obs.double() * torch.as_tensor(std).double() + torch.as_tensor(mean).double()\n"
                  "    pos_err = torch.sqrt((obs[..., 2:4] ** 2).sum(-1))\n"
                  "    ang_err = torch.atan2(obs[..., 4], obs[..., 5]).abs()\n"
                  "    reward = -0.5 * (pos_err / np.float64(POS_SCALE) + ang_err / np.float64(ANG_SCALE))\n"
                  "    as_given = lambda x: x.to(norm_obs.dtype)       # float64 inside, the caller's dtype out\n"
                  "    return as_given(reward), as_given(pos_err), as_given(ang_err)\n"),
    "03_imagination_actor": ("lambda_return_impl", "    ### BEGIN SOLUTION\n",
                             "    ### BEGIN SOLUTION\n"
                             "    H = len(rewards)\n"
                             "    returns = [None] * H\n"
                             "    nxt = values[H]\n"
                             "    t = H - 1\n"
                             "    while t >= 0:\n"
                             "        nxt = rewards[t] + gamma * ((1.0 - lam) * values[t + 1] + lam * nxt)\n"
                             "        returns[t] = nxt\n"
                             "        t -= 1\n"
                             "    return torch.stack(returns)\n"),
    "06_closing_the_gap": ("block_disagreement_impl", "    ### BEGIN SOLUTION\n",
                           "    ### BEGIN SOLUTION\n"
                           "    K = frames.shape[0]\n"
                           "    block = [frames[k][..., 2:4] * std[2:4] for k in range(K)]\n"
                           "    mean = sum(block) / K\n"
                           "    var = sum(((b - mean) ** 2).sum(-1) for b in block) / K\n"
                           "    safe = torch.where(var > 0, var, torch.ones_like(var))\n"
                           "    return torch.where(var > 0, safe ** 0.5, torch.zeros_like(var))\n"),
    "07_planning": ("cem_update_impl", "    ### BEGIN SOLUTION\n",
                    "    ### BEGIN SOLUTION\n"
                    "    B, S = scores.shape\n"
                    "    means, stds = [], []\n"
                    "    for b in range(B):\n"
                    "        order = sorted(range(S), key=lambda j: float(scores[b, j]), reverse=True)[:elites]\n"
                    "        best = samples[b, order].double()\n"
                    "        m = best.mean(0)\n"
                    "        sd = ((best - m) ** 2).sum(0) / np.float64(len(order))\n"
                    "        means.append(m.to(samples.dtype))\n"
                    "        stds.append(torch.clamp(sd ** 0.5, min=np.float64(min_std)).to(samples.dtype))\n"
                    "    return torch.stack(means), torch.stack(stds)\n"),
}


# --- the class --------------------------------------------------------------------------------------
def _runs(name: str, solutions, release) -> dict:
    """{student: (notebook to execute, plan)} of the students whose ``name`` is executed their own way;
    the others hand in the executed solutions, or ``filled`` (as it is, or saved by a front-end)."""
    def filled():
        return fill(release, solutions)

    runs = {"filled": (filled(), None)}
    ex = EXERCISE_NOTEBOOKS.get(name)
    if ex:                           # "relock" goes on in filled's session: one run for the two
        runs["filled"] = (runs["filled"][0], plan_relock(ex))
        runs["restart"] = (filled(), plan_restart(ex))
    if name in SCRATCH:
        nb = filled()
        graded, src = SCRATCH[name]
        nb.cells.insert(_index(nb, graded) + 1, _code_cell(src))
        runs["scratch"] = (nb, None)
    if name in DRAFTS:
        nb = filled()
        graded, src = DRAFTS[name]
        i = _index(nb, graded)
        copy_cell = copy.deepcopy(nb.cells[i])
        copy_cell["id"] = uuid.uuid4().hex[:8]              # a front-end gives the copy a new id
        if src is not None:
            copy_cell.source = src
            nb.cells.insert(i, copy_cell)        # the draft above; the answer below is the last
        else:
            nb.cells.insert(i + 1, copy_cell)    # the same cell twice, one after the other
        runs["duplicate"] = (nb, None)
    if (OLDER_RELEASE / f"{name}.ipynb").exists():
        runs["older"] = (fill(nbformat.read(OLDER_RELEASE / f"{name}.ipynb", as_version=4), solutions), None)
    if name in NUMERIC:
        nb = filled()
        graded, _, new = NUMERIC[name]
        _replace_answer_in_filled(nb, solutions, graded, new)
        runs["numeric"] = (nb, None)
    return runs


def build(executed: Path, work: Path, log=print) -> dict[str, bytes]:
    """{zip member name: bytes} for the whole honest class. ``executed``: the solutions executed
    in smoke mode, with their stage cache (``executed/cache``), as tests/conftest.py makes them;
    ``work``: a folder for the learners' working folders. One notebook runs at a time."""
    solutions = {n: nbformat.read(ROOT / "solutions" / f"{n}.ipynb", as_version=4) for n in NOTEBOOKS}
    release = {n: nbformat.read(ROOT / "notebooks" / f"{n}.ipynb", as_version=4) for n in NOTEBOOKS}
    jobs = {(student, name): run for name in NOTEBOOKS
            for student, run in _runs(name, solutions[name], release[name]).items()}

    def run(key):
        (student, name), (nb, plan) = key, jobs[key]
        log(f"honest class: {student} runs {name}")
        return execute(nb, work / student, executed, plan)

    ran = {}
    for key in jobs:
        ran |= {(student or key[0], key[1]): nb for student, nb in run(key).items()}
    files: dict[str, bytes] = {}
    for name in NOTEBOOKS:
        solved = nbformat.read(executed / f"{name}.ipynb", as_version=4)
        solved.cells = [c for c in solved.cells if "injected-parameters" not in c.metadata.get("tags", [])]
        filled = ran["filled", name]
        saved = {student: filled for student in STUDENTS}            # lab4, vscode, colab: saved again
        saved |= {student: solved for student in ("solutions", *LOOKALIKE)}
        saved |= {student: nb for (student, n), nb in ran.items() if n == name}
        for student, nb in saved.items():
            data = {"lab4": save_lab4, "vscode": save_vscode, "colab": save_colab}.get(
                student, lambda nb: nbformat.writes(nb).encode())(nb)
            files[f"{student}_{name}.ipynb"] = data
    return files


def _replace_answer_in_filled(nb, solutions_nb, grade_id: str, new_region: str) -> None:
    """In a filled cell, the instructor's answer lines replaced by ``new_region`` (which starts with
    the BEGIN SOLUTION marker line, for readability)."""
    answer = _solution_region(source(solutions_nb.cells[_index(solutions_nb, grade_id)]))
    cell = nb.cells[_index(nb, grade_id)]
    cell.source = source(cell).replace(answer, new_region.split("\n", 1)[1])
    if "import numpy as np" not in "".join(source(c) for c in nb.cells):
        cell.source = "import numpy as np\n" + cell.source


def write_zip(out: Path, executed: Path, work: Path, log=print) -> Path:
    with zipfile.ZipFile(out, "w") as zf:
        for name, data in sorted(build(executed, work, log).items()):
            zf.writestr(name, data)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", type=Path)
    p.add_argument("--executed", type=Path, required=True,
                   help="the solutions executed in smoke mode, with their stage cache")
    p.add_argument("--work", type=Path, required=True, help="a folder for the learners' working folders")
    args = p.parse_args(argv)
    print(f"wrote {write_zip(args.out, args.executed, args.work)}")


if __name__ == "__main__":
    main()
