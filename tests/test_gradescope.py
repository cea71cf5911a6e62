"""The Gradescope autograder bundle (autograde/gradescope.py): its zip as Gradescope's specification
lays it out, and its run_autograder grading one hand-in in an emulated /autograder.

The emulation is what Gradescope's image holds after setup.sh, less the installs: the zip
extracted into source/, run_autograder copied to the root, and in source/course/.venv the venv
these tests run in, cloned with hard links (a second or so), with this package installed from the
bundle's own copy (a path entry, as ``pip install -e`` makes one) instead of from the working tree.
So the code that grades is the bundle's, in confined kernels where bubblewrap works here.
"""

import json
import os
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import nbformat
import pytest
import yaml

from autograde import grade, gradescope, sandbox
from autograde.course import GRADING_SOURCE, NOTEBOOKS

pytestmark = pytest.mark.slow          # builds the bundle (pip, nbgrader) and grades in the sandbox

ROOT = Path(__file__).resolve().parents[1]


VISIBILITY = ["hidden", "after_due_date", "after_published", "visible"]
FORMATS = ["text", "html", "simple_format", "md", "ansi"]
# results.json as https://gradescope-autograders.readthedocs.io/en/latest/specs/ documents it; no other key
SCHEMA = {
    "type": "object", "additionalProperties": False,
    "properties": {
        "score": {"type": "number"}, "execution_time": {"type": "number"}, "output": {"type": "string"},
        "output_format": {"enum": FORMATS}, "test_output_format": {"enum": FORMATS},
        "test_name_format": {"enum": FORMATS}, "visibility": {"enum": VISIBILITY},
        "stdout_visibility": {"enum": VISIBILITY}, "extra_data": {"type": "object"},
        "tests": {"type": "array", "items": {
            "type": "object", "additionalProperties": False,
            "properties": {
                "score": {"type": "number"}, "max_score": {"type": "number"}, "status": {"enum": ["passed", "failed"]},
                "name": {"type": "string"}, "name_format": {"enum": FORMATS}, "number": {"type": "string"},
                "output": {"type": "string"}, "output_format": {"enum": FORMATS},
                "tags": {"type": "array", "items": {"type": "string"}}, "visibility": {"enum": VISIBILITY},
                "extra_data": {"type": "object"}}}},
        "leaderboard": {"type": "array"}},
    "anyOf": [{"required": ["score"]}, {"properties": {"tests": {"items": {"required": ["score"]}}}}],
}
def _automatic_points() -> float:
    """What the grader gives by itself for full marks: every hidden-test cell's points and every
    completion point (the ``exN_order`` tasks), read from the instructor's notebooks' own metadata
    (notebooks 02-07: six hidden-test cells, 4+4+4+3+4+4, and four completion points)."""
    total = 0.0
    for name in NOTEBOOKS:
        for c in nbformat.read(ROOT / "solutions" / name, as_version=4).cells:
            meta = c.metadata.get("nbgrader", {})
            if meta.get("grade_id", "").endswith(("_tests", "_order")):
                total += float(meta.get("points", 0))
    return total


AUTOMATIC = _automatic_points()


# --- the bundle ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    out = tmp_path_factory.mktemp("bundle") / "autograder.zip"
    assert gradescope.main(["build", str(out)]) == 0
    return out


def test_the_zip_is_laid_out_as_gradescope_asks(bundle):
    with zipfile.ZipFile(bundle) as zf:
        infos = {i.filename: i for i in zf.infolist()}
        for script in ("setup.sh", "run_autograder"):          # at the root, executable, bash
            assert script in infos
            assert (infos[script].external_attr >> 16) & 0o111 == 0o111, script
            text = zf.read(script).decode()
            assert text.startswith("#!/usr/bin/env bash\n")
            subprocess.run(["bash", "-n"], input=text, text=True, check=True)
        config = json.loads(zf.read(gradescope.CONFIG))
        course = {n[len("course/"):]: zf.read(n) for n in infos if n.startswith("course/")}
        setup = zf.read("setup.sh").decode()
        requirements = zf.read(gradescope.REQUIREMENTS).decode()
    # the package at the commit built: the working tree's own bytes, and what grading reads beside them
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    assert config["commit"] == head and config["timeout"] == 120 and config["visibility"] == "visible"
    assert config["confine"] == "require"                   # the default: nothing graded without a sandbox
    for rel, data in course.items():
        if rel != "pyproject.toml" and not rel.startswith(f"{GRADING_SOURCE}/"):       # those two are made
            assert (ROOT / rel).read_bytes() == data, rel
    need = {"pyproject.toml", "course.yaml", "autograde/gradescope.py", "autograde/grade.py", "autograde/checks.py",
            "autograde/probe.py", "autograde/nbgrader_config.py", "autograde/lms_export.py", "autograde/class_report.py",
            "pusht/__init__.py", "pusht/grading.py", "pusht/grader/zygote.py", "pusht/grader/probes.py",
            "pusht/nb/times.json"}
    need |= {f"{GRADING_SOURCE}/{n}" for n in NOTEBOOKS}
    assert need <= set(course), need - set(course)
    assert set(course) >= {f"autograde/{p.name}" for p in (ROOT / "autograde").glob("*.py")} - \
        {"autograde/manual_grade.py", "autograde/dask_preload.py"}
    assert set(course) >= {p.relative_to(ROOT).as_posix() for p in (ROOT / "pusht").rglob("*.py")}
    assert set(course) >= {p.relative_to(ROOT).as_posix() for p in (ROOT / "pusht" / "nb" / "text").glob("*.md")}
    # only what grading needs: no solutions, no test classes, no site builder, no tests, no mark scheme
    unneeded = ("solutions/", "autograde/classes/", "chapter_site/", "tests/", "scripts/", "notebooks/", "text/",
                "benchmarks/", "README.md", "docs/", "requirements.txt", "autograde/mark_scheme.yaml",
                "autograde/manual_grade.py", "autograde/dask_preload.py")
    assert not [n for n in infos if n.startswith(unneeded) or n.startswith(tuple(f"course/{u}" for u in unneeded))]
    assert not [n for n in course if "__pycache__" in n or n.endswith((".pyc", ".db")) or n.startswith("autograde/source/")]
    assert 'packages = ["pusht", "pusht.grader", "pusht.nb", "autograde", "autograde.lms"]' in course["pyproject.toml"].decode()
    # torch's CPU build at requirements.txt's pin, the rest of what grading needs with requirements.txt's pins
    assert "--index-url https://download.pytorch.org/whl/cpu \"torch==2.13.0\"" in setup
    assert "torch==2.13.0" in (ROOT / "requirements.txt").read_text()
    pins = dict(line.split("==") for line in requirements.splitlines() if line and not line.startswith("#"))
    assert set(pins) == set(gradescope.GRADING_PACKAGES) and pins["nbgrader"] == "0.9.6" and pins["nh3"] == "0.3.8"
    assert "apt-get install" in setup and "bubblewrap" in setup and "pip install -q --no-deps -e \"$COURSE\"" in setup
    assert setup.rstrip().endswith('-m autograde.gradescope check --config "$SRC/gradescope.json"')


def test_the_bundle_holds_no_solution_and_every_hidden_test(bundle, tmp_path):
    """The bundle's notebooks are the instructor's with every solution taken out: no line of a solution
    region, no one-sentence answer, no output; the hidden tests, which the gradebook must hold, all kept,
    and blanked from whatever the bundle's grader writes."""
    solution, hidden = _solution_and_hidden_lines()
    assert len(solution) > 30 and len(hidden) >= 5, (len(solution), len(hidden))
    with zipfile.ZipFile(bundle) as zf:
        notebooks = {n: zf.read(n).decode() for n in zf.namelist() if n.startswith(f"course/{GRADING_SOURCE}/")}
        everything = b"\n".join(zf.read(n) for n in zf.namelist() if not n.startswith("course/pusht/"))
    assert sorted(n.rsplit("/", 1)[1] for n in notebooks) == NOTEBOOKS
    cells = [c for text in notebooks.values() for c in nbformat.reads(text, as_version=4).cells]
    text = "\n".join(c.source for c in cells)
    assert not [line for line in solution if line in text]
    # nor anywhere else in the zip (but the students' package, which holds its own implementation of
    # every exercise: that is how the chapter runs, and it is public)
    assert not [line for line in solution if line.encode() in everything]
    assert all(line in text for line in hidden)
    assert not [c for c in cells if c.cell_type == "code" and (c.outputs or c.execution_count)]
    sentences = [c for c in cells if c.cell_type == "markdown" and c.metadata.get("nbgrader", {}).get("solution")]
    assert sentences and all(c.source == "" for c in sentences)
    for name, text in notebooks.items():
        (tmp_path / name.rsplit("/", 1)[1]).write_text(text)
    assert set(hidden) <= set(gradescope.secret_lines(tmp_path))


def test_the_bundles_pyproject_installs_what_it_carries(bundle, tmp_path):
    with zipfile.ZipFile(bundle) as zf:
        zf.extractall(tmp_path, [n for n in zf.namelist() if n.startswith("course/")])
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(tmp_path / "wheel"), str(tmp_path / "course")], capture_output=True, text=True)
    assert built.returncode == 0, built.stdout[-2000:] + built.stderr[-2000:]
    wheel, = (tmp_path / "wheel").glob("*.whl")
    with zipfile.ZipFile(wheel) as zf:
        tops = {n.split("/")[0] for n in zf.namelist() if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"pusht", "autograde"}


def test_the_bundles_notebooks_strip_only_solutions():
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "language": "python", "display_name": "Python 3"}
    nb.cells = [
        nbformat.v4.new_code_cell("def f(x):\n    ### BEGIN SOLUTION\n    return x + 1\n    ### END SOLUTION\n",
                                  metadata={"nbgrader": {"solution": True, "grade": False, "grade_id": "f",
                                                         "locked": False, "schema_version": 3}}),
        nbformat.v4.new_markdown_cell("The model forgets.", metadata={"nbgrader": {
            "solution": True, "grade": True, "grade_id": "s", "points": 1, "locked": False, "schema_version": 3}}),
        nbformat.v4.new_code_cell("assert f(1) == 2\n### BEGIN HIDDEN TESTS\nassert f(2) == 3\n### END HIDDEN TESTS",
                                  metadata={"nbgrader": {"solution": False, "grade": True, "grade_id": "t",
                                                         "points": 2, "locked": True, "schema_version": 3}}),
        nbformat.v4.new_code_cell("print(f(1))", execution_count=3,
                                  outputs=[nbformat.v4.new_output("stream", text="2\n")]),
    ]
    out = nbformat.reads(gradescope.grading_source(nbformat.writes(nb)), as_version=4)
    assert out.cells[0].source == "def f(x):\n    ### BEGIN SOLUTION\n    ### END SOLUTION\n"
    assert out.cells[1].source == ""
    assert out.cells[2].source == nb.cells[2].source and out.cells[3].source == "print(f(1))"
    assert out.cells[3].outputs == [] and out.cells[3].execution_count is None
    assert [c.id for c in out.cells] == [c.id for c in nb.cells] and out.cells[2].metadata == nb.cells[2].metadata
    unended = nbformat.v4.new_code_cell("### BEGIN SOLUTION\nx = 1")
    with pytest.raises(ValueError, match="without its end"):
        gradescope.grading_source(nbformat.writes(nbformat.v4.new_notebook(cells=[unended])))


def test_a_bundle_whose_notebooks_nbgrader_reads_differently_is_not_built():
    """``same_assignment`` (each build runs it): a grading source that loses a hidden test, or keeps a
    solution line outside its region, is refused."""
    solutions = sorted((ROOT / "solutions").glob("*.ipynb"))
    source = {p.name: gradescope.grading_source(p.read_text()) for p in solutions}
    gradescope.same_assignment(solutions, source)
    nb = nbformat.reads(source["02_reward.ipynb"], as_version=4)
    cell = next(c for c in nb.cells if "BEGIN HIDDEN TESTS" in c.source)
    cell.source = cell.source.replace("grading.submit", "grading.submitted")
    with pytest.raises(ValueError, match="gradebook 02_reward"):
        gradescope.same_assignment(solutions, {**source, "02_reward.ipynb": nbformat.writes(nb)})


def test_the_same_tree_builds_the_same_zip(bundle, tmp_path):
    again = tmp_path / "again.zip"
    gradescope.build(again)
    assert again.read_bytes() == bundle.read_bytes()


def test_make_gradescope_builds_the_bundle():
    dry = subprocess.run(["make", "-n", "gradescope", "OUT=x.zip"], cwd=ROOT, capture_output=True, text=True)
    assert dry.returncode == 0, dry.stderr
    assert '-m autograde.gradescope build "x.zip" --confine "require"' in dry.stdout
    dry = subprocess.run(["make", "-n", "gradescope", "CONFINE=allow"], cwd=ROOT, capture_output=True, text=True)
    assert '-m autograde.gradescope build "runs/gradescope/autograder.zip" --confine "allow"' in dry.stdout


def test_an_unconfined_bundle_is_built_only_when_asked_and_says_so(tmp_path, capsys):
    assert gradescope.main(["build", str(tmp_path / "allow.zip"), "--confine", "allow"]) == 0
    err = capsys.readouterr().err
    assert "WARNING: this bundle grades UNCONFINED" in err and "--confine require" in err
    with zipfile.ZipFile(tmp_path / "allow.zip") as zf:
        assert json.loads(zf.read(gradescope.CONFIG))["confine"] == "allow"
    with pytest.raises(SystemExit):
        gradescope.main(["build", str(tmp_path / "auto.zip"), "--confine", "auto"])


# --- an emulated /autograder -----------------------------------------------------------------------
class Container:
    """/autograder as Gradescope lays it out once setup.sh has run (see the module's docstring)."""

    def __init__(self, root: Path, bundle: Path):
        self.root = root
        root.mkdir()
        os.chmod(root, 0o755)
        with zipfile.ZipFile(bundle) as zf:
            zf.extractall(root / "source")
        for script in ("setup.sh", "run_autograder"):
            os.chmod(root / "source" / script, 0o755)
        shutil.copy(root / "source" / "run_autograder", root / "run_autograder")
        venv = root / "source" / "course" / ".venv"
        # the venv's real folder: where .venv is a symbolic link (a git worktree sharing one venv), copying
        # the link would make the clone the real venv, and the lines below would rewrite its install
        made = subprocess.run(["cp", "-al", os.path.realpath(sys.prefix), str(venv)], capture_output=True, text=True)
        if made.returncode:
            pytest.skip(f"the venv cannot be cloned with hard links here: {made.stderr.strip()}")
        site = next(venv.glob("lib/python3*/site-packages"))
        assert not venv.is_symlink() and venv.resolve() != Path(sys.prefix).resolve()
        for p in site.iterdir():          # the working tree's install of this package out, the bundle's in
            if p.name.startswith("__editable__") and "pusht_dreamer" in p.name or p.name in ("pusht", "autograde"):
                shutil.rmtree(p) if p.is_dir() else p.unlink()
        (site / "pusht-course.pth").write_text(str(root / "source" / "course") + "\n")
        course = root / "source" / "course"           # as setup.sh: bytecode before any kernel reads it
        subprocess.run([str(venv / "bin" / "python"), "-m", "compileall", "-q", str(course / "pusht"),
                        str(course / "autograde")], check=True)

    def grade(self, files: dict) -> tuple[dict, str, float]:
        """Submit ``files`` ({path in the submission: bytes}); (results.json, stdout, seconds)."""
        for sub in ("submission", "results"):
            shutil.rmtree(self.root / sub, ignore_errors=True)
            (self.root / sub).mkdir()
        for rel, data in files.items():
            (self.root / "submission" / rel).parent.mkdir(parents=True, exist_ok=True)
            (self.root / "submission" / rel).write_bytes(data)
        env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON"))}
        t = time.perf_counter()
        proc = subprocess.run([str(self.root / "run_autograder")], cwd="/", capture_output=True, text=True,
                              env={**env, gradescope.ROOT_ENV: str(self.root)}, timeout=900)
        seconds = time.perf_counter() - t
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        return json.loads((self.root / "results" / "results.json").read_text()), proc.stdout, seconds


@pytest.fixture(scope="module")
def container(bundle, tmp_path_factory):
    c = Container(tmp_path_factory.mktemp("gradescope") / "autograder", bundle)
    yield c
    subprocess.run(["rm", "-rf", str(c.root / "source" / "course" / ".venv")])      # 55,000 links: rm is quicker


@pytest.fixture(scope="module")
def full_marks(container, executed_solutions):
    """The instructor's solutions, executed in smoke mode (the conftest's session fixture), handed in."""
    out = container.grade({n: (executed_solutions / n).read_bytes() for n in NOTEBOOKS})
    print(f"full-marks hand-in graded in {out[2]:.0f} s")
    return out


@pytest.fixture(scope="module")
def release_hand_in(container):
    """The student release handed in unchanged (every exercise raises NotImplementedError), under the
    names learners' downloads get, without 05 and 06, with a link and a file that is no notebook."""
    nb = lambda n: (ROOT / "notebooks" / n).read_bytes()     # noqa: E731
    files = {"Copy of 02_reward.ipynb": nb("02_reward.ipynb"),
             "notebooks/s042_03_imagination_actor.ipynb": nb("03_imagination_actor.ipynb"),
             "04_imagination_gap (1).ipynb": nb("04_imagination_gap.ipynb"),
             "01_world_model.ipynb": nb("01_world_model.ipynb"), "notes.txt": b"my notes"}
    out = container.grade(files)
    print(f"release hand-in graded in {out[2]:.0f} s")
    return out


def _check_schema(results):
    import jsonschema

    jsonschema.validate(results, SCHEMA)
    assert results["score"] == sum(t["score"] for t in results["tests"])
    assert all(0 <= t["score"] <= t["max_score"] for t in results["tests"])
    assert results["stdout_visibility"] == "hidden" and results["output_format"] == "text"


def _cells():
    return [(c["notebook"][:-len(".ipynb")], c["grade_id"], c["points"]) for c in gradescope.graded_cells()]


def test_the_instructors_solutions_score_full_marks(full_marks, container):
    results, stdout, _ = full_marks
    _check_schema(results)
    assert results["score"] == AUTOMATIC, results["output"]
    tests = results["tests"]
    assert [t["name"].split(" ")[0] + " " + t["name"].split(" ")[1] for t in tests] == \
        [f"{nb}: {g}" for nb, g, _ in _cells()]                  # one per graded cell, in notebook order
    for t, (_, g, points) in zip(tests, _cells()):
        if g.endswith("_sentence"):          # graded by hand on Gradescope: a 0-point note
            assert (t["score"], t["max_score"]) == (0, 0) and "by hand" in t["output"]
            assert t["visibility"] == "visible"
        else:
            assert t["score"] == t["max_score"] == points, t
            assert t["visibility"] == "visible"
            assert ("checks passed" if g.endswith("_tests") else ": in order") in t["output"], t
    if sandbox.available()[0]:
        assert "confinement: bubblewrap sandboxes" in stdout
    assert "/source/course/autograde" in stdout        # the bundle's copy graded, not the working tree's
    assert f"the assignment from {container.root}/source/course/{GRADING_SOURCE}" in stdout      # no solutions/


def test_the_unchanged_release_scores_zero_on_every_automatic_test(release_hand_in):
    results, stdout, _ = release_hand_in
    _check_schema(results)
    assert results["score"] == 0
    by_cell = {t["name"].split(" ")[1]: t for t in results["tests"]}
    for g in ("reward_impl_tests", "lambda_return_impl_tests", "losses_impl_tests", "dream_impl_tests"):
        assert by_cell[g]["max_score"] > 0 and "first failure" in by_cell[g]["output"]
        assert "NotImplementedError" in by_cell[g]["output"]
    assert "no prediction receipt" in by_cell["ex1_order"]["output"]
    for g in ("ex2_order", "ex3_order", "block_disagreement_impl_tests",      # 05-07 were not handed in
              "ex4_order", "cem_update_impl_tests"):
        assert by_cell[g]["score"] == 0 and "not in this submission" in by_cell[g]["output"]
    assert "Notebooks graded: 01_world_model.ipynb, 02_reward.ipynb, 03_imagination_actor.ipynb, " \
           "04_imagination_gap.ipynb." in results["output"]
    assert "notes.txt" in results["output"]


def _secret_lines() -> list[str]:
    """Every line of a hidden-test or solution region of the instructor's notebooks, and every line
    of a solution cell without regions (the one-sentence answers), that the student release does
    not show; the mark scheme's sentences. Found here from the notebooks, not by the module."""
    release = "\n".join(c.source for n in NOTEBOOKS for c in nbformat.read(ROOT / "notebooks" / n, as_version=4).cells)
    lines = []
    for n in NOTEBOOKS:
        for cell in nbformat.read(ROOT / "solutions" / n, as_version=4).cells:
            src = cell.source.splitlines()
            marks = [i for i, line in enumerate(src) if line.strip().startswith(("### BEGIN", "### END"))]
            if cell.metadata.get("nbgrader", {}).get("solution") and not marks:
                lines += src
            for a, b in zip(marks[::2], marks[1::2]):
                lines += src[a + 1:b]
    lines = [line.strip() for line in lines if len(line.strip()) >= gradescope.MIN_SECRET_CHARS and line.strip() not in release]
    scheme = yaml.safe_load((ROOT / "autograde" / "mark_scheme.yaml").read_text())
    lines += [s.strip() for text in scheme.values() for s in text.split(". ") if len(s.strip()) >= 20]
    return lines


def _solution_and_hidden_lines() -> tuple[list[str], list[str]]:
    """(the lines of the instructor's solutions the release does not show anywhere: solution regions and
    solution cells without regions; the lines of the hidden-test regions), stripped, 8 characters or longer."""
    release = "\n".join(c.source for n in NOTEBOOKS for c in nbformat.read(ROOT / "notebooks" / n, as_version=4).cells)
    solution, hidden = [], []
    for n in NOTEBOOKS:
        for cell in nbformat.read(ROOT / "solutions" / n, as_version=4).cells:
            inside = None
            if cell.metadata.get("nbgrader", {}).get("solution") and "BEGIN SOLUTION" not in cell.source:
                solution += cell.source.splitlines()
                continue
            for line in cell.source.splitlines():
                if "BEGIN SOLUTION" in line or "BEGIN HIDDEN TESTS" in line:
                    inside = solution if "SOLUTION" in line else hidden
                elif "END SOLUTION" in line or "END HIDDEN TESTS" in line:
                    inside = None
                elif inside is not None:
                    inside.append(line)
    keep = lambda lines: sorted({line.strip() for line in lines if len(line.strip()) >= 8 and line.strip() not in release})  # noqa: E731
    return keep(solution), keep(hidden)


def test_nothing_hidden_reaches_results_or_stdout(full_marks, release_hand_in):
    secrets = _secret_lines()
    assert len(secrets) > 40, secrets          # the hidden tests, the six exercises, the sentences, the scheme
    for results, stdout, _ in (full_marks, release_hand_in):
        text = json.dumps(results, ensure_ascii=False)
        shown = json.loads(text)
        for place, where in (("results.json", "\n".join(_strings(shown))), ("stdout", stdout)):
            found = [s for s in secrets if s in where]
            assert not found, (place, found[:5])
            for marker in ("BEGIN HIDDEN TESTS", "BEGIN SOLUTION", "grading.submit", "Mark scheme"):
                assert marker not in where, (place, marker)


def _strings(obj):
    if isinstance(obj, str):
        yield obj
    elif isinstance(obj, list):
        for x in obj:
            yield from _strings(x)
    elif isinstance(obj, dict):
        for x in obj.values():
            yield from _strings(x)


# --- the pieces, without grading -------------------------------------------------------------------
def test_a_hidden_line_in_any_message_is_blanked():
    secrets = gradescope.secret_lines(ROOT / "solutions")
    hidden = '__import__("pusht.grading").grading.submit("reward_impl_tests", reward_from_obs)'
    assert hidden in secrets
    assert gradescope.redact(f"a preview of the cell: ['{hidden}']", secrets) == "a preview of the cell: ['[hidden]']"
    # the release's own lines are no secret
    release = "\n".join(c.source for c in nbformat.read(ROOT / "notebooks" / "02_reward.ipynb", as_version=4).cells)
    assert not [s for s in secrets if s in release.splitlines()]


def test_the_hand_in_is_staged_as_the_intake_names_it(tmp_path):
    sub = tmp_path / "submission"
    (sub / "deep" / "er").mkdir(parents=True)
    (sub / "Copy of 02_reward.ipynb").write_text("{}")
    (sub / "02_reward.ipynb").write_text("old")
    os.utime(sub / "02_reward.ipynb", (1, 1))
    (sub / "deep" / "er" / "ann_lee_05_horizon (2).ipynb").write_text("{}")
    (sub / "06_closing_the_gap.py").write_text("")
    (sub / "07_bonus.ipynb").write_text("{}")
    (sub / "deep" / "04 my final version.ipynb").write_bytes((ROOT / "solutions" / "04_imagination_gap.ipynb").read_bytes())
    (sub / "__MACOSX").mkdir()
    (sub / "__MACOSX" / "._02_reward.ipynb").write_text("")
    os.symlink("/etc/passwd", sub / "03_imagination_actor.ipynb")
    staged, notes = gradescope.stage(sub, tmp_path / "dest" / "student")
    assert staged == ["02_reward.ipynb", "04_imagination_gap.ipynb", "05_horizon.ipynb"]
    assert (tmp_path / "dest" / "student" / "02_reward.ipynb").read_text() == "{}"      # the newest of two
    text = " | ".join(notes)
    assert "graded Copy of 02_reward.ipynb, the newest, not 02_reward.ipynb" in text
    assert "03_imagination_actor.ipynb: a link, not a file, not graded" in text
    assert "07_bonus.ipynb: not a notebook of this assignment" in text and "by its name or by its content" in text
    assert "deep/04 my final version.ipynb: graded as 04_imagination_gap.ipynb" in text   # known by its content
    assert "06_closing_the_gap.py" in text and "._02_reward" not in text


def test_required_confinement_grades_nothing_where_no_sandbox_starts(tmp_path, monkeypatch):
    root = tmp_path / "autograder"
    (root / "source").mkdir(parents=True)
    (root / "submission").mkdir()
    (root / "source" / gradescope.CONFIG).write_text(json.dumps({"confine": "require"}))
    (root / "submission" / "02_reward.ipynb").write_bytes((ROOT / "notebooks" / "02_reward.ipynb").read_bytes())
    monkeypatch.setattr(sandbox, "available", lambda: (False, "no namespaces in this container"))
    lines = []
    results = gradescope.run(root, log=lines.append)
    assert results == json.loads((root / "results" / "results.json").read_text())
    _check_schema(results)
    assert results["score"] == 0 and not results["tests"] and "could not start its sandbox" in results["output"]
    assert any("no namespaces in this container" in line for line in lines)


def test_jobs_follow_the_environment_then_the_cpu_quota(monkeypatch):
    monkeypatch.setenv(gradescope.JOBS_ENV, "3")
    assert gradescope.jobs() == 3
    monkeypatch.delenv(gradescope.JOBS_ENV)
    assert 1 <= gradescope.jobs() <= (os.cpu_count() or 1)


def test_a_bundle_without_settings_requires_confinement(tmp_path, monkeypatch):
    root = tmp_path / "autograder"
    (root / "submission").mkdir(parents=True)
    (root / "submission" / "02_reward.ipynb").write_bytes((ROOT / "notebooks" / "02_reward.ipynb").read_bytes())
    monkeypatch.setattr(sandbox, "available", lambda: (False, "no namespaces in this container"))
    monkeypatch.setattr(grade, "grade_class", lambda *a, **k: pytest.fail("graded without a sandbox"))
    results = gradescope.run(root, log=lambda line: None)
    assert results["score"] == 0 and not results["tests"] and "could not start its sandbox" in results["output"]


def _allow_bundle(tmp_path, monkeypatch, available, notebooks=("02_reward.ipynb",)):
    """An emulated /autograder of a --confine allow bundle, grading faked (only what run adds is checked)."""
    root = tmp_path / "autograder"
    (root / "source").mkdir(parents=True)
    (root / "submission").mkdir()
    (root / "source" / gradescope.CONFIG).write_text(json.dumps({"confine": "allow"}))
    for n in notebooks:
        (root / "submission" / n).write_bytes((ROOT / "notebooks" / n).read_bytes())
    monkeypatch.setattr(sandbox, "available", lambda: available)
    graded = []

    def fake_grade_class(hand_in, course, **kwargs):
        graded.append(kwargs["confine"])
        return {gradescope.STUDENT: {"notes": [], "verdicts": {}, "completion": {}}}
    monkeypatch.setattr(grade, "grade_class", fake_grade_class)
    monkeypatch.setattr(gradescope, "_scores", lambda course: {})
    lines = []
    results = gradescope.run(root, log=lines.append)
    assert results == json.loads((root / "results" / "results.json").read_text())
    _check_schema(results)
    return results, lines, graded


def test_an_unconfined_bundle_warns_in_every_result_where_no_sandbox_starts(tmp_path, monkeypatch):
    results, lines, graded = _allow_bundle(tmp_path, monkeypatch, (False, "bwrap: Unknown option --size"))
    assert graded == [False]                               # graded, unconfined, as this bundle allows
    first = results["tests"][0]
    assert first["name"] == gradescope.SANDBOX_TEST and first["output"] == gradescope.UNCONFINED_NOTE
    assert (first["score"], first["max_score"], first["status"], first["visibility"]) == (0, 0, "failed", "visible")
    assert results["output"].startswith("WARNING: your notebooks were graded WITHOUT a sandbox")
    assert any("WARNING" in line and "allows grading without one" in line for line in lines)
    # a submission with no notebook in it is told too
    shutil.rmtree(tmp_path / "autograder")
    results, _, graded = _allow_bundle(tmp_path, monkeypatch, (False, "no bwrap"), notebooks=())
    assert not graded and results["tests"][0]["output"] == gradescope.UNCONFINED_NOTE


def test_an_unconfined_bundle_says_so_where_a_sandbox_starts_too(tmp_path, monkeypatch):
    results, _, graded = _allow_bundle(tmp_path, monkeypatch, (True, ""))
    assert graded == [True]
    first = results["tests"][0]
    assert first["name"] == gradescope.SANDBOX_TEST and first["output"] == gradescope.CONFINED_NOTE
    assert first["status"] == "passed" and not results["output"].startswith("WARNING")
    # the results.json written first, in case grading never finishes, warns as well
    unfinished = gradescope._unfinished({"confine": "allow"})
    assert unfinished["tests"][0]["output"] == gradescope.UNKNOWN_NOTE and unfinished["output"].startswith("WARNING")
    assert not gradescope._unfinished({"confine": "require"})["tests"]


@pytest.mark.parametrize("confine, version, ok", [("require", (0, 6, 1), False), ("require", None, False),
                                                  ("require", (0, 9, 0), True), ("allow", (0, 6, 1), True)])
def test_setup_fails_the_image_build_only_where_required_confinement_never_can_be(monkeypatch, confine, version, ok):
    monkeypatch.setattr(sandbox, "available", lambda: (False, "bwrap refused to start a sandbox here"))
    monkeypatch.setattr(gradescope, "bwrap_version", lambda: version)
    lines = []
    assert gradescope.check({"confine": confine}, log=lines.append) is ok
    assert ("ERROR" in lines[-1] and "Ubuntu 24.04" in lines[-1]) if not ok else "WARNING" in lines[-1]
    monkeypatch.setattr(sandbox, "available", lambda: (True, ""))
    assert gradescope.check({"confine": confine}, log=lines.append)


def test_no_output_of_grading_a_class_goes_into_the_bundle():
    """Every file a class's grading writes (students' answers, names, scores, feedback) is in the
    course folder, one folder outside every vendored path and ignored by git as a whole."""
    from autograde.course import COURSE_DIR

    assert COURSE_DIR == ROOT / "course"
    outputs = ["gradebook.db", "gradebook.template.db", "grades.csv", "report.csv", "manual_grades.csv",
               "to_grade.csv", "to_grade.unapplied-20261206-154500.csv", "graded.json", ".grading.lock",
               "canvas_import.csv", "moodle_import.csv", "lms_export_notes.txt", "class_report.html",
               "nbgrader_config.py", "feedback/canvas_1/ch3.2/02_reward.html",
               "feedback_return/canvas_feedback_upload.zip", "feedback_return/report.json",
               "shared_stages/expert.npz", "source/ch3.2/02_reward.ipynb", "release/ch3.2/02_reward.ipynb",
               "autograded/canvas_1/ch3.2/02_reward.ipynb", "submitted/s1/ch3.2/02_reward.ipynb"]
    outputs = [f"course/{p}" for p in outputs]
    assert not [p for p in outputs if p.startswith(tuple(f"{top}/" for top in gradescope.VENDORED))]
    ignored = subprocess.run(["git", "-C", str(ROOT), "check-ignore", "--no-index", *outputs], capture_output=True,
                             text=True).stdout.split()
    assert sorted(ignored) == sorted(outputs)
    assert (ROOT / ".gitignore").read_text().splitlines().count("/course/") == 1


def test_the_bundle_vendors_no_untracked_data_nor_the_course_folder(tmp_path):
    """An untracked file under a vendored path goes into the bundle only if it is Python source:
    not an output left in autograde/ by a grading run from before the course folder moved (no
    longer ignored there), nor anything of a course folder given inside the package."""
    def git(*a):
        return subprocess.run(["git", "-C", str(tmp_path), *a], check=True, capture_output=True)

    git("init", "-q")
    for rel in ("course.yaml", "autograde/grade.py", "autograde/old/grades.csv", "autograde/grades.csv",
                "autograde/new_step.py", "autograde/feedback/s1/ch3.2/02_reward.html", "pusht/nb/times.json",
                "autograde/mine/nbgrader_config.py", "autograde/mine/gradebook.db"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("x")
    git("add", "course.yaml", "autograde/grade.py", "pusht/nb/times.json")
    files = gradescope._vendored_files(tmp_path, course=tmp_path / "autograde" / "mine")
    assert files == ["autograde/grade.py", "autograde/new_step.py", "course.yaml", "pusht/nb/times.json"]
