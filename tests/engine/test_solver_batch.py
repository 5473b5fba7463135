"""Offline solves of many frames at once (engine/solver/batch.py, engine/methods/dragposer_batch.py):
the same frames as the frame-by-frame solve, with the decoder run on many latents per pass."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.methods import dragposer_batch as DB
from engine.methods import get_method, run_method
from engine.solver import batch as B

CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"


@pytest.fixture(scope="module")
def clip():
    from engine.motion.retarget import load_motion

    return load_motion(CLIP, max_frames=40)


def _offline(**kw):
    m = get_method("dragposer", mode="offline", **kw)
    if m.bank is None:
        pytest.skip("the shipped pose bank is not installed")
    return m


def _frame_by_frame(m, tracking, skeleton):
    m.solve_clip = lambda frames: None  # the caller then steps frame by frame
    return run_method(m, tracking, skeleton, progress=False)


@pytest.mark.parametrize("preset", ["6", "4"])
def test_one_segment_is_the_frame_by_frame_solve(clip, preset, monkeypatch):
    from engine.tracking import simulate

    tr = simulate(clip, preset)
    monkeypatch.setattr(DB, "STREAMS", 1)  # the whole clip is one segment: every frame starts from the last
    monkeypatch.setattr(DB, "SEGMENT", 1000)
    batched, res_b = run_method(_offline(), tr, clip.skeleton, progress=False)
    seq, res_s = _frame_by_frame(_offline(), tr, clip.skeleton)
    gap = np.linalg.norm(batched.positions() - seq.positions(), axis=-1)
    its_b, its_s = np.array([r.iterations for r in res_b]), np.array([r.iterations for r in res_s])
    # float32 products in another order (a matrix, not a vector) move a stopping test by an
    # iteration now and then, and the frames after it drift apart by up to a few centimetres
    assert (its_b[:8] == its_s[:8]).all() and abs(its_b.mean() - its_s.mean()) < 0.05 * its_s.mean()
    assert gap[:8].max() < 1e-4 and np.median(gap) < 1e-5 and gap.max() < 0.05


def test_segments_are_solved_side_by_side_and_stay_close_to_the_frame_by_frame_solve(clip, monkeypatch):
    from engine.tracking import simulate

    tr = simulate(clip, "6")
    monkeypatch.setattr(DB, "SEGMENT", 8)
    widths = []
    forward = B.BatchDecoder.forward
    monkeypatch.setattr(B.BatchDecoder, "forward", lambda self, z: widths.append(z.shape[1]) or forward(self, z))
    batched, res = run_method(_offline(), tr, clip.skeleton, progress=False)
    assert len(res) == len(tr) and max(widths) == 5  # 40 frames: five segments of eight
    seq, _ = _frame_by_frame(_offline(), tr, clip.skeleton)
    gap = np.linalg.norm(batched.positions() - seq.positions(), axis=-1)
    assert np.median(gap) < 0.005 and gap.max() < 0.05  # only the segments' starts differ


def test_clips_it_cannot_batch_are_solved_frame_by_frame(clip):
    from engine.constraints import PinConstraint
    from engine.tracking import simulate

    frames = [simulate(clip, "6").frame(i) for i in range(6)]
    assert _offline().solve_clip(frames) is not None
    assert get_method("dragposer", mode="realtime").solve_clip(frames) is None
    assert _offline().solve_clip([simulate(clip, "5").frame(i) for i in range(6)]) is None  # no hip tracker
    assert _offline(prior="predictor").solve_clip(frames) is None  # the predictor reads the solved history
    m = _offline()
    m.add_constraint(PinConstraint(name="pin", joint="lwrist", position=np.zeros(3)))
    assert m.solve_clip(frames) is None


def test_the_batched_gradient_is_the_derivative_of_the_batched_loss(clip):
    from engine.tracking import simulate

    m = _offline()
    tr = simulate(clip, "4")
    read = DB._read_all(m, [tr.frame(i) for i in range(5)])
    terms = DB._terms(read)
    rng = np.random.default_rng(0)
    terms.smooth_on[:] = [False, True, True, False, True]
    terms.smooth_target[:] = rng.normal(scale=0.3, size=terms.smooth_target.shape) + np.array([0, 0, 1.0])
    terms.ground_weight = 10.0
    dense = m.optimizer._fast.decoder
    dec, pose = B.BatchDecoder(dense), B.BatchPose(m.skeleton.offsets, dense)
    pose.setup(terms)
    z = terms.prior + rng.normal(scale=0.3, size=terms.prior.shape)  # float64: exact differences
    idx = np.array([0, 1, 3, 4])
    w = pose.term_weights()[idx]

    def total(zz):
        z32 = zz[idx].astype(np.float32)
        return float((w * pose.forward(z32, dec.forward(z32.T), idx)).sum())

    total(z)
    g_out, g_z = pose.backward()
    grad = dec.backward(g_out).T + g_z
    for a, f in enumerate(idx):
        for d in (0, 7, 19):
            up, down = z.copy(), z.copy()
            up[f, d] += 1e-3
            down[f, d] -= 1e-3
            assert (total(up) - total(down)) / 2e-3 == pytest.approx(grad[a, d], rel=0.02, abs=2e-3)


def test_the_overlap_is_cross_faded_from_the_previous_segment_to_the_next():
    from engine.kinematics.fk import fk
    from engine.methods.base import FrameResult

    offsets = np.tile([0.0, 0.1, 0.0], (22, 1))
    own_q = np.tile([1.0, 0.0, 0.0, 0.0], (22, 1))
    turn = np.tile([np.cos(0.4), 0.0, 0.0, -np.sin(0.4)], (22, 1))  # 0.8 rad about x
    own = [FrameResult(local_rot=own_q.copy(), root_pos=np.zeros(3), positions=np.zeros((22, 3))) for _ in range(3)]
    DB._crossfade(own, [turn] * 3, offsets)
    angle = [2 * np.arccos(np.clip(abs(r.local_rot[5, 0]), 0, 1)) for r in own]
    assert np.allclose(angle, [0.2, 0.4, 0.6])  # 1/4, 2/4, 3/4 of the way to the next segment's pose
    for r in own:
        assert np.allclose(r.positions, fk(r.local_rot, r.root_pos, offsets)[0])


def test_segment_starts_step_less_with_the_cross_fade(clip, monkeypatch):
    from engine.tracking import simulate

    tr = simulate(clip, "6")
    monkeypatch.setattr(DB, "SEGMENT", 8)
    monkeypatch.setattr(DB, "WARMUP", 6)
    steps = {}
    for fade in (False, True):
        monkeypatch.setattr(DB, "CROSSFADE", fade)
        rec, _ = run_method(_offline(), tr, clip.skeleton, progress=False)
        jump = np.linalg.norm(np.diff(rec.positions(), axis=0), axis=-1).max(1)  # per frame pair, m
        steps[fade] = jump[[7, 15, 23, 31]].mean()  # into each segment's first frame (8, 16, 24, 32)
    assert steps[True] < steps[False]


@pytest.mark.parametrize("prior_start", [False, True])
def test_later_segments_start_from_the_bank_latent_of_their_first_warm_up_frame(clip, monkeypatch, prior_start):
    from engine.tracking import simulate

    tr = simulate(clip, "6")
    monkeypatch.setattr(DB, "SEGMENT", 8)
    monkeypatch.setattr(DB, "PRIOR_START", prior_start)
    starts = []
    solve = DB.solve_streams

    def record(dec, pose, terms, z, *rest):
        starts.append(z.copy())
        return solve(dec, pose, terms, z, *rest)

    monkeypatch.setattr(DB, "solve_streams", record)
    frames = [tr.frame(i) for i in range(len(tr))]
    assert _offline().solve_clip(frames) is not None
    read = DB._read_all(_offline(), frames)
    w = min(DB.WARMUP, 8)
    z0 = starts[0]
    assert not z0[0].any()  # the clip's first frame: the mean latent, as frame by frame
    for c in range(1, 5):
        want = read[8 * c - w]["prior"] if prior_start else np.zeros_like(z0[c])
        assert np.allclose(z0[c], want, atol=1e-6)
