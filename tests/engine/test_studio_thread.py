"""Engine thread (engine.studio.thread): commands in, snapshots out, headless and without Qt."""

from __future__ import annotations

import contextlib
import threading
import time

import numpy as np
import pytest

from engine.gizmos import LineGizmo
from engine.methods.base import FrameResult, Method
from engine.studio import commands as w
from engine.studio.session import Session
from engine.studio.session_sensors import SensorSet
from engine.studio.thread import EngineThread


def wait_for(predicate, timeout=10.0):
    """Poll a condition set by the engine thread (a condition variable would hide hangs)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    raise AssertionError("condition not reached in time")


@pytest.fixture
def engine(synthetic_motion):
    session = Session()
    session.set_motion(synthetic_motion)
    worker = session.start_engine()
    yield session, worker
    worker.stop()
    assert not worker.is_alive()


def newest(worker, after=0):
    wait_for(lambda: worker.latest is not None and worker.latest.seq > after)
    return worker.latest


def test_snapshot_is_plain_readonly_numpy(engine):
    session, worker = engine
    snap = newest(worker)
    assert snap.positions.shape == (22, 3) and snap.ground_truth.shape == (22, 3)
    assert len(snap.target_joints) == len(session.sensors)
    with pytest.raises(ValueError):
        snap.positions[0, 0] = 1.0


def test_toggling_a_sensor_changes_the_loss_terms(engine):
    session, worker = engine
    wait_for(lambda: worker.latest is not None and worker.latest.losses)
    joint = next(iter(session.sensors))
    terms = set(worker.latest.losses[-1])
    seq = worker.latest.seq
    session.sensors.edit(joint, enabled=False)
    snap = newest(worker, seq)
    assert joint not in snap.target_joints
    assert set(snap.losses[-1]) != terms


def test_dragging_the_hip_target_moves_the_pose(engine):
    session, worker = engine
    session.sensors.set_preset(next(p for p, j in w_presets().items() if "root" in j))
    snap = newest(worker)
    seq, before = snap.seq, snap.positions.copy()
    session.drag_target("root", session.tracked_position("root", 0) + [0.0, 0.0, 0.3])
    wait_for(
        lambda: (
            worker.latest.seq > seq
            and worker.latest.target_positions.size
            and abs(worker.latest.positions[0, 2] - before[0, 2] - 0.3) < 0.05
        )
    )


def w_presets():
    return {name: tuple(s.joint for s in sensors) for name, sensors in SensorSet.presets().items()}


def test_playback_advances_with_time_and_seek_wins(engine):
    session, worker = engine
    newest(worker)
    session.play()
    wait_for(lambda: worker.latest.frame > 5)
    session.pause()
    session.seek(100)
    wait_for(lambda: worker.latest.frame == 100 and not worker.latest.playing)


class Exploding(Method):
    name = "exploding"

    def reset(self, skeleton, fps=60.0):
        self.n = 0

    def step(self, sensors):
        self.n += 1
        if sensors.frame == 3:
            raise RuntimeError("boom")
        pos = np.full((22, 3), np.nan if sensors.frame == 4 else 0.0)
        return FrameResult(np.zeros((22, 4)), np.zeros(3), pos)


def test_a_failing_method_never_kills_the_thread(synthetic_motion):
    worker = EngineThread(method_factory=lambda name: Exploding())
    worker.start()
    try:
        worker.submit(w.SetMethod("exploding"))
        worker.submit(w.SetMotion(synthetic_motion))
        for f, expect in ((3, "boom"), (4, "non-finite"), (5, "")):
            worker.submit(w.Seek(f))
            wait_for(lambda f=f: worker.latest is not None and worker.latest.frame == f)
            assert expect in worker.latest.error and (expect == "" or worker.latest.error)
            assert np.all(np.isfinite(worker.latest.positions))
        assert worker.latest.warnings >= 2 and worker.is_alive()
    finally:
        worker.stop()


def test_stop_joins_and_leaves_no_thread():
    before = set(threading.enumerate())
    worker = EngineThread()
    worker.start()
    worker.stop()
    assert not worker.is_alive() and [t for t in threading.enumerate() if t not in before] == []


def test_playback_skipping_a_few_frames_keeps_the_methods_temporal_state():
    """A solver slower than real time makes playback skip frames; resetting the method then
    would make every frame a first frame (solved offline, slower still)."""
    from engine.studio.playback import is_jump

    assert is_jump(0, -2, 60.0)  # nothing solved yet
    assert not is_jump(101, 100, 60.0)
    assert not is_jump(105, 100, 60.0)  # a few frames skipped by playback
    assert is_jump(99, 100, 60.0)  # seek backwards (or a loop)
    assert is_jump(100 + 121, 100, 60.0)  # more than 2 s ahead at 60 fps


def test_gizmos_that_relate_joints_get_the_current_pose(engine):
    session, worker = engine
    session.constraints.add("distance", name="hands", joint_a="lwrist", joint_b="rwrist", distance=0.3)
    session.play()
    wait_for(lambda: worker.latest is not None and dict(worker.latest.gizmos).get("hands"))
    giz = dict(worker.latest.gizmos)["hands"]
    assert isinstance(giz, LineGizmo) and giz.points.shape == (2, 3)


class Counting(Method):
    """Counts its steps; decodes any latent to a pose lifted by latent[0] metres."""

    name = "counting"

    def __init__(self):
        self.steps = 0

    def reset(self, skeleton, fps=60.0, **kw):
        pass

    def step(self, sensors):
        self.steps += 1
        return FrameResult(np.tile([1.0, 0, 0, 0], (22, 1)), np.zeros(3), np.zeros((22, 3)), latent=np.zeros(4))

    def decode_latent(self, latent):
        return np.full((22, 3), float(latent[0]))


def test_a_method_that_cannot_be_built_leaves_the_old_one_and_says_why(synthetic_motion):
    def factory(name):
        if name == "broken":
            raise ValueError("assets/models/vae.pt: not a weights file")
        return Counting()

    worker = EngineThread(method_factory=factory)
    worker.start()
    try:
        worker.submit(w.SetMethod("counting"))
        worker.submit(w.SetMotion(synthetic_motion))
        first = newest(worker)
        worker.submit(w.SetMethod("broken"))
        snap = newest(worker, first.seq)
        assert "vae.pt" in snap.method_error and snap.method == "counting"
        worker.submit(w.Seek(5))
        wait_for(lambda: worker.latest.frame == 5)
        assert worker.latest.method_error == "" and worker.latest.method == "counting", "said once, kept"
    finally:
        worker.stop()


def test_a_method_that_cannot_run_from_the_sensors_is_refused_at_the_switch(synthetic_motion):
    from engine.tracking import PRESET_SENSORS

    built = []

    def factory(name):
        built.append(name)
        method = Counting()
        method.name = name
        return method

    worker = EngineThread(method_factory=factory)
    worker.start()
    try:
        worker.submit(w.SetMethod("counting"))
        worker.submit(w.SetSensors(PRESET_SENSORS["6"]))
        worker.submit(w.SetMotion(synthetic_motion))
        first = newest(worker)
        worker.submit(w.SetMethod("rpm"))
        snap = newest(worker, first.seq)
        assert "'3-head-hands'" in snap.method_error and snap.method == "counting"
        assert "rpm" not in built, "refused before its models are loaded"
        worker.submit(w.SetSensors(PRESET_SENSORS["3-head-hands"]))
        worker.submit(w.SetMethod("rpm"))
        wait_for(lambda: worker.latest.method == "rpm")
        assert worker.latest.method_error == "" and built[-1] == "rpm"
    finally:
        worker.stop()


@contextlib.contextmanager
def running(method, motion):
    """An engine thread whose every method is ``method``, loaded with ``motion``."""
    worker = EngineThread(method_factory=lambda name: method)
    worker.start()
    try:
        worker.submit(w.SetMethod(method.name))
        worker.submit(w.SetMotion(motion))
        yield worker
    finally:
        worker.stop()


def test_decoding_a_latent_shows_the_pose_without_solving_again(synthetic_motion):
    method = Counting()
    with running(method, synthetic_motion) as worker:
        first = newest(worker)
        steps = method.steps
        for k, value in enumerate((0.5, 0.7, 0.9)):
            worker.submit(w.DecodeLatent(np.array([value, 0, 0, 0])))
            newest(worker, first.seq + k)
            wait_for(lambda value=value: worker.latest.decoded is not None and worker.latest.decoded[0, 0] == value)
        assert method.steps == steps, "scrubbing a latent must not advance the solver"
        assert worker.latest.frame == first.frame


def test_snapshots_carry_every_solved_frame_and_a_jump_restarts_the_record(engine):
    """The GUI draws only the newest snapshot, so the per-frame record travels with it."""
    session, worker = engine
    for _ in range(5):
        seq = newest(worker).seq
        session.step(1)
        newest(worker, seq)
    wait_for(lambda: len(worker.latest.history) >= 5)
    hist = worker.latest.history
    frames = [r.frame for r in hist]
    assert frames == sorted(frames) and frames[-1] == worker.latest.frame
    assert all(set(r.losses) >= {"total"} and r.iterations >= 0 and r.ms >= 0 for r in hist)
    seq = worker.latest.seq
    session.seek(0)  # backwards: temporal state and the record start again
    wait_for(lambda: worker.latest.seq > seq and worker.latest.frame == 0)
    assert [r.frame for r in worker.latest.history] == [0]


def test_playback_without_loop_ends_on_the_last_frame_and_says_so(engine):
    """Even when the last frame was solved while still playing, a snapshot reports the stop."""
    session, worker = engine
    newest(worker)
    n = session.num_frames
    session.set_playback(speed=4.0, loop=False)
    session.seek(n - 30)
    session.play()
    wait_for(lambda: worker.latest.frame == n - 1 and not worker.latest.playing)
    assert not worker._playing


class CountingResets(Counting):
    def __init__(self):
        super().__init__()
        self.resets = 0

    def reset(self, skeleton, fps=60.0, **kw):
        self.resets += 1


def test_a_load_or_a_jump_resets_the_method_once(synthetic_motion):
    method = CountingResets()
    with running(method, synthetic_motion) as worker:
        first = newest(worker)
        assert method.resets == 1  # the load; the first solve is not a second "jump"
        worker.submit(w.Seek(40))
        snap = newest(worker, first.seq)
        wait_for(lambda: worker.latest.frame == 40)
        assert method.resets == 1  # 40 frames ahead is playback-like, not a jump
        worker.submit(w.Seek(3))
        wait_for(lambda: worker.latest.frame == 3 and worker.latest.seq > snap.seq)
        assert method.resets == 2


class Slow(Counting):
    """Takes ``ms`` per frame, so playback at 60 fps outruns it; records what it solved."""

    name = "slow"

    def __init__(self, ms=30.0, first_ms=0.0):
        super().__init__()
        self.ms, self.first_ms, self.frames, self.fresh = ms, first_ms, [], True

    def reset(self, skeleton, fps=60.0, **kw):
        self.fresh = True

    def step(self, sensors):
        time.sleep((self.first_ms if self.fresh else self.ms) / 1000.0)
        self.fresh = False
        self.frames.append(sensors.frame)
        return super().step(sensors)


def test_every_frame_playback_solves_each_frame_in_order_and_waits_for_the_solver(synthetic_motion):
    method = Slow(ms=30.0)  # 33 frames/s against a 60 fps clip
    with running(method, synthetic_motion) as worker:
        newest(worker)
        worker.submit(w.Play(1.0, True, "every_frame"))
        wait_for(lambda: worker.latest.frame >= 20)
        worker.submit(w.Pause())
        time.sleep(0.1)
        played = method.frames[1:]
        assert played == list(range(1, len(played) + 1)), "no clip frame skipped or repeated"
        assert worker.latest.frames_skipped == 0 and worker.latest.pace == "every_frame"


def test_real_time_playback_skips_frames_and_counts_them(synthetic_motion):
    method = Slow(ms=30.0)
    with running(method, synthetic_motion) as worker:
        newest(worker)
        worker.submit(w.Play(1.0, True, "real_time"))
        wait_for(lambda: worker.latest.frame >= 40)
        worker.submit(w.Pause())
        snap = worker.latest
        assert snap.frames_skipped > 5 and snap.pace == "real_time"
        solved = len([f for f in method.frames if 0 < f <= snap.frame])
        assert solved + snap.frames_skipped == snap.frame  # every frame is solved or counted


@pytest.mark.parametrize("pace", ["every_frame", "real_time"])
def test_looping_does_not_skip_the_start_of_the_clip(synthetic_motion, pace):
    """The first solve after a loop is slow (offline); the clock restarts after it."""
    method = Slow(ms=2.0, first_ms=400.0)
    with running(method, synthetic_motion) as worker:
        newest(worker)
        n = len(synthetic_motion)
        worker.submit(w.Seek(n - 5))
        wait_for(lambda: worker.latest.frame == n - 5)
        worker.submit(w.Play(1.0, True, pace))
        wait_for(lambda: 0 < worker.latest.frame < n - 5 and worker.latest.frame >= 6, timeout=20)
        worker.submit(w.Pause())
        tail = method.frames[method.frames.index(n - 5) :]
        after_loop = tail[tail.index(0) :]
        assert after_loop[:6] == [0, 1, 2, 3, 4, 5], after_loop[:10]


def test_a_sensor_source_that_fails_is_reported_not_replaced_by_perfect_trackers(synthetic_motion):
    from engine.sensor_source import SensorSource

    class Broken(SensorSource):
        fps, num_frames = 60.0, 10

        def set_sensors(self, sensors):
            raise OSError("tracker stream closed")

        def frame(self, frame):
            raise AssertionError("never read")

    method = Counting()
    with running(method, synthetic_motion) as worker:
        first = newest(worker)
        worker.submit(w.SetSource(Broken()))
        worker.submit(w.Seek(2))
        newest(worker, first.seq)
        wait_for(lambda: "tracker stream closed" in worker.latest.error or worker.latest.warnings > first.warnings)
        assert worker._source.num_frames == len(synthetic_motion)  # the clip source stayed


class Timed(Counting):
    """Reports its own per-iteration breakdown, as DragPoser does (``FrameResult.timings``)."""

    name = "timed"

    def step(self, sensors):
        res = super().step(sensors)
        res.iterations = 4
        res.timings = {"ms_per_iteration": 1.5, "decoder": 0.3, "fk_losses": 0.9, "backward": 0.2, "step": 0.1}
        return res


def test_snapshots_carry_the_solver_timing_figures(synthetic_motion):
    with running(Timed(), synthetic_motion) as worker:
        snap = newest(worker)
        assert snap.timing["ms_per_iteration"] == 1.5 and snap.timing["fk_losses"] == 0.9
        assert snap.timing["ms_per_frame"] >= 0
    with running(Counting(), synthetic_motion) as worker:  # no breakdown: wall time only
        snap = newest(worker)
        assert set(snap.timing) == {"ms_per_frame"}


class Deferring(Counting):
    """Records, at each between_frames call, how many snapshots had been published."""

    name = "deferring"

    def __init__(self, worker_box):
        super().__init__()
        self.box, self.calls = worker_box, []

    def between_frames(self):
        worker = self.box[0]
        self.calls.append((self.steps, worker.latest.seq if worker.latest is not None else 0))


def test_deferred_method_work_runs_after_each_frame_is_published(synthetic_motion):
    box = []
    method = Deferring(box)
    worker = EngineThread(method_factory=lambda name: method)
    box.append(worker)
    worker.start()
    try:
        worker.submit(w.SetMethod(method.name))
        worker.submit(w.SetMotion(synthetic_motion))
        first = newest(worker)
        worker.submit(w.Seek(3))
        wait_for(lambda: worker.latest.seq > first.seq and len(method.calls) >= 2)
    finally:
        worker.stop()
    assert all(seq >= 1 for _, seq in method.calls), "called after a snapshot was out"
    assert [steps for steps, _ in method.calls] == sorted(steps for steps, _ in method.calls)
    assert method.calls[-1][0] == method.steps  # once per solved frame, after its step


def test_snapshots_say_which_clip_or_method_they_are_of(engine, synthetic_motion):
    """``opened`` numbers what the session opened; a view tells a snapshot of what was
    open before by it, even one published after the session asked for the change, and
    a restarted engine is sent the current number."""
    session, worker = engine
    wait_for(lambda: worker.latest is not None and worker.latest.opened == session.opened)
    before = session.opened
    session.set_motion(synthetic_motion.slice(0, 30))
    assert session.opened == before + 1
    wait_for(lambda: worker.latest.opened == session.opened and worker.latest.num_frames == 30)
    session.set_method(session.method)  # a method change numbers it too
    wait_for(lambda: worker.latest.opened == session.opened)
    new = session.restart_engine()
    try:
        wait_for(lambda: new.latest is not None and new.latest.opened == session.opened)
    finally:
        new.stop()


class Resetting(Counting):
    """:class:`Counting` that also counts its resets."""

    def __init__(self, name):
        super().__init__()
        self.name, self.resets = name, 0

    def reset(self, skeleton, fps=60.0, **kw):
        self.resets += 1


def test_ghosts_come_and_go_without_resetting_the_shown_method(synthetic_motion):
    built: dict[str, list] = {}

    def factory(name):
        method = Resetting(name)
        built.setdefault(name, []).append(method)
        return method

    worker = EngineThread(method_factory=factory)
    worker.start()
    try:
        worker.submit(w.SetMethod("shown", opened=1))
        worker.submit(w.SetMotion(synthetic_motion, opened=2))
        worker.submit(w.Seek(10))
        wait_for(lambda: worker.latest is not None and worker.latest.frame == 10)
        (shown,) = built["shown"]
        resets, steps, opened = shown.resets, shown.steps, worker.latest.opened
        worker.submit(w.SetGhosts(("ik",)))
        wait_for(lambda: "ik" in worker.latest.ghosts)
        (ghost,) = built["ik"]
        assert ghost.resets == 1 and ghost.steps >= 1  # built, reset for the clip, solved the frame
        assert shown.resets == resets and shown.steps > steps  # the shown method solved on, not reset
        assert built["shown"] == [shown] and worker.latest.opened == opened  # no switch
        worker.submit(w.SetGhosts(()))
        wait_for(lambda: not worker.latest.ghosts)
        assert shown.resets == resets and len(built["ik"]) == 1
    finally:
        worker.stop()


def test_a_ghost_toggled_in_the_session_keeps_the_solved_frames(engine):
    session, worker = engine
    session.seek(30)
    wait_for(lambda: worker.latest is not None and worker.latest.frame == 30)
    opened, run, shown = session.opened, worker.latest.history_run, session.method
    session.set_ghosts(("autoencoder",))
    wait_for(lambda: "autoencoder" in worker.latest.ghosts, timeout=60.0)
    assert session.opened == opened and worker.latest.history_run == run
    assert session.ghosts == ("autoencoder",) and session.method == shown
    session.set_method(shown, ())  # an undo of the ghost takes the same path
    wait_for(lambda: not worker.latest.ghosts)
    assert session.opened == opened and worker.latest.history_run == run


def test_a_method_switch_starts_the_solve_rate_afresh(synthetic_motion):
    class Slow(Counting):
        name = "slow"

        def step(self, sensors):
            time.sleep(0.02)
            return super().step(sensors)

    worker = EngineThread(method_factory=lambda name: Slow() if name == "slow" else Counting())
    worker.start()
    try:
        worker.submit(w.SetMethod("counting", opened=1))
        worker.submit(w.SetMotion(synthetic_motion, opened=2))
        worker.submit(w.Play(1.0, True, "every_frame"))
        wait_for(lambda: worker.latest is not None and worker.latest.engine_fps > 200)
        worker.submit(w.SetMethod("slow", opened=3))
        wait_for(lambda: worker.latest.method == "slow" and worker.latest.solved > 0)
        seq = worker.latest.seq
        wait_for(lambda: worker.latest.seq > seq)
        assert worker.latest.engine_fps < 60  # 20 ms a frame, not the fast method's average
    finally:
        worker.stop()
