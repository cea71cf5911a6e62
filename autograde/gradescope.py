"""The course's grader as a Gradescope autograder: one hand-in graded, ``results.json`` written.

    python -m autograde.gradescope build OUT.zip [--timeout 120] [--visibility visible] [--confine auto]
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
* ``course/``: this package's source (``pusht``, ``autograde``, the solutions, ``course.yaml``,
  ``pyproject.toml``) as the working tree holds it at build time, so the grader on Gradescope is the
  commit built, never fetched later; ``gradescope.json`` records that commit (and any files that
  differed from it) with the build's settings. ``requirements-gradescope.txt``: what grading needs
  of ``requirements.txt``, with its pins (the loose ones pinned to the versions the building venv
  holds, the ones this course's CI ran).
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
the mark scheme is written: every string that reaches ``results.json`` or stdout has any line of
a hidden test or solution region of the instructor's notebooks (but lines the student release
shows too) replaced by ``[hidden]``, and ``tests/test_gradescope.py`` checks ``results.json`` for
each such line. A ``results.json`` saying that grading did not finish is written first, so a crash
or a killed run still leaves one (docs/best_practices.md).

Confinement: ``run`` grades in bubblewrap sandboxes where ``sandbox.available()`` says they start;
otherwise unconfined, with the warning in stdout, unless the bundle was built with ``--confine
require`` (then nothing is graded and the student is told to ask the instructor). What that means
on Gradescope is in the README ("Grading on Gradescope").

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
REQUIREMENTS = "requirements-gradescope.txt"
VENDORED = ("pyproject.toml", "README.md", "requirements.txt", "course.yaml", "solutions", "pusht",
            "autograde", "chapter_site")          # the package as pyproject.toml lists it, and the course
NOT_VENDORED = re.compile(r"(^|/)(__pycache__|\.ipynb_checkpoints)(/|$)|\.pyc$|^autograde/(source|release|"
                          r"submitted|autograded|feedback|shared_stages)/|^autograde/(gradebook\.db|gradebook\."
                          r"template\.db|grades\.csv|report\.csv|manual_grades\.csv|graded\.json|\.grading\.lock|"
                          r"canvas_import\.csv|moodle_import\.csv|lms_export_notes\.txt|class_report\.html)$")
# what grading imports (autograde/, pusht/, the notebooks' kernels), by their requirements.txt names
GRADING_PACKAGES = ("torch", "pymunk", "numpy", "matplotlib", "tqdm", "pyyaml", "ipykernel", "nbgrader", "nh3")
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
def build(out: Path, timeout: int = 120, visibility: str = "visible", confine: str = "auto") -> dict:
    """Write the Gradescope autograder zip to ``out``; returns its ``gradescope.json``."""
    from .course import ROOT

    if visibility not in VISIBILITIES:
        raise ValueError(f"visibility must be one of {', '.join(VISIBILITIES)}")
    if confine not in ("auto", "require"):
        raise ValueError("confine must be auto or require")
    files = _vendored_files(ROOT)
    commit, modified = _git_state(ROOT, files)
    config = {"commit": commit, "modified": modified, "timeout": int(timeout), "visibility": visibility,
              "confine": confine, "python": PYTHON, "uv": UV, "torch_index": TORCH_INDEX}
    requirements = grading_requirements((ROOT / "requirements.txt").read_text())
    torch = next(line for line in requirements.splitlines() if re.match(r"torch\b", line))
    members = {"setup.sh": (setup_script(torch), 0o755), "run_autograder": (RUN_AUTOGRADER, 0o755),
               CONFIG: (json.dumps(config, indent=1) + "\n", 0o644), REQUIREMENTS: (requirements, 0o644)}
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".part")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, (text, mode) in members.items():
            _add(zf, name, text.encode(), mode)
        for rel in files:
            _add(zf, f"course/{rel}", (ROOT / rel).read_bytes(), 0o644)
    os.replace(tmp, out)
    return config


def _add(zf: zipfile.ZipFile, name: str, data: bytes, mode: int) -> None:
    info = zipfile.ZipInfo(name, ZIP_TIME)
    info.external_attr = (stat.S_IFREG | mode) << 16
    info.compress_type = zipfile.ZIP_DEFLATED
    zf.writestr(info, data)


def _vendored_files(root: Path) -> list[str]:
    """The files of ``VENDORED`` that git would commit (tracked, or new and not ignored), that exist."""
    try:
        out = subprocess.run(["git", "-C", str(root), "ls-files", "-z", "-co", "--exclude-standard", "--",
                              *VENDORED], capture_output=True, check=True).stdout.decode()
        names = [n for n in out.split("\0") if n]
    except (OSError, subprocess.CalledProcessError):          # not a git checkout: every file but caches
        names = []
        for top in VENDORED:
            p = root / top
            names += [top] if p.is_file() else [q.relative_to(root).as_posix() for q in p.rglob("*") if q.is_file()]
    return sorted({n for n in names if not NOT_VENDORED.search(n) and (root / n).is_file()
                   and not (root / n).is_symlink()})


def _git_state(root: Path, files: list[str]) -> tuple[str | None, list[str]]:
    """(the commit checked out, the vendored files that differ from it), or (None, []) without git."""
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True,
                                check=True, text=True).stdout.strip()
        status = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "-z", "--", *VENDORED],
                                capture_output=True, check=True).stdout.decode()
    except (OSError, subprocess.CalledProcessError):
        return None, []
    changed = {entry[3:] for entry in status.split("\0") if len(entry) > 3}
    return commit, sorted(changed & set(files))


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
# wrote it; README, "Grading on Gradescope"). Everything grading needs is installed here; grading
# itself fetches nothing.
set -euo pipefail
SRC="$(cd "$(dirname "${{BASH_SOURCE[0]}}")" && pwd)"         # /autograder/source
COURSE="$SRC/course"
VENV="$COURSE/.venv"
export DEBIAN_FRONTEND=noninteractive PIP_DISABLE_PIP_VERSION_CHECK=1 UV_PYTHON_INSTALL_DIR=/opt/pusht-python
apt-get update -qq
# bubblewrap confines the students' kernels (autograde/sandbox.py) and must be 0.7 or newer (--size):
# Ubuntu 24.04 has 0.9; Ubuntu 22.04 has 0.6.1, with which grading runs unconfined (run's log says so).
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
"$PY" -m autograde.gradescope check
"""


RUN_AUTOGRADER = """#!/usr/bin/env bash
# Gradescope runs this for every submission, as root, in /autograder, in a container of its own:
# it grades /autograder/submission and writes /autograder/results/results.json
# (autograde/gradescope.py; README, "Grading on Gradescope").
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
    _write_json(path, _unfinished())
    secrets: list[str] = []
    say = lambda line: log(redact(str(line), secrets))          # noqa: E731  stdout: the instructor's
    try:
        results = _grade(root / "submission", config, say, secrets)
    except Exception:                               # noqa: BLE001  results.json must say something
        say(traceback.format_exc())
        results = {"score": 0.0, "output": "The autograder failed on this submission, so nothing was graded. "
                   "Your instructor can see what went wrong.", "tests": []}
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
    """The bundle's ``gradescope.json`` (defaults where it is missing)."""
    config = {"timeout": 120, "visibility": "visible", "confine": "auto"}
    try:
        config.update(json.loads((root / "source" / CONFIG).read_text()))
    except (OSError, ValueError):
        pass
    return config


def _unfinished() -> dict:
    return {"score": 0.0, "output": "Grading did not finish (it ran out of time or memory, or crashed), so "
            "nothing was graded. Check that your notebooks run, then submit again or ask your instructor.",
            "output_format": "text", "stdout_visibility": "hidden", "tests": []}


def _grade(submission: Path, config: dict, log, secrets: list[str]) -> dict:
    from . import grade, sandbox
    from .course import ROOT

    secrets[:] = secret_lines(ROOT / "solutions")
    work = Path(tempfile.mkdtemp(prefix="pusht-gradescope-"))
    os.chmod(work, 0o755)
    try:
        staged, notes = stage(submission, work / "hand-in" / STUDENT)
        log(f"bundle: commit {config.get('commit')}" + (f", with changes to {', '.join(config['modified'])}"
                                                         if config.get("modified") else "")
            + f"; grading with {Path(grade.__file__).parent} and {sandbox.PACKAGE_DIR}")
        log(f"hand-in: {', '.join(staged) or 'no notebook of this assignment'}")
        report, scores = {}, {}
        if staged:
            ok, why = sandbox.available()
            log(f"confinement: {'bubblewrap sandboxes' if ok else 'NONE (' + why + ')'}")
            if not ok and config.get("confine") == "require":
                return {"score": 0.0, "tests": [], "output": "The autograder could not start its sandbox on this "
                        "machine, so your notebooks were not graded. Please tell your instructor."}
            course = work / "course"
            course.mkdir()
            report = grade.grade_class(work / "hand-in", course, timeout=int(config.get("timeout", 120)),
                                       jobs=jobs(), log=log, progress=False).get(STUDENT, {})
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

    from .course import NOTEBOOKS, ROOT

    out = []
    for name in NOTEBOOKS:
        for cell in nbformat.read(ROOT / "solutions" / name, as_version=4).cells:
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
    ``s042_02_reward.ipynb``); of several files for one notebook the newest is graded."""
    from . import intake
    from .course import NOTEBOOKS

    names = intake._Names(NOTEBOOKS)     # the intake's own reading of a file name
    dest.mkdir(parents=True, exist_ok=True)
    found: dict[str, list] = {}
    notes, other = [], []
    for order, (rel, path, st) in enumerate(_walk(submission)):
        if stat.S_ISLNK(st.st_mode):
            notes.append(f"{rel}: a link, not a file, not graded")
            continue
        base = rel.rsplit("/", 1)[-1]
        parsed = names.parse(base) if base.casefold().endswith(".ipynb") else None
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
def secret_lines(solutions: Path) -> list[str]:
    """The lines of the instructor's notebooks that students never see: inside a hidden-test or
    solution region, or in a solution cell without regions (a one-sentence answer), less lines the
    notebooks also hold outside those (the release shows those). Longest first; lines under
    ``MIN_SECRET_CHARS`` characters are left out."""
    import nbformat

    secret, public = set(), set()
    for path in sorted(Path(solutions).glob("*.ipynb")):
        for cell in nbformat.read(path, as_version=4).cells:
            lines = [l.strip() for l in cell.get("source", "").splitlines()]
            m = cell.get("metadata", {}).get("nbgrader", {})
            delimited = any(l in ("### BEGIN SOLUTION", "### BEGIN HIDDEN TESTS") for l in lines)
            if m.get("solution") and not delimited:
                secret.update(lines)
                continue
            inside = False
            for l in lines:
                if l in ("### BEGIN SOLUTION", "### BEGIN HIDDEN TESTS"):
                    inside = True
                elif l in ("### END SOLUTION", "### END HIDDEN TESTS"):
                    inside = False
                else:
                    (secret if inside else public).add(l)
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
def check(log=print) -> bool:
    """What setup.sh prints last: whether kernels can be confined on this machine (at image-build
    time; a submission's container may differ, and run says again)."""
    from . import sandbox

    ok, why = sandbox.available()
    log(f"autograde.gradescope: Python {sys.version.split()[0]} at {sys.executable}; confined grading "
        + ("available (bubblewrap)" if ok else f"NOT available here: {why}"))
    return ok


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("build", help="write the autograder zip for Gradescope")
    b.add_argument("out", type=Path)
    b.add_argument("--timeout", type=int, default=120, help="seconds per cell before it is interrupted")
    b.add_argument("--visibility", choices=VISIBILITIES, default="visible",
                   help="when students see each automatic test's result (the spec's values)")
    b.add_argument("--confine", choices=("auto", "require"), default="auto",
                   help="require: grade nothing where bubblewrap sandboxes cannot start")
    sub.add_parser("run", help="grade $GRADESCOPE_ROOT/submission (default /autograder) -> results/results.json")
    sub.add_parser("check", help="say whether student code can be confined here")
    args = p.parse_args(argv)
    if args.cmd == "build":
        config = build(args.out, args.timeout, args.visibility, args.confine)
        size = args.out.stat().st_size
        print(f"{args.out}: {size / 1024:.0f} KB, commit {config['commit']}"
              + (f" with changes to {len(config['modified'])} files" if config["modified"] else "")
              + ": upload it on the assignment's Configure Autograder page")
        return 0
    if args.cmd == "check":
        check()
        return 0
    _become_subreaper()
    run(log=lambda line: print(line, flush=True), sweep=_kill_children)
    return 0


if __name__ == "__main__":
    sys.exit(main())
