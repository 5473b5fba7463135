"""run_method(light=True): per-frame results kept in arrays read back as FrameResults."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.methods import FrameResult, get_method, run_method
from engine.methods.records import ResultArrays
from engine.tracking import simulate


def test_light_run_gives_the_same_motion_and_figures(synthetic_motion):
    clip = synthetic_motion.slice(0, 30)
    tracking = simulate(clip, "6")
    full_rec, full = run_method(get_method("ik"), tracking, clip.skeleton, progress=False)
    light_rec, light = run_method(get_method("ik"), tracking, clip.skeleton, progress=False, light=True)
    assert isinstance(light, ResultArrays) and len(light) == len(full) == 30
    np.testing.assert_allclose(light_rec.local_rot, full_rec.local_rot, atol=1e-12)
    np.testing.assert_allclose(light_rec.root_pos, full_rec.root_pos, atol=1e-12)
    for a, b in zip(light, full):
        np.testing.assert_allclose(a.positions, b.positions, atol=1e-12)
        assert a.iterations == b.iterations and a.warnings == b.warnings
    assert light[-1].ms == light.ms[29] > 0


def test_records_keep_latent_final_loss_timings_and_warnings():
    rec = ResultArrays(3)
    pose = dict(
        local_rot=np.tile([1.0, 0, 0, 0], (sk.NUM_JOINTS, 1)),
        root_pos=np.ones(3),
        positions=np.zeros((sk.NUM_JOINTS, 3)),
    )
    rec.store(
        0,
        FrameResult(
            **pose,
            iterations=10,
            losses=[{"a": 2.0, "total": 2.0}, {"a": 1.0, "total": 1.0}],
            latent=np.arange(24.0),
            ms=3.0,
            warnings=["lost lwrist"],
            timings={"ms_per_iteration": 0.4, "decoder": 0.1, "fk_losses": 0.1, "backward": 0.15, "step": 0.05},
        ),
    )
    rec.store(1, FrameResult(**pose, ms=1.0))
    assert len(rec) == 2  # frame 2 not stored yet
    first, second = rec
    assert first.losses == [{"total": 1.0}] and first.warnings == ["lost lwrist"] and first.iterations == 10
    np.testing.assert_array_equal(first.latent, np.arange(24.0))
    assert first.timings["backward"] == 0.15 and second.timings == {} and second.losses == []
    assert second.warnings == [] and rec[-1].ms == 1.0
