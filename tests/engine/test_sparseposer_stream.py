"""SparsePoser's realtime step: the streamed generator, the features, the kernel-5 fallback."""

from __future__ import annotations

import numpy as np
import torch

from engine.kinematics.features import encoder_input, pose_from_motion
from engine.methods.sparseposer import TAIL, SparsePoserMethod
from engine.models.loading import load_sparseposer
from engine.models.sparseposer import SPARSE_INDEX, SparsePoser, SparsePoserConfig
from engine.models.sparseposer_infer import DenseGenerator, context_frames
from engine.models.sparseposer_stream import StreamingGenerator, streaming_generator
from engine.tracking import simulate
from tests.engine.test_sparseposer import _reference_poses


def _example(frames: int):
    from engine.motion.retarget import load_motion
    from tests.engine.test_hardening_cli import EX

    return load_motion(EX).slice(100, 100 + frames)


def test_streamed_generator_equals_the_windowed_one_with_the_shipped_weights():
    model, _ = load_sparseposer()
    motion = _example(70)
    rot, disp = pose_from_motion(motion.local_rot, motion.root_pos)
    dq = torch.as_tensor(encoder_input(rot, disp, np.asarray(motion.skeleton.offsets)), dtype=torch.float32)
    x = model.sparse_input(dq)  # (F, 22, 8), zeros off the trackers
    dense, ctx = DenseGenerator(model), context_frames(model)
    static = model.generator.static_features(torch.as_tensor(np.asarray(motion.skeleton.offsets)).float()[None])
    stream = streaming_generator(model, dense, ctx, SPARSE_INDEX, TAIL)
    assert isinstance(stream, StreamingGenerator)
    stream.reset(static)
    twice = StreamingGenerator(dense, ctx, SPARSE_INDEX, TAIL)  # two streams in one batch: the same clip twice
    twice.reset([torch.cat((s, s)) for s in static])
    with torch.no_grad():
        for t in range(len(motion)):
            window = torch.stack([x[max(0, i)] for i in range(t - ctx + 1, t + 1)])  # first frame repeated
            want = dense(window, static, TAIL)
            got = stream(x[t : t + 1, list(SPARSE_INDEX)])[0]
            torch.testing.assert_close(got, want, atol=1e-5, rtol=0)
            both = twice(torch.cat([x[t : t + 1, list(SPARSE_INDEX)]] * 2))
            torch.testing.assert_close(both[1], got, atol=1e-5, rtol=0)
        stream.reset()  # a new clip: its first frame is the whole past again
        want = dense(x[40].expand(ctx, -1, -1), static, TAIL)
        torch.testing.assert_close(stream(x[40:41, list(SPARSE_INDEX)])[0], want, atol=1e-5, rtol=0)


def test_features_are_the_training_features():
    """What the method feeds the generator is what it was trained on (data prepare's
    root-space dual quaternions of the tracked joints)."""
    motion = _example(60)
    rot, disp = pose_from_motion(motion.local_rot, motion.root_pos)
    want = encoder_input(rot, disp, np.asarray(motion.skeleton.offsets))[:, list(SPARSE_INDEX)]
    method = SparsePoserMethod(model=load_sparseposer()[0])
    method.reset(motion.skeleton, motion.fps)
    tracking = simulate(motion, "6")
    got = np.stack([method.features(tracking.frame(i))[list(SPARSE_INDEX)] for i in range(len(motion))])
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_a_kernel_without_streaming_steps_a_window_and_gives_the_plain_pipeline():
    torch.manual_seed(0)
    model = SparsePoser(SparsePoserConfig(window=32, channels=(4, 6, 8), kernel=5, ik_hidden=16)).eval()
    for p in model.ik.parameters():  # non-zero last layers: the limb networks change the pose
        torch.nn.init.normal_(p, std=0.05)
    method = SparsePoserMethod(model=model)
    assert method.stream is None
    motion = _example(40)
    ref = _reference_poses(model, motion, 40)
    method.reset(motion.skeleton, motion.fps)
    tracking = simulate(motion, "6")
    got = np.stack([method.step(tracking.frame(i)).local_rot for i in range(40)])
    np.testing.assert_allclose(got[:, 1:], ref[:, 1:], atol=1e-5)
