"""The course's grader as a Gradescope autograder: one hand-in graded, ``results.json`` written.

    python -m autograde.gradescope build OUT.zip [--timeout 120] [--visibility visible] [--confine require]
    python -m autograde.gradescope run          (what the bundle's run_autograder calls, per submission)
    python -m autograde.gradescope check        (what setup.sh calls last: can kernels be confined here?)

``make gradescope`` runs ``build``. The zip is what Gradescope's "Configure Autograder" page takes,
laid out as its specification asks (https://gradescope-autograders.readthedocs.io/en/latest/specs/,
the source of that page: github.com/gradescope/autograder_samples, docs/specs.md):

* ``setup.sh`` and ``run_autograder`` at the root of the zip. Gradescope extracts the zip into
  ``/autograder/source``, runs ``setup.sh`` once, as root, while it builds the assignment's Docker
  image (default base image Ubuntu 22.04, docs/base_images.md; Ubuntu 24.04 can be chosen there),
  and copies ``run_autograder`` to ``/autograder/run_autograder``. For every submission it starts
  a new container from that image (docs/tech.md: "each time students submit a new instance of
  that image is spun up"), puts the student's files in ``/autograder/submission`` and runs
  ``/autograder/run_autograder`` in ``/autograder``, as root; what it prints is kept in
  ``/autograder/results/stdout`` for the instructor, and ``/autograder/results/results.json`` is
  uploaded as the result.
* ``course/``: what grading reads of this package, as the working tree holds it at build time, so
  the grader on Gradescope is the commit built, never fetched later: ``pusht`` (the students'
  kernels import it), ``autograde`` less what no grading step imports or reads (``classes/``, the
  test classes; ``manual_grade.py``, ``dask_preload.py``, ``mark_scheme.yaml``), ``course.yaml``, and
  ``pyproject.toml`` listing only those packages. Not the solutions: ``grading_source/`` holds the
  instructor's notebooks with every solution taken out (``grading_source``: the hidden tests and
  every other cell kept), of which nbgrader makes the same release and gradebook (``build`` checks
  that, ``same_assignment``); the verdicts come from ``autograde/checks.py`` against the package's
  own implementations, never from the solutions. Not the site builder, the tests, the README or docs/.
  ``gradescope.json`` records the commit (and any files that differed from it) with the build's
  settings. ``requirements-gradescope.txt``: what grading needs of ``requirements.txt``, with its
  pins (the loose ones pinned to the versions the building venv holds, the ones this course's CI
  ran).
* ``setup.sh`` installs bubblewrap (apt), Python as CI runs it (3.11: a standalone build that ``uv``,
  installed from PyPI, puts in /opt/pusht-python, since nbgrader 0.9.6 needs 3.11 and Ubuntu 22.04
  has 3.10), a venv in ``course/.venv`` with torch's CPU build from PyTorch's own index
  (https://download.pytorch.org/whl/cpu: the PyPI wheel brings several GB of CUDA libraries a
  grader never uses), the rest from ``requirements-gradescope.txt`` (PyPI), and this package
  (``pip install --no-deps -e course``). Gradescope's image build reaches the internet (its docs
  install with apt and pip in ``setup.sh``, and docs/git_pull.md clones from GitHub at run time).

``run`` grades the hand-in the way ``make grade`` grades a class (``grade.grade_class`` on a
one-student folder: intake, repair, receipts, confined kernels, the probe, the gradebook) and
writes ``results.json`` in the documented schema: a top-level ``score``, ``execution_time`` and
``output`` (plain text: ``output_format`` "text", since file names and notes come from the hand-in),
``stdout_visibility`` "hidden" (the default; the log is the instructor's), and one test per graded
cell of the assignment, in notebook order:

* a hidden-test cell: its score (all or nothing, as ``make grade``), its points as ``max_score``,
  and as ``output`` the line the feedback page prints for it (``checks.judge``'s verdict: "all 9
  checks passed", or the first failing check's hint);
* a completion point (``ex1_order``...): its score and the receipts' verdict;
* a one-sentence answer: a 0-point note that the instructor grades it by hand. Gradescope grades
  by hand in questions of their own, with a rubric, next to the autograder's
  (docs/manual_grading.md: "create more questions via the Edit Outline step"); a point the
  autograder cannot give would only lower every autograder score, so the sentences' 3 points
  belong to a manually graded question, and this note says so, without the mark scheme (results
  are shown at once, while the student may still resubmit).

Each test's ``visibility`` is ``visible`` unless ``build --visibility`` says otherwise (``hidden``,
``after_due_date``, ``after_published``, the spec's values). A graded cell of a notebook the
submission lacks scores 0 and says so: Gradescope grades each submission on its own and keeps the
last, so the notebooks must be submitted together. Nothing of the hidden tests, the solutions or
the mark scheme is written: the solutions and the mark scheme are not in the bundle, and every
string that reaches ``results.json`` or stdout has any line of a hidden test of the assignment's
notebooks (``secret_lines``: of ``course.SOURCE``, the bundle's ``grading_source/``; but lines the
student release shows too) replaced by ``[hidden]``; ``tests/test_gradescope.py`` checks
``results.json`` and stdout for every line of the instructor's hidden tests and solutions. A ``results.json`` saying that grading did not finish is written first, so a crash
or a killed run still leaves one (docs/best_practices.md).

Confinement: ``run`` grades in bubblewrap sandboxes where ``sandbox.available()`` says they start.
Where none starts, a bundle built with ``--confine require`` (the default, ``make gradescope``)
grades nothing and tells the student to ask the instructor, and ``setup.sh``'s last step (``check``)
fails the image build where that is certain (no bubblewrap, or one older than 0.7, as on Gradescope's
default Ubuntu 22.04 image). Only a bundle built with ``--confine allow`` (``make gradescope
CONFINE=allow``) grades there unconfined: the build prints a warning, and every student's
``results.json`` says how it was graded (a visible 0-point test first, and when unconfined the top
of the output). What that means on Gradescope is in docs/gradescope.md ("Confinement on Gradescope").

The root of the container layout is ``$GRADESCOPE_ROOT`` (default ``/autograder``), so tests
emulate it in a temporary folder. How otter-grader builds its Gradescope zip was read for
comparison (ucbds-infra/otter-grader, otter/generate: a ``setup.sh`` that installs its environment
with conda/mamba, a ``run_autograder`` that runs ``run_otter.py``, tests and an
``otter_config.json`` beside them); nothing of it is used here.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import traceback
import zipfile
from pathlib import Path

ROOT_ENV = "GRADESCOPE_ROOT"
DEFAULT_ROOT = "/autograder"
JOBS_ENV = "GRADESCOPE_JOBS"          # grading tasks at once; default: from the container's CPU quota
STUDENT = "student"                   # the hand-in's id in the one-student course
CONFIG = "gradescope.json"            # in the bundle's root: what was built, with which settings
CONFINE = ("require", "allow")        # build --confine: require (the default) grades nothing unconfined
REQUIREMENTS = "requirements-gradescope.txt"
# What grading reads of the working tree: the course's settings, the students' package (the kernels
# import it) and the grader. Not the solutions (the bundle carries GRADING_SOURCE instead: see
# grading_source), the site builder, the tests, the README and docs/, or requirements.txt (setup.sh
# installs from REQUIREMENTS).
VENDORED = ("pyproject.toml", "course.yaml", "pusht", "autograde")
# of those, what no grading step imports or reads: the test classes (autograde/classes: hostile
# hand-ins, honest variants, LMS downloads), the command-line tools for manual grades and Dask
# workers, and the mark scheme (on Gradescope the sentences are a manually graded question)
NOT_NEEDED = re.compile(r"^autograde/(classes/|manual_grade\.py$|dask_preload\.py$|mark_scheme\.yaml$)")
# of those, caches. Grading writes nothing in them: its outputs (students' names, answers, scores)
# go to the course folder (course.COURSE_DIR, course/), which no path of VENDORED holds and which
# _vendored_files leaves out wherever it is. An untracked file is vendored only if it is Python
# source (a new module not committed yet): never a data file, such as an output of a grading run
# from before the course folder left autograde/ (no longer ignored by git there).
NOT_VENDORED = re.compile(r"(^|/)(__pycache__|\.ipynb_checkpoints)(/|$)|\.pyc$")
# what grading imports (autograde/, pusht/, the notebooks' kernels), by their requirements.txt names
GRADING_PACKAGES = ("torch", "pymunk", "numpy", "matplotlib", "tqdm", "pyyaml", "ipykernel", "nbgrader", "nh3",
                    "latex2mathml")
PYTHON = "3.11"                       # as CI runs it (nbgrader 0.9.6 needs 3.11 or newer)
UV = "0.13.9"                         # installs that Python on Gradescope's image (PyPI)
TORCH_INDEX = "https://download.pytorch.org/whl/cpu"
VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")   # the spec's values
MAX_FILES, MAX_DEPTH = 1000, 4        # what is looked at in /autograder/submission
HIDDEN = "[hidden]"
MIN_SECRET_CHARS = 8                  # shorter lines ("else:", "pass") give nothing away
ZIP_TIME = (1980, 1, 1, 0, 0, 0)      # every member's date: the same tree gives the same zip

NOT_HANDED_IN = ("{notebook} is not in this submission, so this scores 0. Gradescope grades each "
                 "submission on its own and keeps your last one: submit all your notebooks together.")
MANUAL_NOTE = ("Graded by hand by your instructor ({points:g} point{s}, in this assignment's manually "
               "graded question), not by the autograder: it adds nothing to the autograder's score.")
MANUAL_MISSING = (" {notebook} is not in this submission, so there is nothing to grade: Gradescope keeps "
                  "only your last submission, so submit all your notebooks together.")


# --- build ---------------------------------------------------------------------------------------
UNCONFINED_BUILD = """\
################################################################################################
WARNING: this bundle grades UNCONFINED wherever no bubblewrap sandbox starts (built with
--confine allow). Gradescope's default image, Ubuntu 22.04, has bubblewrap 0.6.1, too old for the
sandbox, and Docker's default seccomp profile refuses bwrap: there a student's code runs as root
beside the grader, can read the hidden tests and can write its own results.json. Every student's
results will say that grading was not confined. Build without --confine allow (the default,
--confine require) to have such a submission refused instead, and choose Ubuntu 24.04 as the base
image on the Configure Autograder page.
################################################################################################"""


def build(out: Path, timeout: int = 120, visibility: str = "visible", confine: str = "require",
          log=None) -> dict:
    """Write the Gradescope autograder zip to ``out``; returns its ``gradescope.json``.

    ``confine``: "require" (the default) grades nothing where no sandbox starts; "allow" grades
    there unconfined, and says so loudly now (``log``, default stderr) and in every result."""
    from .course import GRADING_SOURCE, ROOT

    log = log or (lambda line: print(line, file=sys.stderr, flush=True))
    if visibility not in VISIBILITIES:
        raise ValueError(f"visibility must be one of {', '.join(VISIBILITIES)}")
    if confine not in CONFINE:
        raise ValueError(f"confine must be one of {', '.join(CONFINE)}")
    files = _vendored_files(ROOT)
    solutions = sorted((ROOT / "solutions").glob("*.ipynb"))
    commit, modified = _git_state(ROOT, files + [p.relative_to(ROOT).as_posix() for p in solutions])
    source = {p.name: grading_source(p.read_text(encoding="utf-8")) for p in solutions}
    same_assignment(solutions, source)
    config = {"commit": commit, "modified": modified, "timeout": int(timeout), "visibility": visibility,
              "confine": confine, "python": PYTHON, "uv": UV, "torch_index": TORCH_INDEX}
    requirements = grading_requirements((ROOT / "requirements.txt").read_text())
    torch = next(line for line in requirements.splitlines() if re.match(r"torch\b", line))
    members = {"setup.sh": (setup_script(torch), 0o755), "run_autograder": (RUN_AUTOGRADER, 0o755),
               CONFIG: (json.dumps(config, indent=1) + "\n", 0o644), REQUIREMENTS: (requirements, 0o644)}
    course = {rel: (ROOT / rel).read_bytes() for rel in files}
    course["pyproject.toml"] = bundle_pyproject(course["pyproject.toml"].decode(), files).encode()
    course.update({f"{GRADING_SOURCE}/{name}": text.encode() for name, text in source.items()})
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".part")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, (text, mode) in members.items():
            _add(zf, name, text.encode(), mode)
        for rel in sorted(course):
            _add(zf, f"course/{rel}", course[rel], 0o644)
    os.replace(tmp, out)
    if confine == "allow":
        log(UNCONFINED_BUILD)
    return config


def _add(zf: zipfile.ZipFile, name: str, data: bytes, mode: int) -> None:
    info = zipfile.ZipInfo(name, ZIP_TIME)
    info.external_attr = (stat.S_IFREG | mode) << 16
    info.compress_type = zipfile.ZIP_DEFLATED
    zf.writestr(info, data)


def _vendored_files(root: Path, course: Path | None = None) -> list[str]:
    """The files of ``VENDORED`` that git would commit (tracked, or new, not ignored and Python
    source), that exist, that grading needs (``NOT_NEEDED``) and that are not in the course folder
    ``course`` (default ``course.COURSE_DIR``)."""
    from .course import COURSE_DIR

    course = Path(course or COURSE_DIR).resolve()

    def git(*args: str) -> list[str]:
        out = subprocess.run(["git", "-C", str(root), "ls-files", "-z", *args, "--", *VENDORED],
                             capture_output=True, check=True).stdout.decode()
        return [n for n in out.split("\0") if n]

    try:
        names = git("-c") + [n for n in git("-o", "--exclude-standard") if n.endswith(".py")]
    except (OSError, subprocess.CalledProcessError):          # not a git checkout: every file but caches,
        names = []                                            # and of the grader only its Python source
        for top in VENDORED:
            p = root / top
            names += [top] if p.is_file() else [q.relative_to(root).as_posix() for q in p.rglob("*") if q.is_file()]
        names = [n for n in names if not n.startswith("autograde/") or n.endswith(".py")]
    return sorted({n for n in names if not NOT_VENDORED.search(n) and not NOT_NEEDED.search(n)
                   and (root / n).is_file() and not (root / n).is_symlink()
                   and not (root / n).resolve().is_relative_to(course)})


def _git_state(root: Path, files: list[str]) -> tuple[str | None, list[str]]:
    """(the commit checked out, those of ``files`` that differ from it), or (None, []) without git."""
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True,
                                check=True, text=True).stdout.strip()
        status = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "-z", "--", *VENDORED,
                                 "solutions"], capture_output=True, check=True).stdout.decode()
    except (OSError, subprocess.CalledProcessError):
        return None, []
    changed = {entry[3:] for entry in status.split("\0") if len(entry) > 3}
    return commit, sorted(changed & set(files))


def bundle_pyproject(text: str, files: list[str]) -> str:
    """pyproject.toml as the bundle holds it: the packages it lists less those not vendored (the
    site builder, the test classes), no readme (not vendored); ``pip install -e`` needs no more."""
    import tomllib

    listed = tomllib.loads(text)["tool"]["setuptools"]["packages"]
    kept = [p for p in listed if f"{p.replace('.', '/')}/__init__.py" in files]
    text, n = re.subn(r"(?m)^packages = \[.*\]$", "packages = " + json.dumps(kept), text)
    text = re.sub(r"(?m)^readme = .*\n", "", text)
    if n != 1 or tomllib.loads(text)["tool"]["setuptools"]["packages"] != kept:
        raise ValueError("pyproject.toml: its [tool.setuptools] packages line could not be rewritten for the bundle")
    return ("# pyproject.toml as the Gradescope bundle holds it (autograde/gradescope.py, bundle_pyproject):\n"
            "# only the packages the bundle carries\n" + text)


SOLUTION_BEGIN, SOLUTION_END = "BEGIN SOLUTION", "END SOLUTION"     # nbgrader's ClearSolutions defaults


def grading_source(text: str) -> str:
    """The instructor's notebook ``text`` (JSON) as the bundle carries it, for nbgrader's
    ``generate_assignment``: every solution taken out, all else kept (the hidden tests, which the
    gradebook must hold, the locked cells, the cell ids and metadata).

    nbgrader replaces each solution region (the lines from one holding ``BEGIN SOLUTION`` to one
    holding ``END SOLUTION``) with its stub, indented as the first line, and a solution cell
    without a region (a one-sentence answer) with its stub whole, before it saves any cell in the
    gradebook (``ClearSolutions`` precedes ``SaveCells``). So the region's lines are dropped here,
    its delimiters kept, and a solution cell without a region is emptied: nbgrader makes the same
    release and gradebook of this as of the solutions (``same_assignment`` checks it at each
    build). Outputs are dropped too (nbgrader clears them anyway)."""
    import nbformat

    nb = nbformat.reads(text, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
        lines, kept, inside, region = cell.source.split("\n"), [], False, False
        for line in lines:
            if SOLUTION_BEGIN in line:
                if inside:
                    raise ValueError(f"a solution region inside another: {cell.source[:200]!r}")
                inside = region = True
                kept.append(line)
            elif SOLUTION_END in line:
                inside = False
                kept.append(line)
            elif not inside:
                kept.append(line)
        if inside:
            raise ValueError(f"a solution region without its end: {cell.source[:200]!r}")
        if region:
            cell.source = "\n".join(kept)
        elif cell.get("metadata", {}).get("nbgrader", {}).get("solution"):
            cell.source = ""
    return nbformat.writes(nb) + "\n"


def same_assignment(solutions: list[Path], source: dict[str, str]) -> None:
    """Raise ValueError unless nbgrader's ``generate_assignment`` makes the same student release and
    the same gradebook (every cell it saves: grade, solution, task and source cells, with their
    sources, hidden tests included, and checksums) of the bundle's notebooks ``source`` ({name:
    JSON}) as of the instructor's ``solutions``."""
    made = []
    with tempfile.TemporaryDirectory(prefix="pusht-gradescope-build-") as tmp:
        for which, notebooks in (("solutions", {p.name: p.read_text(encoding="utf-8") for p in solutions}),
                                 ("bundle", source)):
            made.append(_generated(Path(tmp) / which, notebooks))
    if made[0] != made[1]:
        differ = sorted(k for k in set(made[0]) | set(made[1]) if made[0].get(k) != made[1].get(k))
        raise ValueError("nbgrader makes a different assignment of the bundle's notebooks than of the solutions "
                         f"(grading_source cannot strip them safely): {', '.join(differ[:10])}")


def _generated(course: Path, notebooks: dict[str, str]) -> dict:
    """{what: value} of the assignment nbgrader generates from ``notebooks`` in a new ``course``."""
    import nbformat
    from nbgrader.api import Gradebook

    from .course import ASSIGNMENT, COURSE_ID, HERE, nbgrader_api

    src = course / "source" / ASSIGNMENT
    src.mkdir(parents=True)
    for name, text in notebooks.items():
        (src / name).write_text(text, encoding="utf-8")
    shutil.copy(HERE / "nbgrader_config.py", course / "nbgrader_config.py")
    res = nbgrader_api(course).generate_assignment(ASSIGNMENT, force=True)
    if not res.get("success"):
        raise ValueError(f"nbgrader generate_assignment failed:\n{(res.get('error') or res.get('log') or '')[-3000:]}")
    out = {}
    for path in sorted((course / "release" / ASSIGNMENT).glob("*.ipynb")):
        out[f"release {path.name}"] = json.dumps(nbformat.read(path, as_version=4), sort_keys=True)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        for nb in gb.find_assignment(ASSIGNMENT).notebooks:
            out[f"gradebook {nb.name}"] = json.dumps({
                "grade": sorted((c.name, c.cell_type, c.max_score) for c in nb.grade_cells),
                "solution": sorted(c.name for c in nb.solution_cells),
                "task": sorted((c.name, c.cell_type, c.max_score) for c in nb.task_cells),
                "source": sorted((c.name, c.cell_type, c.locked, c.source, c.checksum) for c in nb.source_cells)})
    return out


def grading_requirements(text: str) -> str:
    """The lines of ``requirements.txt`` that grading needs (``GRADING_PACKAGES``); a loose one is
    pinned to the version this interpreter holds (what CI ran), where it holds one."""
    from importlib import metadata

    found = {}
    for line in text.splitlines():
        spec = line.split("#", 1)[0].strip()
        m = re.match(r"([A-Za-z0-9_.\-]+)\s*(.*)$", spec)
        if m and m[1].lower() in GRADING_PACKAGES:
            name, rest = m[1], m[2].strip()
            if not rest.startswith("=="):
                try:
                    rest = "==" + metadata.version(name).split("+")[0]
                except metadata.PackageNotFoundError:
                    pass
            found[name.lower()] = f"{name}{rest}"
    missing = [p for p in GRADING_PACKAGES if p not in found]
    if missing:
        raise ValueError(f"requirements.txt names no {', '.join(missing)}, which grading needs")
    return ("# What grading needs of requirements.txt (autograde/gradescope.py); loose ones pinned to the\n"
            "# versions of the venv the bundle was built from. setup.sh installs torch first, from\n"
            f"# {TORCH_INDEX}.\n" + "".join(found[p] + "\n" for p in GRADING_PACKAGES))


def setup_script(torch: str) -> str:
    return f"""#!/usr/bin/env bash
# Gradescope runs this once, as root, while it builds the autograder's image (autograde/gradescope.py
# wrote it; docs/gradescope.md). Everything grading needs is installed here; grading
# itself fetches nothing.
set -euo pipefail
SRC="$(cd "$(dirname "${{BASH_SOURCE[0]}}")" && pwd)"         # /autograder/source
COURSE="$SRC/course"
VENV="$COURSE/.venv"
export DEBIAN_FRONTEND=noninteractive PIP_DISABLE_PIP_VERSION_CHECK=1 UV_PYTHON_INSTALL_DIR=/opt/pusht-python
apt-get update -qq
# bubblewrap confines the students' kernels (autograde/sandbox.py) and must be 0.7 or newer (--size):
# Ubuntu 24.04 has 0.9; Ubuntu 22.04 (Gradescope's default image) has 0.6.1, with which a bundle built
# --confine require (the default) fails here, at the check below, and one built --confine allow grades
# unconfined, saying so in every student's results.
apt-get install -y -qq --no-install-recommends ca-certificates bubblewrap util-linux python3 python3-venv
bwrap --version || true
# Python {PYTHON}, as CI runs it, whatever the image's own: uv (PyPI) installs a standalone build.
python3 -m venv /opt/pusht-bootstrap
/opt/pusht-bootstrap/bin/pip install -q "uv=={UV}"
/opt/pusht-bootstrap/bin/uv python install {PYTHON}
/opt/pusht-bootstrap/bin/uv venv --seed --python {PYTHON} "$VENV"
PY="$VENV/bin/python"
# torch's CPU build from PyTorch's index (the PyPI wheel pulls several GB of CUDA libraries that
# grading never uses); requirements-gradescope.txt pins the same version, so pip keeps this one.
"$PY" -m pip install -q --index-url {TORCH_INDEX} "{torch}"
"$PY" -m pip install -q -r "$SRC/{REQUIREMENTS}"
"$PY" -m pip install -q --no-deps -e "$COURSE"
# as make setup: an optional extra of jsonschema that adds seconds to every nbformat import
"$PY" -m pip uninstall -q -y rfc3987-syntax 2>/dev/null || true
# bytecode now: the kernels read the package read-only and would compile it on every import
"$PY" -m compileall -q "$COURSE/pusht" "$COURSE/autograde"
chmod -R a+rX /opt/pusht-python "$VENV" "$COURSE/pusht"        # the students' kernels read these
# last: can kernels be confined here? Fails the image build where a bundle that requires it never can be.
"$PY" -m autograde.gradescope check --config "$SRC/{CONFIG}"
"""


RUN_AUTOGRADER = """#!/usr/bin/env bash
# Gradescope runs this for every submission, as root, in /autograder, in a container of its own:
# it grades /autograder/submission and writes /autograder/results/results.json
# (autograde/gradescope.py; docs/gradescope.md).
export GRADESCOPE_ROOT="${GRADESCOPE_ROOT:-/autograder}"
cd "$GRADESCOPE_ROOT" || exit 1
exec "$GRADESCOPE_ROOT/source/course/.venv/bin/python" -P -m autograde.gradescope run
"""


# --- run -----------------------------------------------------------------------------------------
def run(root: Path | None = None, log=print, sweep=None) -> dict:
    """Grade ``root/submission`` and write ``root/results/results.json``; returns what was written.

    ``root``: the container layout's root (default ``$GRADESCOPE_ROOT``, else ``/autograder``).
    ``sweep``: called once grading is done, before results.json is written (the command line's
    ``_kill_children``: nothing grading started is left to write after it)."""
    started = time.monotonic()
    root = Path(root or os.environ.get(ROOT_ENV) or DEFAULT_ROOT)
    path = root / "results" / "results.json"
    config = bundle_config(root)
    _write_json(path, _unfinished(config))
    secrets: list[str] = []
    say = lambda line: log(redact(str(line), secrets))          # noqa: E731  stdout: the instructor's
    state: dict = {}
    try:
        results = _grade(root / "submission", config, say, secrets, state)
    except Exception:                               # noqa: BLE001  results.json must say something
        say(traceback.format_exc())
        results = {"score": 0.0, "output": "The autograder failed on this submission, so nothing was graded. "
                   "Your instructor can see what went wrong.", "tests": []}
    if confinement(config) == "allow":
        _say_confinement(results, state.get("confined"))
    results.update({"execution_time": round(time.monotonic() - started), "output_format": "text",
                    "test_output_format": "text", "stdout_visibility": "hidden"})
    results = _redacted(results, secrets)
    if sweep is not None:
        for cmd in sweep():
            say(f"killed a process left running after grading: {cmd}")
    _write_json(path, results)
    say(f"results.json: {results['score']:g} points in {len(results['tests'])} tests, written to {path}")
    return results


def bundle_config(root: Path) -> dict:
    """The bundle's ``gradescope.json`` (defaults where it is missing: confinement required)."""
    config = {"timeout": 120, "visibility": "visible", "confine": "require"}
    try:
        config.update(json.loads((root / "source" / CONFIG).read_text()))
    except (OSError, ValueError):
        pass
    return config


def confinement(config: dict) -> str:
    """"require" or "allow": the bundle's ``--confine`` (a bundle built before "allow" says "auto",
    which meant the same; anything else requires a sandbox)."""
    return "allow" if config.get("confine") in ("allow", "auto") else "require"


SANDBOX_TEST = "Grading sandbox: read this"
UNCONFINED_NOTE = (
    "WARNING: your notebooks were graded WITHOUT a sandbox. The autograder could not start one on this "
    "machine, and your instructor set it up to grade without one there, so your code ran with the "
    "autograder's own rights, where it could have changed this result. Your instructor sees this warning "
    "too and may check your result by hand.")
CONFINED_NOTE = (
    "Your notebooks were graded in a sandbox, as they should be. This autograder is set up to grade without "
    "one on a machine where none starts, and would then say so here.")
UNKNOWN_NOTE = (
    "WARNING: this autograder is set up to grade without a sandbox on a machine where none starts, and it "
    "stopped before it could tell whether one started for this submission. Your instructor sees this "
    "warning too.")


def _say_confinement(results: dict, confined: bool | None) -> None:
    """In an "allow" bundle, every result says how it was graded: a 0-point test first, visible at once
    whatever the bundle's visibility, and, when grading was (or may have been) unconfined, the top
    of the output too."""
    note = CONFINED_NOTE if confined else UNCONFINED_NOTE if confined is False else UNKNOWN_NOTE
    results["tests"] = [{"name": SANDBOX_TEST, "score": 0.0, "max_score": 0.0, "output": note,
                         "status": "passed" if confined else "failed", "visibility": "visible"}] + results["tests"]
    if not confined:
        results["output"] = note + "\n\n" + results.get("output", "")


def _unfinished(config: dict | None = None) -> dict:
    results = {"score": 0.0, "output": "Grading did not finish (it ran out of time or memory, or crashed), so "
               "nothing was graded. Check that your notebooks run, then submit again or ask your instructor.",
               "output_format": "text", "stdout_visibility": "hidden", "tests": []}
    if config is not None and confinement(config) == "allow":
        _say_confinement(results, None)
    return results


def _grade(submission: Path, config: dict, log, secrets: list[str], state: dict | None = None) -> dict:
    """Grade the hand-in in ``submission``; ``state["confined"]``: whether a sandbox started."""
    from . import grade, sandbox
    from .course import SOURCE

    state = {} if state is None else state
    secrets[:] = secret_lines(SOURCE)
    work = Path(tempfile.mkdtemp(prefix="pusht-gradescope-"))
    os.chmod(work, 0o755)
    try:
        staged, notes = stage(submission, work / "hand-in" / STUDENT)
        log(f"bundle: commit {config.get('commit')}" + (f", with changes to {', '.join(config['modified'])}"
                                                         if config.get("modified") else "")
            + f"; grading with {Path(grade.__file__).parent} and {sandbox.PACKAGE_DIR}, the assignment from {SOURCE}")
        log(f"hand-in: {', '.join(staged) or 'no notebook of this assignment'}")
        ok, why = sandbox.available()
        state["confined"] = ok
        mode = confinement(config)
        log(f"confinement: {'bubblewrap sandboxes' if ok else 'NONE (' + why + ')'} (bundle built with --confine "
            f"{mode})")
        if not ok:
            log("WARNING: " + ("no sandbox starts here, and this bundle requires one: nothing is graded. Choose "
                               "Ubuntu 24.04 as the base image (bubblewrap 0.7 or newer)" if mode == "require" else
                               "no sandbox starts here, and this bundle allows grading without one: the student's "
                               "code runs as root beside the grader; the student's results say so"))
        report, scores = {}, {}
        if staged:
            if not ok and mode == "require":
                return {"score": 0.0, "tests": [], "output": "The autograder could not start its sandbox on this "
                        "machine, so your notebooks were not graded. Please tell your instructor."}
            course = work / "course"
            course.mkdir()
            # share=False: the shared stages are computed from the instructor's solutions, which the
            # bundle does not hold (one student would never share them anyway)
            report = grade.grade_class(work / "hand-in", course, timeout=int(config.get("timeout", 120)),
                                       jobs=jobs(), log=log, confine=ok, progress=False, share=False).get(STUDENT, {})
            scores = _scores(course)
        return results(staged, notes, report, scores, config.get("visibility", "visible"), log)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def results(staged: list[str], notes: list[str], report: dict, scores: dict, visibility: str,
            log=print) -> dict:
    """results.json from a one-student grading: ``staged`` the notebooks graded, ``notes`` for the
    student, ``report`` ``grade_class``'s entry for the student, ``scores`` {(notebook stem,
    grade id): score} from the gradebook."""
    from . import checks
    from .course import EXERCISES

    tests = []
    for cell in graded_cells():
        name, g, points = cell["notebook"], cell["grade_id"], cell["points"]
        stem = name[:-len(".ipynb")]
        handed = name in staged
        missing = NOT_HANDED_IN.format(notebook=name)
        ex = g[:-len("_order")] if g.endswith("_order") else None
        if g in checks.TESTS:
            verdict = report.get("verdicts", {}).get(g)
            output = (verdict[2] if verdict else "not graded: this notebook could not be read (see the notes above)"
                      ) if handed else missing
            title, score = f"hidden tests of {checks.TESTS[g].function}", scores.get((stem, g), 0.0)
        elif ex in EXERCISES and cell["task"]:
            done = report.get("completion", {}).get(ex)
            output = (done[1] if done else "not graded: this notebook could not be read") if handed else missing
            title, score = f"completion point of {ex}: your prediction locked before the experiment", \
                scores.get((stem, g), 0.0)
        else:
            tests.append({"name": f"{stem}: {g} (graded by hand)", "score": 0.0, "max_score": 0.0,
                          "output": MANUAL_NOTE.format(points=points, s="" if points == 1 else "s")
                          + ("" if handed else MANUAL_MISSING.format(notebook=name)),
                          "visibility": "visible"})
            continue
        tests.append({"name": f"{stem}: {g} ({title})", "score": float(score or 0.0) if handed else 0.0,
                      "max_score": points,
                      "output": output, "visibility": visibility})
    student_notes = notes + [n for n in report.get("notes", []) if "for the instructor" not in n]
    for n in report.get("notes", []):
        if "for the instructor" in n:
            log(f"note for the instructor: {n}")
    auto = [t for t in tests if t["max_score"] > 0]
    score = sum(t["score"] for t in auto)
    top = [f"Notebooks graded: {', '.join(staged)}." if staged else
           "No notebook of this assignment was found in this submission: upload your .ipynb files (in "
           "Jupyter or Colab: File > Download > Download .ipynb)."]
    top.append(f"Automatic points: {score:g} of {sum(t['max_score'] for t in auto):g}. The one-sentence answers "
               f"are graded by hand by your instructor.")
    if student_notes:
        top.append("Notes:\n" + "\n".join(f"- {n}" for n in student_notes))
    for t in tests:
        log(f"{t['score']:g}/{t['max_score']:g}  {t['name']}: {t['output']}")
    return {"score": score, "output": "\n\n".join(top), "tests": tests}


def graded_cells() -> list[dict]:
    """Every graded cell of the assignment, in notebook order: {"notebook", "grade_id", "points",
    "task"}, from the instructor's notebooks' nbgrader metadata (ids and points only)."""
    import nbformat

    from .course import NOTEBOOKS, SOURCE

    out = []
    for name in NOTEBOOKS:
        for cell in nbformat.read(SOURCE / name, as_version=4).cells:
            m = cell.get("metadata", {}).get("nbgrader", {})
            if (m.get("grade") or m.get("task")) and m.get("grade_id"):
                out.append({"notebook": name, "grade_id": m["grade_id"], "points": float(m.get("points", 0)),
                            "task": bool(m.get("task"))})
    return out


def _scores(course: Path) -> dict:
    """{(notebook stem, grade id): score} of the student in the course's gradebook."""
    from nbgrader.api import Gradebook, MissingEntry

    from .course import ASSIGNMENT, COURSE_ID

    out = {}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}", course_id=COURSE_ID) as gb:
        try:
            sub = gb.find_submission(ASSIGNMENT, STUDENT)
        except MissingEntry:
            return out
        for nb in sub.notebooks:
            for g in nb.grades:
                out[(nb.name, g.name)] = float(g.score or 0.0)
    return out


def stage(submission: Path, dest: Path) -> tuple[list[str], list[str]]:
    """Copy the notebooks of the assignment found in ``submission`` (Gradescope's folder: files as
    uploaded, in folders or not) into ``dest``, one student's folder for ``grade_class``, each under
    its own name: (the notebooks staged, notes for the student).

    The folder is the student's: links are never followed, hidden files and folders are skipped,
    at most ``MAX_FILES`` entries ``MAX_DEPTH`` folders deep are looked at, and a file is copied
    up to one byte past the size ``intake`` accepts (which then refuses it, with its note). A name
    is accepted as ``intake`` accepts it (``Copy of 02_reward.ipynb``, ``02_reward (1).ipynb``,
    ``s042_02_reward.ipynb``); a notebook whose name names none of the assignment's
    (``05_horizon_final.ipynb``) is known by its content, as intake knows it (``identify``, from the
    instructor's notebooks); of several files for one notebook the newest is graded."""
    import nbformat

    from . import intake
    from .course import NOTEBOOKS, SOURCE
    from .identify import Identifier

    names = intake.NotebookNames(NOTEBOOKS)     # the intake's own reading of a file name
    identifier = None
    dest.mkdir(parents=True, exist_ok=True)
    found: dict[str, list] = {}
    notes, other = [], []
    for order, (rel, path, st) in enumerate(_walk(submission)):
        if stat.S_ISLNK(st.st_mode):
            notes.append(f"{rel}: a link, not a file, not graded")
            continue
        base = rel.rsplit("/", 1)[-1]
        parsed = names.parse(base) if base.casefold().endswith(".ipynb") else None
        if parsed is None and base.casefold().endswith(".ipynb") and not stat.S_ISLNK(st.st_mode):
            identifier = identifier or Identifier(
                {n: nbformat.read(SOURCE / n, as_version=4) for n in NOTEBOOKS})
            data = _read_capped(path, intake.MAX_NOTEBOOK_BYTES + 1)
            try:
                match = identifier.identify(intake.decode_notebook(data)) if data is not None else None
            except ValueError:
                match = None
            if match is not None and match.notebook:
                notes.append(f"{rel}: graded as {match.notebook}: its name names no notebook of this assignment, "
                             f"but {match.words()}")
                parsed = (None, match.notebook, intake.reupload(base)[1])
            else:
                why = f": {match.words()}" if match is not None else ""
                notes.append(f"{rel}: not a notebook of this assignment ({names.expected}), by its name or by "
                             f"its content{why}; not graded")
                continue
        if parsed is None:
            if base.casefold().endswith(".ipynb"):
                notes.append(f"{rel}: not a notebook of this assignment ({names.expected}), not graded")
            else:
                other.append(rel)
            continue
        found.setdefault(parsed[1], []).append((st.st_mtime, parsed[2], -order, rel, path))
    if other:
        notes.append(f"not graded (not .ipynb notebooks): {', '.join(other[:10])}"
                     + (f" and {len(other) - 10} more" if len(other) > 10 else ""))
    staged = []
    for notebook, group in sorted(found.items()):
        group.sort(reverse=True)
        mtime, _, _, rel, path = group[0]
        data = _read_capped(path, intake.MAX_NOTEBOOK_BYTES + 1)
        if data is None:
            notes.append(f"{rel}: could not be read, not graded")
            continue
        (dest / notebook).write_bytes(data)
        os.utime(dest / notebook, (mtime, mtime))
        staged.append(notebook)
        if len(group) > 1:
            notes.append(f"{notebook}: {len(group)} files for it in this submission; graded {rel}, the newest, "
                         f"not {', '.join(g[3] for g in group[1:])}")
    return staged, notes


def _walk(top: Path, prefix: str = "", depth: int = 0, seen: list | None = None):
    """(path relative to the submission, path, stat) of the files under ``top``: regular files, and
    links (never followed: ``stage`` says they are not graded)."""
    seen = [0] if seen is None else seen
    try:
        entries = sorted(os.scandir(top), key=lambda e: e.name)
    except OSError:
        return
    for e in entries:
        seen[0] += 1
        if seen[0] > MAX_FILES:
            return
        if e.name.startswith(".") or e.name == "__MACOSX":
            continue
        try:
            st = e.stat(follow_symlinks=False)
        except OSError:
            continue
        if stat.S_ISDIR(st.st_mode) and depth < MAX_DEPTH:
            yield from _walk(Path(e.path), f"{prefix}{e.name}/", depth + 1, seen)
        elif stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode):
            yield f"{prefix}{e.name}", Path(e.path), st


def _read_capped(path: Path, cap: int) -> bytes | None:
    """At most ``cap`` bytes of a plain file, never through a link; None if it cannot be opened."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            return None
        return f.read(cap)


def jobs() -> int:
    """Grading tasks at once: ``$GRADESCOPE_JOBS``, else the container's CPU quota rounded up (a
    Gradescope container sees the host's cores but may use half of one by default), at most one
    per core it may run on."""
    from .schedule import default_jobs

    if os.environ.get(JOBS_ENV, "").isdigit() and int(os.environ[JOBS_ENV]) > 0:
        return int(os.environ[JOBS_ENV])
    quota = None
    try:
        q, period = Path("/sys/fs/cgroup/cpu.max").read_text().split()[:2]
        quota = None if q == "max" else int(q) / int(period)
    except (OSError, ValueError):
        try:
            q = int(Path("/sys/fs/cgroup/cpu/cpu.cfs_quota_us").read_text())
            quota = None if q <= 0 else q / int(Path("/sys/fs/cgroup/cpu/cpu.cfs_period_us").read_text())
        except (OSError, ValueError):
            pass
    cores = default_jobs()
    return max(1, min(cores, math.ceil(quota))) if quota else cores


# --- nothing hidden leaks ------------------------------------------------------------------------
def secret_lines(source: Path) -> list[str]:
    """The lines of the notebooks in ``source`` that students never see: inside a hidden-test or
    solution region, or in a solution cell without regions (a one-sentence answer), less lines the
    notebooks also hold outside those (the release shows those). Longest first; lines under
    ``MIN_SECRET_CHARS`` characters are left out. Of the instructor's solutions/, all of those; of
    the bundle's grading_source/, the hidden tests (it holds no solution)."""
    import nbformat

    secret, public = set(), set()
    for path in sorted(Path(source).glob("*.ipynb")):
        for cell in nbformat.read(path, as_version=4).cells:
            lines = [line.strip() for line in cell.get("source", "").splitlines()]
            m = cell.get("metadata", {}).get("nbgrader", {})
            delimited = any(line in ("### BEGIN SOLUTION", "### BEGIN HIDDEN TESTS") for line in lines)
            if m.get("solution") and not delimited:
                secret.update(lines)
                continue
            inside = False
            for line in lines:
                if line in ("### BEGIN SOLUTION", "### BEGIN HIDDEN TESTS"):
                    inside = True
                elif line in ("### END SOLUTION", "### END HIDDEN TESTS"):
                    inside = False
                else:
                    (secret if inside else public).add(line)
    return sorted((s for s in secret - public if len(s) >= MIN_SECRET_CHARS), key=len, reverse=True)


def redact(text: str, secrets: list[str]) -> str:
    for s in secrets:
        if s in text:
            text = text.replace(s, HIDDEN)
    return text


def _redacted(obj, secrets: list[str]):
    if isinstance(obj, str):
        return redact(obj, secrets)
    if isinstance(obj, list):
        return [_redacted(x, secrets) for x in obj]
    if isinstance(obj, dict):
        return {k: _redacted(v, secrets) for k, v in obj.items()}
    return obj


def _write_json(path: Path, obj: dict) -> None:
    """Write ``obj`` to ``path`` whole (a new file renamed over the old: a link there is replaced,
    never followed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".results-")
    with os.fdopen(fd, "w") as f:
        json.dump(obj, f, indent=1)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


# --- what the container leaves running -----------------------------------------------------------
def _become_subreaper() -> bool:
    """Orphans of everything this process starts become its children (PR_SET_CHILD_SUBREAPER), so
    ``_kill_children`` finds even a process that left its session; False where Linux says no."""
    try:
        return ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _kill_children(rounds: int = 50) -> list[str]:
    """SIGKILL every child of this process until none is left (a killed child's own children come
    to this process, a subreaper); returns the start of each killed one's command line."""
    me, killed = str(os.getpid()), []
    for _ in range(rounds):
        kids, zombies = [], []
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                continue
            if fields[1] == me:             # a child; an orphan that already exited is only reaped
                (zombies if fields[0] == "Z" else kids).append(int(pid))
        for pid in zombies:
            try:
                os.waitpid(pid, 0)
            except ChildProcessError:
                pass
        if not kids:
            break
        for pid in kids:
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes()[:120].replace(b"\0", b" ").decode(errors="replace")
                os.kill(pid, signal.SIGKILL)
                killed.append(cmd.strip())
            except (OSError, ProcessLookupError):
                pass
        for pid in kids:
            try:
                os.waitpid(pid, 0)
            except ChildProcessError:
                pass
    return killed


# --- command line --------------------------------------------------------------------------------
MIN_BWRAP = (0, 7)                    # --size, which the sandbox's tmpfs caps use


def bwrap_version() -> tuple[int, ...] | None:
    """The installed bubblewrap's version, or None where there is none (or it does not say)."""
    try:
        out = subprocess.run(["bwrap", "--version"], capture_output=True, text=True, timeout=20).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    m = re.search(r"(\d+)\.(\d+)(?:\.(\d+))?", out)
    return tuple(int(x) for x in m.groups() if x is not None) if m else None


def check(config: dict | None = None, log=print) -> bool:
    """What setup.sh runs last, at image-build time: whether kernels can be confined on this machine
    (a submission's container may differ, and run checks again). False, which fails the image build,
    only where a bundle that requires confinement can never have it here: no bubblewrap, or one older
    than 0.7 (Gradescope's default Ubuntu 22.04 image has 0.6.1); the instructor sees that on the
    Configure Autograder page at once, not in every student's refused submission."""
    from . import sandbox

    mode = confinement(config or {})
    ok, why = sandbox.available()
    log(f"autograde.gradescope: Python {sys.version.split()[0]} at {sys.executable}; confined grading "
        + ("available (bubblewrap)" if ok else f"NOT available here: {why}") + f"; bundle built with --confine {mode}")
    if ok:
        return True
    version = bwrap_version()
    never = version is None or version < MIN_BWRAP
    if mode == "require" and never:
        log(f"ERROR: this bundle grades only in a sandbox (--confine require), and bubblewrap "
            f"{'is not installed' if version is None else '.'.join(map(str, version)) + ' is older than 0.7'} in "
            f"this image: every submission would be refused. Choose Ubuntu 24.04 as the base image on the "
            f"Configure Autograder page (or build the bundle with --confine allow, which grades unconfined here).")
        return False
    log("WARNING: " + ("no sandbox starts while the image is built; each submission checks again, and is refused "
                       "where none starts (--confine require). Try one with Test Autograder." if mode == "require" else
                       "no sandbox starts here, and this bundle grades without one (--confine allow): student "
                       "code would run as root beside the grader, and every student's results will say so."))
    return True


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("build", help="write the autograder zip for Gradescope")
    b.add_argument("out", type=Path)
    b.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    b.add_argument("--visibility", choices=VISIBILITIES, default="visible",
                   help="when students see each automatic test's result (the spec's values)")
    b.add_argument("--confine", choices=CONFINE, default="require",
                   help="require (the default): grade nothing where bubblewrap sandboxes cannot start; allow: "
                        "grade there unconfined, with a warning now and in every student's results")
    sub.add_parser("run", help="grade $GRADESCOPE_ROOT/submission (default /autograder) -> results/results.json")
    c = sub.add_parser("check", help="say whether student code can be confined here (setup.sh runs it)")
    c.add_argument("--config", type=Path, help="the bundle's gradescope.json (its --confine)")
    args = p.parse_args(argv)
    if args.cmd == "build":
        config = build(args.out, args.timeout, args.visibility, args.confine)
        size = args.out.stat().st_size
        print(f"{args.out}: {size / 1024:.0f} KB, commit {config['commit']}"
              + (f" with changes to {len(config['modified'])} files" if config["modified"] else "")
              + f", --confine {config['confine']}: upload it on the assignment's Configure Autograder page")
        return 0
    if args.cmd == "check":
        config = {}
        if args.config is not None:
            try:
                config = json.loads(args.config.read_text())
            except (OSError, ValueError):
                pass
        return 0 if check(config) else 1
    _become_subreaper()
    run(log=lambda line: print(line, flush=True), sweep=_kill_children)
    return 0


if __name__ == "__main__":
    sys.exit(main())
