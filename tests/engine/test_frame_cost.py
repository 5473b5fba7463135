"""The per-frame work outside DragPoser's iterations, written for speed, gives what plain
references give on real frames (the shipped models on the bundled clip):

* the limb reach and tracker rotations (``engine/solver/limb_ik.py``: partial FK on Python
  floats, one FK at the end) against a plain numpy reference (a full FK per limb) below;
* the predictor's conditioning from the root increment (numpy) against the torch formula;
* the predictor's look-ahead deferred to ``between_frames`` against running it at once.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods import dragposer as D
from engine.methods import dragposer_parts
from engine.methods import dragposer_root as R
from engine.models import load_default_models
from engine.motion.retarget import load_motion
from engine.solver import OptimizerSettings, limb_ik
from engine.solver.temporal import TemporalSchedule
from engine.tracking import simulate

CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"
FRAMES = 30


# -- the reference: plain numpy, a full FK per limb --------------------------------------


def _axis_angle(axis, angle):
    return np.concatenate(([math.cos(angle / 2)], math.sin(angle / 2) * axis))


def _between(u, v):
    u, v = u / np.linalg.norm(u), v / np.linalg.norm(v)
    q = np.concatenate(([1.0 + float(u @ v)], np.cross(u, v)))
    n = np.linalg.norm(q)
    if n < 1e-9:
        perp = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
        return _axis_angle(perp / np.linalg.norm(perp), math.pi)
    return q / n


def reach_reference(local_rot, root_pos, offsets, targets):
    local = np.array(local_rot, dtype=np.float64)
    for c, target in targets.items():
        a, b = limb_ik.LIMBS[c]
        pos, world = fk(local, root_pos, offsets)
        pa, pb, pc = pos[a], pos[b], pos[c]
        t = np.asarray(target, dtype=np.float64)
        l1, l2 = np.linalg.norm(pb - pa), np.linalg.norm(pc - pb)
        d = float(np.clip(np.linalg.norm(t - pa), abs(l1 - l2) + 1e-3, l1 + l2 - 1e-3))
        u, v = pa - pb, pc - pb
        n = np.cross(u, v)
        if np.linalg.norm(n) < 1e-9:
            n = QN.rotate(world[b], np.array([1.0, 0.0, 0.0]))
        n = n / np.linalg.norm(n)
        current = math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v))
        wanted = math.acos(float(np.clip((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0, 1.0)))
        bend = _axis_angle(n, wanted - current)
        wb = QN.mul(bend, world[b])
        pc_new = pb + QN.rotate(bend, v)
        turn = _between(pc_new - pa, t - pa) if np.linalg.norm(t - pa) > 1e-9 else np.array([1.0, 0, 0, 0])
        wa, wb = QN.mul(turn, world[a]), QN.mul(turn, wb)
        local[a] = QN.mul(QN.conjugate(world[sk.PARENTS[a]]), wa)
        local[b] = QN.mul(QN.conjugate(wa), wb)
        local[c] = QN.mul(QN.conjugate(wb), world[c])
    local *= np.where(local[:, :1] < 0, -1.0, 1.0)
    return local, fk(local, root_pos, offsets)[0]


def adopt_reference(local_rot, root_pos, offsets, targets):
    local = np.array(local_rot, dtype=np.float64)
    world = np.empty_like(local)
    world[0] = local[0]
    for j in range(1, sk.NUM_JOINTS):
        p = sk.PARENTS[j]
        if j in targets:
            t = np.asarray(targets[j], dtype=np.float64)
            t = t / max(float(np.linalg.norm(t)), 1e-12)
            local[j] = QN.mul(QN.conjugate(world[p]), t)
            if local[j, 0] < 0:
                local[j] = -local[j]
        world[j] = QN.mul(world[p], local[j])
    return local, fk(local, root_pos, offsets)[0]


# -- real frames ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def models():
    return load_default_models()


@pytest.fixture(scope="module")
def motion():
    return load_motion(CLIP)


@pytest.mark.parametrize("sensors", ["6", "3-head-hands"])
def test_reach_and_rotations_equal_the_previous_code_on_real_frames(models, motion, sensors, monkeypatch):
    calls = []
    new_finish = limb_ik.finish

    def spy(local, root, offsets, reach_to, turn_to, neck_twist_share=0.0, level=(), shoulder_deg=0.0):
        assert level == ()  # 6-DoF feet, or none: nothing to level (tests/engine/test_level_feet.py)
        # the clavicles' turn is a step the previous code had not (tests/engine/test_shoulder_reach.py)
        assert shoulder_deg == OptimizerSettings().shoulder_reach
        got = new_finish(local, root, offsets, reach_to, turn_to, neck_twist_share)
        want_local, want_pos = local, None
        limbs = {j: t for j, t in reach_to.items() if j != limb_ik.HEAD}
        if limb_ik.HEAD in reach_to:  # the spine's turn before the limbs (tests/engine/test_head_reach.py)
            want_local = limb_ik.reach_head_local(want_local, root, offsets, reach_to[limb_ik.HEAD])
        if limbs:
            want_local, want_pos = reach_reference(want_local, root, offsets, limbs)
        if limb_ik.HEAD in turn_to:  # the step between the two (tests/engine/test_limb_ik.py)
            want_local = limb_ik.share_neck_twist(want_local, root, offsets, turn_to[limb_ik.HEAD], neck_twist_share)
        if turn_to:
            want_local, want_pos = adopt_reference(want_local, root, offsets, turn_to)
        calls.append((len(reach_to), len(turn_to)))
        np.testing.assert_allclose(got[0], want_local, atol=1e-9, rtol=0)
        np.testing.assert_allclose(got[1], want_pos, atol=1e-9, rtol=0)
        return new_finish(local, root, offsets, reach_to, turn_to, neck_twist_share, level, shoulder_deg)

    monkeypatch.setattr(dragposer_parts, "finish", spy)  # what FramePlan.finished calls
    m = D.DragPoserMethod(models.vae, models.predictor)
    m.reset(motion.skeleton, motion.fps)
    tr = simulate(motion, sensors)
    for i in range(FRAMES):
        m.step(tr.frame(i))
    assert len(calls) == FRAMES
    assert calls[-1] == ((5, 5) if sensors == "6" else (2, 3))  # head+wrists+ankles / head+hands


def test_reach_and_rotations_equal_the_previous_code_on_random_poses():
    rng = np.random.default_rng(3)
    off = sk.Skeleton.canonical().offsets
    for _ in range(20):
        local = rng.normal(size=(22, 4))
        local /= np.linalg.norm(local, axis=-1, keepdims=True)
        root = rng.normal(0, 0.3, 3) + [0, 0, 1]
        pos, _ = fk(local, root, off)
        ends = [j for j in limb_ik.LIMBS if rng.random() < 0.7]
        reach_to = {j: pos[j] + rng.normal(0, 0.1, 3) for j in ends}
        turn_to = {j: rng.normal(size=4) for j in (3, 7, 13, 17, 21) if rng.random() < 0.7}
        turn_to[4] = rng.normal(size=4)  # a toe below a turned ankle: the nested case
        got = limb_ik.finish(local, root, off, reach_to, turn_to)
        want = reach_reference(local, root, off, reach_to) if reach_to else (local, None)
        want = adopt_reference(want[0], root, off, turn_to)
        np.testing.assert_allclose(got[0], want[0], atol=1e-9)
        np.testing.assert_allclose(got[1], want[1], atol=1e-9)


def test_predictor_conditioning_equals_the_torch_root_increment(models, motion, monkeypatch):
    m = D.DragPoserMethod(models.vae, models.predictor)
    m.reset(motion.skeleton, motion.fps)
    tr = simulate(motion, "6")
    conds = []
    record = m.priors.schedule.record

    def spy(frame, latent, cond):
        conds.append(cond().clone())  # the conditioning is computed when first read
        record(frame, latent, cond)

    monkeypatch.setattr(m.priors.schedule, "record", spy)
    roots, results = [], []
    for i in range(FRAMES):
        roots.append(m._root)
        results.append(m.step(tr.frame(i)))
    disps = []
    for i in range(1, FRAMES):
        # the hips are tracked: frame i's root is relative to the previous solved root as is
        prev = roots[i]
        pos = torch.as_tensor(results[i].positions, dtype=torch.float32)
        h_inv = Q.conjugate(Q.heading(prev.rotation))
        disps.append(Q.rotate(h_inv, pos[0] - prev.position))
        want = torch.cat((torch.stack(disps[-4:]).sum(0), pos[R._HEIGHT_IDX, 2]))
        np.testing.assert_allclose(conds[i].numpy(), want.numpy(), atol=1e-6)


def test_predictor_runs_in_pieces_give_the_latents_of_one_run(models):
    """Deferred blocks, run piece by piece between frames (sometimes) or by the frames
    that need them, against the whole run at once through ``predict``: bit for bit."""

    class Whole:  # the predictor without pieces
        def predict(self, *args):
            return models.predictor.predict(*args)

    torch.set_num_threads(1)
    rng = np.random.default_rng(0)
    latents = torch.as_tensor(rng.normal(0, 1, (80, 24)), dtype=torch.float32)
    conds = torch.as_tensor(rng.normal(0, 0.1, (80, 9)), dtype=torch.float32)
    for future in (1, 16):
        got = {}
        for pieces in (False, True):
            sched, out = TemporalSchedule(4, 16), []
            pred = models.predictor if pieces else Whole()
            for i in range(80):
                z, warn = sched.prediction(i, pred, future, defer=pieces)
                assert not warn
                out.append(z)
                sched.record(i, latents[i], conds[i])
                if pieces and i % 3:  # between frames, sometimes
                    sched.run_pending()
            got[pieces] = out
        assert sum(z is not None for z in got[True]) == 79
        for a, b in zip(got[False], got[True]):
            assert (a is None and b is None) or torch.equal(a, b)


def test_between_frames_leaves_one_piece_per_gap(models, motion):
    """Six trackers: the block due every fourth frame is one decoder step between two
    frames, the encoder of the next block another; a frame then runs no predictor."""
    m = D.DragPoserMethod(models.vae, models.predictor)
    m.reset(motion.skeleton, motion.fps)
    tr = simulate(motion, "6")
    calls = []
    enc, nxt = models.predictor.encode_past, models.predictor.next_latent
    try:
        models.predictor.encode_past = lambda *a: (calls.append("enc"), enc(*a))[1]
        models.predictor.next_latent = lambda *a: (calls.append("dec"), nxt(*a))[1]
        per_frame = []
        for i in range(16):
            calls.clear()
            m.step(tr.frame(i))
            in_step = list(calls)
            calls.clear()
            m.between_frames()
            per_frame.append((in_step, list(calls)))
    finally:
        del models.predictor.encode_past, models.predictor.next_latent
    for i, (in_step, between) in enumerate(per_frame[5:], start=5):
        assert in_step == [], (i, in_step)
        assert len(between) <= 1, (i, between)
    assert sum(len(b) for _, b in per_frame[4:16]) == 6  # three blocks: encoder + one step each


# -- the live policy: a per-frame deadline ----------------------------------------------


@pytest.mark.parametrize("fast", [True, False])
def test_a_deadline_cuts_the_iterations_and_keeps_at_least_one(models, motion, fast):
    import time

    m = D.DragPoserMethod(models.vae, models.predictor, fast=fast, iterations=10)
    m.reset(motion.skeleton, motion.fps)
    tr = simulate(motion, "6")
    assert m.step(tr.frame(0), deadline=time.perf_counter() - 1.0).iterations == 1  # offline, bounded too
    assert m.step(tr.frame(1), deadline=time.perf_counter() - 1.0).iterations == 1
    assert m.step(tr.frame(2), deadline=time.perf_counter() + 60.0).iterations == 10
    assert m.step(tr.frame(3)).iterations == 10
    t0 = time.perf_counter()
    cut = m.step(tr.frame(4), deadline=t0 + 0.002)
    assert 1 <= cut.iterations < 10  # ten iterations take far more than 2 ms
    assert np.isfinite(cut.positions).all()


def test_live_run_gives_the_method_its_deadline_and_time_between_frames():
    from engine.sensors import Sensor, SensorFrame
    from engine.tracker_io.live import LiveRun
    from engine.tracker_io.receiver import LiveFrame

    class Stream:  # three frames, then nothing
        def __init__(self):
            self.frames = [
                LiveFrame(k + 1, k / 60.0, 100.0 + k, SensorFrame(k, {"root": Sensor("root", np.zeros(3))}))
                for k in range(3)
            ]
            self.last_arrival = None

        def wait_frame(self, after, timeout):
            nxt = [f for f in self.frames if f.index > after]
            if nxt:
                return nxt[0]
            import time

            self.last_arrival = time.perf_counter() - 10.0
            return None

    class Probe(D.Method):
        takes_deadline = True

        def __init__(self):
            self.calls = []

        def reset(self, skeleton, fps=60.0, *, reference=None):
            pass

        def step(self, sensors, deadline=None):
            self.calls.append(("step", deadline))
            from engine.methods import FrameResult

            return FrameResult(np.tile([1.0, 0, 0, 0], (22, 1)), np.zeros(3), np.zeros((22, 3)), iterations=3)

        def between_frames(self):
            self.calls.append(("between", None))

    import gc

    probe = Probe()
    gc_during = []
    probe.reset = lambda *a, **k: gc_during.append(gc.isenabled())  # noqa: E731
    step = probe.step
    probe.step = lambda sensors, deadline=None: (gc_during.append(gc.isenabled()), step(sensors, deadline))[1]  # noqa: E731
    assert gc.isenabled()
    out = LiveRun(Stream(), probe, sk.Skeleton.canonical(), 60.0, budget_ms=12.0).run(idle_timeout_s=1.0)
    # no automatic full collection while streaming (they stalled frames by 220-240 ms); back on after
    assert gc_during[-3:] == [False, False, False] and gc.isenabled()
    assert out.frames_solved == 3 and list(out.figures.iterations) == [3, 3, 3]
    assert probe.calls == [
        ("step", pytest.approx(100.012)),
        ("between", None),
        ("step", pytest.approx(101.012)),
        ("between", None),
        ("step", pytest.approx(102.012)),
        ("between", None),
    ]
