"""SparsePoser as a method (``--method sparseposer``): six 6-DoF trackers, preset ``6``.

Per frame the trackers become root-space dual quaternions (the root slot holds the hip
tracker's rotation in the previous frame's heading and its displacement), appended to a
window of the last ``T`` frames (64; at the start of a clip the first frame is
repeated). The generator decodes the window's last frame, the learned IK moves each
limb towards its tracker, and the root takes the hip tracker's position and rotation,
as in the paper. A step computes only what changes from one frame to the next: the
encoder's newest output per level and the decoder rows the last frame reads
(:mod:`engine.models.sparseposer_stream`; the same last frame as a full decode of the
whole window, to 1e-5 with the shipped weights), the four limb networks as one batched
MLP, and the per-frame arithmetic on small arrays in numpy.

**Future frames.** The paper's realtime variant (*Ours-0*) sees no future frames and an
offline variant sees 7. Methods here are fed one frame at a time, so this is the
realtime variant in both ``--mode`` settings; the model is trained with extra weight
on the window's last frame for that reason (``engine/training/sparseposer.py``).

A lost tracker (``connected`` False) keeps feeding its last connected reading: the
paper's method has no notion of tracking loss.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult, Method, check_preset
from engine.methods.presets import REQUIRED_PRESET
from engine.models.sparseposer import LIMB_EE, SPARSE_INDEX, SPARSE_JOINTS, local_rotations
from engine.models.sparseposer_infer import DenseGenerator, StackedLimbIK, context_frames
from engine.models.sparseposer_stream import streaming_generator
from engine.motion.clip import Motion
from engine.sensors import SensorFrame

#: Rows of the limbs' end effectors (ankles, wrists) in the tracked joints.
_EE_ROWS = [SPARSE_INDEX.index(j) for j in LIMB_EE]
#: Decoder frames evaluated per step (the last output frame equals the full decode's).
TAIL = 8


class SparsePoserMethod(Method):
    """Generator + learned IK over a sliding window of tracker frames.

    Parameters
    ----------
    model : SparsePoser, optional
        Default: the shipped ``assets/models/sparseposer.pt``.
    sparseposer_path : path, optional
        Load the weights from this file instead.
    threads : int
        Torch intra-op threads during a step (0 = leave torch's setting). One is fastest:
        a step is many small products, which a second thread slows down.
    **_unused
        Optimizer keywords meant for other methods (``mode``, ``iterations``...), ignored.
    """

    name = "sparseposer"

    def __init__(self, model: Any = None, sparseposer_path: Any = None, threads: int = 1, **_unused: Any) -> None:
        if model is None:
            from engine.models.loading import load_sparseposer

            model, _ = load_sparseposer(sparseposer_path)
        self.model = model.eval().requires_grad_(False)
        self.window = model.config.window
        self.context = context_frames(self.model)
        self.generator = DenseGenerator(self.model)
        self.limb_ik = StackedLimbIK(self.model)
        # one new frame per step; None (a window per step) for kernels other than 3
        self.stream = streaming_generator(self.model, self.generator, self.context, SPARSE_INDEX, TAIL)
        sparse = list(SPARSE_INDEX)
        self._sparse_mean, self._sparse_std = model.dq_mean[sparse], model.dq_std[sparse]
        self._rot_mean, self._rot_std = model.dq_mean[:, :4].double().numpy(), model.dq_std[:, :4].double().numpy()
        self.threads = int(threads)
        self.reset(sk.Skeleton.canonical())

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.offsets = np.asarray(skeleton.offsets, dtype=np.float64)
        self._off_t = torch.as_tensor(self.offsets, dtype=torch.float32)[None]
        with torch.inference_mode():
            self._static = self.model.generator.static_features(self._off_t)
        # the limb networks' offset inputs (x 10, as trained), constant per skeleton
        self._limb_off = (self._off_t[0, self.limb_ik.limb] * 10.0).flatten(1).numpy()  # (4, 12)
        # the last ``context`` normalised sparse frames, written twice so that they are
        # always one contiguous slice: frames[:, pos : pos + context] (kernels other than 3)
        self._frames = torch.zeros(1, 2 * self.context, sk.NUM_JOINTS, 8)
        self._pos = -1  # no frame yet
        if self.stream is not None:
            self.stream.reset(self._static)
        self._last_rot, self._last_pos = np.zeros((len(SPARSE_JOINTS), 4)), np.zeros((len(SPARSE_JOINTS), 3))
        self._seen = np.zeros(len(SPARSE_JOINTS), dtype=bool)
        self._prev_root: tuple[np.ndarray, np.ndarray] | None = None

    def _sparse_features(self, frame: SensorFrame) -> np.ndarray:
        """Raw root-space dual quaternions ``(6, 8)`` of the tracked joints (SPARSE_JOINTS)."""
        check_preset(frame.readings, SPARSE_JOINTS, self.name, REQUIRED_PRESET["sparseposer"])
        rd = [frame.readings[j] for j in SPARSE_JOINTS]
        rot = np.array([r.rotation for r in rd], dtype=np.float64)  # (6, 4)
        pos = np.array([r.position for r in rd], dtype=np.float64)  # (6, 3)
        ok = np.array([r.connected for r in rd]) & np.isfinite(rot).all(1) & np.isfinite(pos).all(1)
        take = ok | ~self._seen  # a lost tracker keeps its last good reading (the first is taken)
        self._last_rot[take], self._last_pos[take], self._seen[take] = rot[take], pos[take], True
        rot, pos = Q.normalize(self._last_rot), self._last_pos.copy()
        r_rot, r_pos = rot[0].copy(), pos[0].copy()
        prev_rot, prev_pos = self._prev_root or (r_rot, r_pos)
        self._prev_root = (r_rot, r_pos)
        # slot 0: the hip tracker in the previous frame's heading; others: in the hip's frame
        inv = np.stack((Q.conjugate(Q.heading(prev_rot)), Q.conjugate(r_rot)))[[0] + [1] * (len(rd) - 1)]
        pos[0] -= prev_pos
        pos[1:] -= r_pos
        # dual quaternions (r, 0.5 (0, t) r), as pymotion's from_rotation_translation
        # (whose component-wise product costs more than the rest of the step's features)
        out = np.empty((len(rd), 8))
        out[:, :4] = Q.canonicalize(Q.mul(inv, rot))
        t = np.zeros((len(rd), 4))
        t[:, 1:] = Q.rotate(inv, pos)
        out[:, 4:] = 0.5 * Q.mul(t, out[:, :4])
        return out

    def features(self, frame: SensorFrame) -> np.ndarray:
        """Raw root-space dual quaternions ``(22, 8)`` of this frame (zeros off the trackers)."""
        out = np.zeros((sk.NUM_JOINTS, 8))
        out[list(SPARSE_INDEX)] = self._sparse_features(frame)
        return out

    def _push(self, dq: np.ndarray | torch.Tensor) -> torch.Tensor:
        """Append one frame's raw dq ``(22, 8)``; return the window ``(1, context, 22, 8)``
        (normalised, zeros off the trackers; the first frame fills it at a clip's start)."""
        x = self.model.sparse_input(torch.as_tensor(dq, dtype=torch.float32))
        c = self.context
        if self._pos < 0:
            self._frames[0] = x
            self._pos = 0
        else:
            self._frames[0, self._pos] = x
            self._frames[0, self._pos + c] = x
            self._pos = (self._pos + 1) % c
        return self._frames[:, self._pos : self._pos + c]

    def _generate(self, dq6: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Generator output (normalised dq, ``(22, 8)``) of the stream so far with this
        frame's tracked dq ``(6, 8)``, and that frame normalised ``(6, 8)``."""
        x = (torch.from_numpy(dq6).float() - self._sparse_mean) / self._sparse_std
        if self.stream is not None:
            return self.stream(x[None])[0].numpy(), x.numpy()
        dq = torch.zeros(sk.NUM_JOINTS, 8)
        dq[list(SPARSE_INDEX)] = torch.from_numpy(dq6).float()
        return self.generator(self._push(dq)[0], self._static, TAIL).numpy(), x.numpy()

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        threads = torch.get_num_threads()
        if self.threads:
            torch.set_num_threads(self.threads)
        try:
            dq6 = self._sparse_features(sensors)
            with torch.inference_mode():
                out, x = self._generate(dq6)
                # learned IK: each limb's generator dq, offsets and normalised tracker dq
                inp = np.concatenate((out[self.limb_ik.limb_index].reshape(4, -1), self._limb_off, x[_EE_ROWS]), axis=1)
                delta = self.limb_ik.mlp(torch.from_numpy(inp)[:, None])[:, 0].numpy()
        finally:
            torch.set_num_threads(threads)
        local = local_rotations(out[:, :4] * self._rot_std + self._rot_mean)
        limb = self.limb_ik.limb_index
        local[limb] = Q.canonicalize(Q.normalize(local[limb] + delta.reshape(4, 4, 4)))
        assert self._prev_root is not None  # set by _sparse_features above
        root_rot, root_pos = self._prev_root  # this frame's hip tracker
        local[0] = root_rot
        pos, _ = fk(local, root_pos, self.offsets)
        return FrameResult(local, root_pos.copy(), pos, ms=1000.0 * (time.perf_counter() - t0))


def create(**kwargs: Any) -> SparsePoserMethod:
    """Registry factory (``mode``/``iterations`` are accepted and ignored)."""
    return SparsePoserMethod(**kwargs)
