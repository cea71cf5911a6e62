"""The Colab lane (`make colab-check`, scripts/colab_check.py).

The lane itself is slow (it makes .venv-colab the first time, then runs every notebook on
Colab's stack): ``test_colab_lane`` is marked ``lane``. The rest are fast checks of its parts: the
stack file, the version comparison, finding Python 3.13, the google.colab stand-in and its start-up
import, the local stand-in for GitHub, and the kernelspec that sends papermill to .venv-colab.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from scripts import colab_check as cc

ROOT = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------------- the stack file ----

def test_the_stack_file_pins_colabs_runtime_and_names_its_source():
    text = cc.STACK_FILE.read_text()
    stack = cc.parse_stack(text)
    assert stack.python == "3.13"
    assert {"torch", "numpy", "matplotlib", "ipython", "ipykernel", "tqdm", "pyyaml", "pip"} <= set(stack.pins)
    assert stack.pins["torch"].startswith("2.11") and stack.pins["ipython"] == "7.34.0"
    assert "github.com/googlecolab/backend-info" in text and "2026-08" in text


def test_parse_stack_reads_pins_comments_and_the_python_line():
    stack = cc.parse_stack("# source: somewhere\n# python: 3.13\n\ntorch==2.11.0\nnumpy==2.1.3  # Colab's\n"
                           "PyYAML==6.0.3\npython-dateutil==2.9.0.post0\n")
    assert stack.python == "3.13"
    assert stack.pins == {"torch": "2.11.0", "numpy": "2.1.3", "pyyaml": "6.0.3", "python-dateutil": "2.9.0.post0"}
    assert stack.digest != cc.parse_stack("# python: 3.13\ntorch==2.11.0\nnumpy==2.1.4\n").digest


@pytest.mark.parametrize("text, error", [
    ("torch==2.11.0\nnumpy==2.1.3\n", "no `# python: 3.NN` line"),
    ("# python: 3\ntorch==2.11.0\nnumpy==2.1.3\n", "minor version like 3.13"),
    ("# python: 3.13\n# python: 3.12\ntorch==2.11.0\nnumpy==2.1.3\n", "second `# python:`"),
    ("# python: 3.13\ntorch>=2.1\nnumpy==2.1.3\n", "line 2: 'torch>=2.1' is not an exact pin"),
    ("# python: 3.13\ntorch==2.11.0\nnumpy==2.1.3\nNumPy==2.1.3\n", "numpy is pinned twice"),
    ("# python: 3.13\ntorch==2.11.0\n", "must pin numpy"),
])
def test_parse_stack_refuses_what_would_loosen_the_stack(text, error):
    with pytest.raises(ValueError) as e:
        cc.parse_stack(text)
    assert error.lower() in str(e.value).lower()


def test_version_changes():
    before = {"torch": "2.11.0", "numpy": "2.1.3", "tqdm": "4.67.3"}
    assert cc.version_changes(before, {**before, "pymunk": "7.3.1"}) == []
    assert cc.version_changes(before, {"torch": "2.11.0", "numpy": "2.3.5"}) == [
        "numpy 2.1.3 -> 2.3.5", "tqdm 4.67.3 -> removed"]
    assert cc.version_changes({"numpy": "2.1"}, {"numpy": "2.1.0"}) == []          # PEP 440: the same
    assert cc.version_changes({"torch": "2.11.0"}, {"torch": "2.11.0+cpu"}) == ["torch 2.11.0 -> 2.11.0+cpu"]
    assert cc.canonical("PyYAML") == cc.canonical("pyyaml") and cc.canonical("jupyter_client") == "jupyter-client"


# ------------------------------------------------------------------------ finding Python ----

def _fake_python(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("#!/bin/sh\n")
    path.chmod(0o755)
    return path


def test_find_python_takes_the_newest_pyenv_patch_release(tmp_path):
    root = tmp_path / "pyenv"
    for name in ("3.13.0", "3.13.5", "3.12.9"):
        _fake_python(root / "versions" / name / "bin" / f"python{name[:4]}")
    _fake_python(root / "versions" / "3.13t" / "bin" / "python3.13")        # free-threaded: not Colab's
    _fake_python(root / "versions" / "3.13.9t" / "bin" / "python3.13")
    assert cc.find_python("3.13", roots=[root], path="") == root / "versions" / "3.13.5" / "bin" / "python3.13"


def test_find_python_falls_back_to_path_and_names_what_is_missing(tmp_path):
    bindir = tmp_path / "bin"
    exe = _fake_python(bindir / "python3.13")
    assert cc.find_python("3.13", roots=[tmp_path / "nopyenv"], path=str(bindir)) == exe
    with pytest.raises(FileNotFoundError) as e:
        cc.find_python("3.13", roots=[tmp_path / "nopyenv"], path=str(tmp_path / "empty"))
    message = str(e.value)
    assert "Python 3.13" in message and "nopyenv/versions/3.13.*" in message
    assert "python3.13 on PATH" in message and "pyenv install 3.13" in message


# ------------------------------------------------- the stand-in and its start-up import ----

def test_google_colab_is_imported_at_kernel_start(tmp_path):
    """IPython (what the kernel runs) executes the startup file before any cell, so a notebook's
    first cell already sees google.colab in sys.modules, as in Colab."""
    ipython_dir = cc.ipython_dir(tmp_path / "ipython")
    env = {**os.environ, "IPYTHONDIR": str(ipython_dir), "PYTHONPATH": str(cc.STANDIN)}
    code = "import sys; print('colab' if 'google.colab' in sys.modules else 'not colab', sys.modules['google.colab'].STANDIN)"
    proc = subprocess.run([sys.executable, "-m", "IPython", "--no-banner", "--colors=NoColor", "-c", code],
                          env=env, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "colab True"
    # without the startup file nothing imports it: the notebooks' install branch would not run
    plain = subprocess.run([sys.executable, "-c", "import sys; print('google.colab' in sys.modules)"],
                           env=env, capture_output=True, text=True, timeout=60)
    assert plain.stdout.strip() == "False"


def test_the_stand_in_is_a_namespace_package_beside_other_google_packages():
    assert not (cc.STANDIN / "google" / "__init__.py").exists()
    assert (cc.STANDIN / "google" / "colab" / "__init__.py").exists()


# ------------------------------------------------------------ the local stand-in for GitHub ----

def test_the_install_address_is_served_from_a_snapshot_of_the_working_tree(tmp_path):
    course = yaml.safe_load((ROOT / "course.yaml").read_text())
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    bare, commit, count = cc.snapshot_repo(ROOT, tmp_path, course["ref"])
    assert count > 50 and not (tmp_path / "work").exists()
    config = cc.github_redirect(tmp_path / "gitconfig", course["repository"], bare)
    env = {**os.environ, "GIT_CONFIG_GLOBAL": str(config), "GIT_TERMINAL_PROMPT": "0"}
    url = f"https://github.com/{course['repository']}"
    remote = subprocess.run(["git", "ls-remote", url, course["ref"]], env=env, capture_output=True, text=True,
                            timeout=60)
    assert remote.returncode == 0, remote.stderr
    assert remote.stdout.split() == [commit, f"refs/heads/{course['ref']}"]
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "--quiet", url, str(clone)], env=env, check=True, timeout=60)
    assert (clone / "pyproject.toml").read_bytes() == (ROOT / "pyproject.toml").read_bytes()
    assert (clone / "scripts" / "colab_check.py").exists()            # untracked files travel too
    assert not (clone / ".venv").exists() and not (clone / ".venv-colab").exists()
    # the checkout's own git state is untouched
    assert subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout == head


# --------------------------------------------------------------- the kernel papermill starts ----

def test_the_kernelspec_wins_over_the_main_venvs_python3(tmp_path, monkeypatch):
    from jupyter_client.kernelspec import KernelSpecManager

    python = _fake_python(tmp_path / "venv" / "bin" / "python")
    jupyter = cc.write_kernelspec(tmp_path / "jupyter", python, {"IPYTHONDIR": "/x"})
    monkeypatch.setenv("JUPYTER_PATH", str(jupyter))
    spec = KernelSpecManager().get_kernel_spec("python3")            # the name chapter.execute() asks for
    assert spec.argv[:3] == [str(python), "-m", "ipykernel_launcher"] and spec.env == {"IPYTHONDIR": "/x"}


def test_the_kernel_environment_drops_the_main_venv(monkeypatch, tmp_path):
    main_bin = str(Path(sys.prefix) / "bin")
    monkeypatch.setenv("PATH", os.pathsep.join([main_bin, "/usr/bin"]))
    monkeypatch.setenv("VIRTUAL_ENV", sys.prefix)
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    env = cc.kernel_environ(tmp_path / "v" / "bin" / "python")
    assert env["PATH"].split(os.pathsep) == [str(tmp_path / "v" / "bin"), "/usr/bin"]
    assert "VIRTUAL_ENV" not in env and "PYTHONPATH" not in env


# ------------------------------------------------------------------------------ the lane ----

@pytest.mark.lane
def test_colab_lane():
    """make colab-check: every notebook runs top to bottom on Colab's stack through its own install
    cell, and the install leaves torch and numpy (every pinned package) as Colab has them."""
    proc = subprocess.run([sys.executable, "-m", "scripts.colab_check"], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600)
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    for nb in sorted((ROOT / "solutions").glob("*.ipynb")):
        row = next((ln for ln in lines if ln.strip().startswith(nb.stem + " ")), "")
        assert " ok " in row and "Installed: pusht-dreamer" in row, row or f"no line for {nb.stem}"
    n = len(list((ROOT / "solutions").glob("*.ipynb")))
    assert any(ln.startswith(f"colab-check: all {n} notebooks ran top to bottom") for ln in lines), proc.stdout[-3000:]
