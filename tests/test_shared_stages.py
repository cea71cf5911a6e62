"""Stages shared by a grading batch: read from the shared folder when they are the same stage,
never when a learner's own code went into them.

When a class is graded, the instructor's solutions are graded first and the stage files their
kernels wrote are given, read-only, to every student's kernel (``autograde.grade``,
``shared_stages``). These tests pin the package's side of that contract.
"""

import shutil
from pathlib import Path

import torch

from pusht import stage_cache
from pusht.config import make_config
from pusht.dreamer import agent_stage, world_model_stage
from pusht.imagination import lambda_return

ROOT = Path(__file__).resolve().parents[1]


def smoke():
    return make_config(smoke=True, seed=0, wm_epochs=2, imag_iters=4)


def files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def test_a_stage_in_the_shared_folder_is_read_not_computed_again(tmp_path, monkeypatch):
    cfg = smoke()
    first = world_model_stage(cfg, cache_dir=tmp_path / "instructor", model_cache=tmp_path / "instructor", log=None)
    shared = tmp_path / "shared"
    shutil.copytree(tmp_path / "instructor", shared)
    assert any(n.startswith("wm_") for n in files(shared)) and any(n.startswith("expert_") for n in files(shared))
    monkeypatch.setenv(stage_cache.SHARED_CACHE_ENV, str(shared))
    mine = tmp_path / "student"
    second = world_model_stage(cfg, cache_dir=mine, model_cache=mine, log=None)
    assert files(mine) == []                   # nothing computed, so nothing written
    for p, q in zip(first.wm.parameters(), second.wm.parameters(), strict=True):
        assert torch.equal(p, q)


def test_a_different_config_is_not_taken_from_the_shared_folder(tmp_path, monkeypatch):
    cfg = smoke()
    world_model_stage(cfg, cache_dir=tmp_path / "shared", model_cache=tmp_path / "shared", log=None)
    monkeypatch.setenv(stage_cache.SHARED_CACHE_ENV, str(tmp_path / "shared"))
    mine = tmp_path / "student"
    world_model_stage(cfg.replace(wm_epochs=3), cache_dir=mine, model_cache=mine, log=None)
    assert any(n.startswith("wm_") for n in files(mine))      # computed here: another stage


def test_a_stage_trained_with_the_learners_function_is_never_cached_so_never_shared(tmp_path):
    cfg = smoke()
    stage = world_model_stage(cfg, cache_dir=tmp_path, model_cache=tmp_path, log=None)

    def my_return(*args, **kwargs):            # a learner's lambda-return (here the same numbers)
        return lambda_return(*args, **kwargs)

    agent_stage(cfg, stage, model_cache=tmp_path, log=None, return_fn=my_return)
    assert not any(n.startswith("agent_") for n in files(tmp_path))
    agent_stage(cfg, stage, model_cache=tmp_path, log=None)
    assert any(n.startswith("agent_") for n in files(tmp_path))
