"""The optional Rerun recording (`--rerun`): what it holds, and what happens without rerun-sdk."""

import sys

import numpy as np
import pytest

from pusht.config import make_config
from pusht.dreamer import main, run
from pusht.env import obs_to_pose


def _columns(path):
    """{entity path: record batch} of a .rrd file, read back with rerun's own reader."""
    import rerun.chunk as ch

    batches = {}
    for chunk in ch.RrdReader(str(path)).store().stream().to_chunks():
        batches.setdefault(str(chunk.entity_path), []).append(chunk.to_record_batch())
    return batches


def test_recording_holds_both_worlds_and_the_curves(tmp_path):
    pytest.importorskip("rerun", reason="rerun-sdk is an optional extra (requirements.txt installs it)")
    from pusht.record import record_rerun

    cfg = make_config(smoke=True, seed=0, out=tmp_path)
    result = run(cfg, log=None)
    path = record_rerun(result, tmp_path / "run.rrd", episodes=2)
    cols = _columns(path)

    steps = cfg.eval_horizon + 1
    for ep in range(2):
        for world in ("dream", "real"):
            for part in ("tee", "pusher"):
                rows = sum(b.num_rows for b in cols[f"/episode_{ep:02d}/{world}/{part}"])
                assert rows == steps, (ep, world, part)
            # the distance curve is the rollout's own block-to-target distance, step by step
            (batch,) = cols[f"/tee_distance_m/episode_{ep:02d}/{world}"]
            logged = np.array([v[0] for v in batch.column("Scalars:scalars").to_pylist()])
            tee = obs_to_pose(result.rollouts[world].obs[:, ep])[1]
            np.testing.assert_allclose(logged, np.linalg.norm(tee[:, :2], axis=-1))
    assert "/episode_02/real/tee" not in cols                       # only the episodes asked for

    # positions are drawn y-up: logged y is the world's y negated
    (batch,) = cols["/episode_00/real/pusher"][:1]
    first = np.array(batch.column("Points2D:positions").to_pylist()[0][0])
    np.testing.assert_allclose(first, result.rollouts["real"].obs[0, 0, :2] * (1, -1), rtol=1e-6)

    (batch,) = cols["/training/imagined_reward_per_step"]
    assert batch.num_rows == cfg.imag_iters
    assert "/report" in cols and "/world_model/recon_loss" in cols


def test_cli_without_rerun_says_how_to_install_before_running(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "rerun", None)                 # as if rerun-sdk were missing
    out = tmp_path / "never"
    with pytest.raises(SystemExit) as exit_:
        main(["--smoke", "--out", str(out), "--rerun"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "pip install rerun-sdk" in err and "usage:" in err
    assert not out.exists()                                          # nothing ran, nothing written
