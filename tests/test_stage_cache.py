"""The stage cache's key is derived from the code: a change to any module a stage can run names a
new file (the optimiser the world model trains with included), a change elsewhere does not."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from pusht import stage_cache
from pusht.agent_stage import AGENT_FIELDS
from pusht.config import make_config
from pusht.wm_stage import WM_FIELDS

PACKAGE = stage_cache.PACKAGE
STAGES = {"pusht.wm_stage": WM_FIELDS, "pusht.agent_stage": AGENT_FIELDS, "pusht.loop": AGENT_FIELDS,
          "pusht.data": ()}


def _names(module, package=PACKAGE):
    return {p.relative_to(package).as_posix() for p in stage_cache.sources(module, package)}


def test_the_world_model_stage_runs_the_optimiser_and_not_the_notebooks():
    names = _names("pusht.wm_stage")
    assert {"optim.py", "world_model.py", "data.py", "env.py", "expert.py", "config.py", "ensemble.py",
            "stage_cache.py", "wm_stage.py", "__init__.py"} <= names
    assert not names & {"dreamer.py", "agent_stage.py", "loop.py", "sweep.py"}
    assert not any(n.startswith("nb/") for n in names)
    assert "wm_stage.py" in _names("pusht.agent_stage") and "optim.py" in _names("pusht.agent_stage")


def test_the_key_changes_with_every_module_the_stage_runs_and_no_other(tmp_path):
    """Each .py file of a copy of the package is edited in turn; every stage's key changes exactly
    when the file is one the stage can run."""
    package = tmp_path / "pusht"
    shutil.copytree(PACKAGE, package, ignore=shutil.ignore_patterns("__pycache__", "*.json"))
    cfg = make_config(smoke=True)
    before = {m: stage_cache.key(cfg, f, m, package) for m, f in STAGES.items()}
    runs = {m: set(stage_cache.sources(m, package)) for m in STAGES}
    wrong = []
    for path in sorted(package.rglob("*.py")):
        text = path.read_text()
        path.write_text(text + "\n# edited\n")
        try:
            for m, f in STAGES.items():
                if (stage_cache.key(cfg, f, m, package) != before[m]) != (path in runs[m]):
                    wrong.append((m, path.relative_to(package).as_posix()))
        finally:
            path.write_text(text)
    assert wrong == []
    assert {m: stage_cache.key(cfg, f, m, package) for m, f in STAGES.items()} == before
    other = cfg.replace(seed=cfg.seed + 1)          # and with every config field it reads
    assert all(stage_cache.key(other, f, m, package) != before[m] for m, f in STAGES.items() if f)


@pytest.mark.parametrize("module", sorted(STAGES))
def test_every_module_the_stage_imports_when_it_runs_is_in_its_key(module):
    """What the static reading finds is checked against what Python really imports."""
    code = ("import json, sys, importlib; importlib.import_module(%r); "
            "print(json.dumps(sorted(m.__file__ for n, m in sys.modules.items() "
            "if n.split('.')[0] == 'pusht' and getattr(m, '__file__', None))))" % module)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=PACKAGE.parent)
    imported = {Path(f).resolve() for f in json.loads(out.stdout)}
    assert imported <= set(stage_cache.sources(module)), imported - set(stage_cache.sources(module))


def test_the_file_names_it_writes_are_the_ones_the_grader_shares(tmp_path):
    cfg = make_config(smoke=True)
    for kind, (module, fields) in {"wm": ("pusht.wm_stage", WM_FIELDS), "agent": ("pusht.agent_stage", AGENT_FIELDS),
                                   "loop": ("pusht.loop", AGENT_FIELDS)}.items():
        path = stage_cache.stage_path(tmp_path, kind, cfg, fields, module)
        assert stage_cache.FILE_PATTERN.match(path.name), path.name
    assert stage_cache.stage_path(None, "wm", cfg, WM_FIELDS, "pusht.wm_stage") is None
    with pytest.raises(ValueError, match="unknown stage kind"):
        stage_cache.stage_path(tmp_path, "actor", cfg, WM_FIELDS, "pusht.wm_stage")
    with pytest.raises(ValueError, match="not a module"):
        stage_cache.sources("pusht.no_such_module")
