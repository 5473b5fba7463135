"""The Qt-free authoring model: every edit a command that undoes and redoes exactly, events
that say what changed, refused edits that change nothing, bakes and range re-solves as
jobs with progress and a cancel that leaves the model as it was."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring import events as ev
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.authoring.state import differences
from engine.errors import UserError
from engine.progress import Cancelled

LW, RW = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rwrist"]


class Clock:
    """Seconds that advance by ``step`` on every read: the history's merge window."""

    def __init__(self, step: float) -> None:
        self.now, self.step = 0.0, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now


@pytest.fixture
def session(vae):
    return AuthoringSession(PoseMode(vae, 1.75), clock=Clock(1.0))  # a second apart: no merging


def record(session) -> list[tuple[str, object]]:
    seen: list[tuple[str, object]] = []
    for name in ("targets", "pose", "keys", "animation", "constraints", "frame", "history", "bake"):
        getattr(session.events, name).connect(lambda e, n=name: seen.append((n, e)))
    return seen


def same(a, b) -> bool:
    """Two model states equal in every part (planted feet and pose arrays too)."""
    d = differences(a, b)
    planted = [j for j, _ in a.planted] == [j for j, _ in b.planted] and all(
        np.array_equal(p, q) for (_, p), (_, q) in zip(a.planted, b.planted)
    )
    return not (d.joints or d.keys or d.pose or d.animation or d.constraints) and planted


def test_every_edit_is_a_command_that_undoes_and_redoes_exactly(session):
    s = session
    start = s.pose.positions[LW].copy()
    edits = [
        lambda: s.drag_joint("lwrist", start + [0.0, -0.1, 0.1]),
        lambda: s.edit_target("lwrist", weight=5.0),
        lambda: s.hold_turn("lwrist", True),
        lambda: s.edit_target("lwrist", enabled=False),
        lambda: s.add_key(0),
        lambda: s.drag_joint("rwrist", s.pose.positions[RW] + [0, 0, 0.2]),
        lambda: s.add_key(20),
        lambda: s.move_key(20, 30),
        lambda: s.set_length(45),
        lambda: s.set_fps(24.0),
        lambda: s.set_interpolation("spherical"),
        lambda: s.add_constraint("floor"),
        lambda: s.update_constraint("floor", {"weight": 3.0}),
        lambda: s.move_body(np.array([0.2, 0.1, 0.0])),
        lambda: s.turn_body(45.0),
        lambda: s.clear_target("rwrist"),
        lambda: s.remove_constraint("floor"),
        lambda: s.delete_key(0),
        lambda: s.clear_all(),
    ]
    states = [s.state()]
    for edit in edits:
        edit()
        states.append(s.state())
        assert not same(states[-1], states[-2]), edit
    assert s.history.count() == len(edits) and s.dirty
    for i in range(len(edits), 0, -1):
        s.undo()
        assert same(s.state(), states[i - 1]), i
    assert not s.dirty and not s.history.can_undo()
    for i in range(1, len(edits) + 1):
        s.redo()
        assert same(s.state(), states[i]), i
    assert s.history.undo_text() == "clear all targets"


def test_a_drag_merges_into_one_step_and_a_pause_starts_another(vae):
    s = AuthoringSession(PoseMode(vae, 1.75), clock=Clock(0.05))
    start = s.pose.positions[LW].copy()
    for k in range(1, 6):
        s.drag_joint("lwrist", start + [0.0, -0.02 * k, 0.0])
    assert s.history.count() == 1 and s.history.undo_text() == "move target lwrist"
    s._clock.now += 5.0  # a pause longer than the merge window
    s.drag_joint("lwrist", start + [0.0, -0.2, 0.0])
    s.drag_joint("rwrist", s.pose.positions[RW] + [0.0, 0.0, 0.1])  # another joint: its own step
    assert s.history.count() == 3
    s.undo()
    s.undo()
    assert np.allclose(s.targets["lwrist"].position, start + [0.0, -0.1, 0.0]) and "rwrist" not in s.targets


class SlowSolveClock:
    """Each edit's work takes 2 s (a loaded machine) and the next starts 0.05 s after it ends:
    reads alternate between the start of an edit and its end."""

    def __init__(self) -> None:
        self.now, self.reads = 0.0, 0

    def __call__(self) -> float:
        self.reads += 1
        self.now += 2.0 if self.reads % 2 == 0 else 0.05
        return self.now


def test_a_drag_whose_solves_outlast_the_merge_window_is_still_one_step(vae):
    s = AuthoringSession(PoseMode(vae, 1.75), clock=SlowSolveClock())
    start = s.pose.positions[LW].copy()
    for k in range(1, 5):
        s.drag_joint("lwrist", start + [0.0, -0.02 * k, 0.0])
    assert s.history.count() == 1
    s.undo()
    assert "lwrist" not in s.targets


def test_events_say_what_changed(session):
    s = session
    seen = record(s)
    s.drag_joint("lwrist", s.pose.positions[LW] + [0.0, -0.1, 0.1])
    kinds = [n for n, _ in seen]
    assert kinds == ["history", "targets", "pose"], kinds
    (targets,) = [e for n, e in seen if n == "targets"]
    assert isinstance(targets, ev.TargetsChanged) and targets.joints == ("lwrist",)
    assert [t.joint for t in targets.targets] == ["lwrist"]
    history = seen[0][1]
    assert history == ev.HistoryChanged(True, False, "move target lwrist", "", False, 1)
    seen.clear()
    s.add_key(12)
    assert [(n, e) for n, e in seen if n == "keys"] == [("keys", ev.KeysChanged((12,), added=(12,)))]
    assert "pose" not in [n for n, _ in seen]  # a key changes no pose
    seen.clear()
    s.set_length(30)
    assert [e for n, e in seen if n == "animation"] == [ev.AnimationChanged(30, 30.0, "cubic", (61, 30.0, "cubic"))]
    seen.clear()
    s.add_constraint("floor", name="ground")
    (c,) = [e for n, e in seen if n == "constraints"]
    assert c.action == "added" and c.name == "ground" and c.names == ("ground",)
    seen.clear()
    s.undo()
    (c,) = [e for n, e in seen if n == "constraints"]
    assert c.action == "removed" and c.name == "ground" and c.constraints == ()
    seen.clear()
    s.undo()  # the length
    assert [e.old for n, e in seen if n == "animation"] == [(30, 30.0, "cubic")]
    s.undo()  # the key
    assert [e for n, e in seen if n == "keys"] == [ev.KeysChanged((), removed=(12,))]


def test_a_refused_edit_changes_nothing_and_records_nothing(session):
    s = session
    s.drag_joint("lwrist", s.pose.positions[LW] + [0.0, -0.1, 0.1])
    before, seen = s.state(), record(s)
    with pytest.raises(UserError, match="in-betweens"):
        s.set_interpolation("bouncy")
    with pytest.raises(UserError, match="unknown constraint kind"):
        s.add_constraint("levitate")
    with pytest.raises(UserError, match="length"):
        s.set_length(0)
    with pytest.raises(UserError, match="weight"):
        s.edit_target("lwrist", weight=99.0)
    assert same(s.state(), before) and s.history.count() == 1 and seen == []


def test_going_between_keys_takes_the_baked_in_between_and_its_targets(session):
    s = session
    start = s.pose.positions[LW].copy()
    s.drag_joint("lwrist", start + [0.0, -0.1, 0.1])
    s.add_key(0)
    s.drag_joint("lwrist", start + [0.1, -0.2, 0.5])
    s.add_key(10)
    s.set_length(11)
    seen = record(s)
    steps = s.history.count()
    s.go_to(5)
    assert s.frame == 5 and s.history.count() == steps  # going to a frame is no edit
    baked = s.baked
    assert baked is not None and [n for n, _ in seen][:1] == ["bake"]
    assert np.allclose(s.pose.positions, baked.motion.positions()[5])
    assert ("frame", ev.FrameChanged(5, 0)) in seen
    between = s.targets["lwrist"].position
    assert 0.05 < np.linalg.norm(between - start) < 0.5  # interpolated, neither key's


def test_a_bake_job_reports_progress_cancels_cleanly_and_a_stale_one_is_dropped(session):
    s = session
    s.drag_joint("lwrist", s.pose.positions[LW] + [0.0, -0.1, 0.1])
    s.add_key(0)
    s.add_key(8)
    s.set_length(9)
    before = s.state()
    job = s.bake_job()
    calls: list[tuple[int, int]] = []
    with pytest.raises(Cancelled):
        job.run(lambda done, total: calls.append((done, total)), lambda: len(calls) >= 3)
    assert len(calls) == 3 and s.baked is None and same(s.state(), before)
    calls.clear()
    baked = job.run(lambda done, total: calls.append((done, total)))
    assert calls[-1] == (11, 11) and [d for d, _ in calls] == sorted(d for d, _ in calls)  # 2 keys + 9 frames
    s.set_fps(25.0)  # an edit while the job ran: its result is stale
    assert not s.take_bake(job, baked) and s.baked is None
    fresh = s.bake_job()
    assert s.take_bake(fresh, fresh.run()) and len(s.baked.motion) == 9
    s.edit_target("lwrist", weight=2.0)  # a target edit alone keeps the keys' bake
    assert s.baked is not None
    s.add_key(4)
    assert s.baked is None


def test_a_range_job_reports_progress_and_cancel_leaves_the_clip_untouched(vae, synthetic_motion):
    from engine.authoring.jobs import range_job

    clip = synthetic_motion
    local, root = clip.local_rot.copy(), clip.root_pos.copy()
    with pytest.raises(UserError, match="not within"):
        range_job(clip, [], 100, 200)
    job = range_job(clip, [], 20, 40, blend=2, vae=vae)
    assert [c.kind for c in job.constraints] == ["floor"]
    calls: list[tuple[int, int]] = []
    with pytest.raises(Cancelled):
        job.run(lambda d, t: calls.append((d, t)), lambda: len(calls) >= 4)
    assert calls == [(1, 25), (2, 25), (3, 25), (4, 25)]
    assert np.array_equal(clip.local_rot, local) and np.array_equal(clip.root_pos, root)
    calls.clear()
    edit = job.run(lambda d, t: calls.append((d, t)))
    assert calls[-1] == (25, 25) and (edit.first, edit.last) == (18, 42)
    assert edit.motion is not clip and np.array_equal(clip.local_rot, local)


def test_opening_a_scene_replaces_the_document_and_starts_a_new_history(session, example_scene):
    from engine.authoring.document import load_authoring

    s = session
    s.drag_joint("lwrist", s.pose.positions[LW] + [0.0, -0.1, 0.1])
    seen = record(s)
    s.open_scene(load_authoring(example_scene))
    assert [k.frame for k in s.keys] == [0, 60] and s.frame == 0 and not s.dirty and s.history.count() == 0
    assert [c.name for c in s.mode.constraints] == ["floor"] and s.scene.constraints is s.mode.constraints
    assert list(s.targets) == ["lwrist"] and np.allclose(s.targets["lwrist"].position, [0.25, -0.35, 1.10])
    names = {n for n, _ in seen}
    assert {"keys", "constraints", "targets", "pose", "history"} <= names


def test_new_scene_starts_an_empty_document_in_the_mean_pose(vae, example_scene):
    from engine.authoring.document import load_authoring

    s = AuthoringSession(PoseMode(vae, 1.75), clock=Clock(1.0))
    s.open_scene(load_authoring(example_scene))
    s.select("lwrist")
    s.drag_joint("lwrist", s.pose.positions[LW] + [0.0, -0.1, 0.1])
    mean = PoseMode(vae, 1.6).pose.positions
    seen = record(s)
    s.new_scene(1.6)
    assert s.keys == [] and s.targets == {} and s.mode.constraints == [] and s.scene.constraints is s.mode.constraints
    assert s.frame == 0 and s.selected is None and not s.dirty and s.history.count() == 0
    assert s.mode.character.height == pytest.approx(1.6) and s.scene.height == pytest.approx(1.6)
    np.testing.assert_allclose(s.pose.positions, mean, atol=1e-5)
    assert {"keys", "constraints", "targets", "pose", "history"} <= {n for n, _ in seen}


def test_turn_maths_ring_and_swept_turns():
    from engine.authoring.turns import TURN_GESTURE_S, TURN_START_M, SweptTurn, ring_turn
    from engine.kinematics import quat_np as QN

    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    q = ring_turn(q0, 2, np.radians(30.0))
    assert np.allclose(q, [np.cos(np.radians(15.0)), 0.0, 0.0, np.sin(np.radians(15.0))])
    g = SweptTurn.follow(None, "lwrist", q0, now=0.0)
    assert g.rotation(np.array([TURN_START_M / 2, 0.0, 0.0])) is None  # too close to the joint: noise
    assert g.rotation(np.array([0.1, 0.0, 0.0])) is None  # the first direction far enough
    turned = g.rotation(np.array([0.0, 0.1, 0.0]))
    assert np.allclose(QN.rotate(turned, np.array([1.0, 0.0, 0.0])), [0.0, 1.0, 0.0], atol=1e-6)
    assert SweptTurn.follow(g, "lwrist", q, now=TURN_GESTURE_S / 2) is g
    assert SweptTurn.follow(g, "lwrist", q, now=TURN_GESTURE_S * 3) is not g  # a pause: a new turn
    assert SweptTurn.follow(g, "rwrist", q, now=TURN_GESTURE_S * 3) is not g


def test_a_constraint_limited_to_frames_acts_on_the_pose_only_on_those_frames(session):
    """Posing frame 130 with a pin limited to frames 100-160 holds the wrist there; on
    frame 0 the pin is not in force, as in the bake."""
    s = session
    s.set_length(200)
    wrist = sk.JOINT_INDEX["lwrist"]
    start = s.pose.positions[wrist].copy()
    goal = start + np.array([0.0, -0.25, 0.35])
    s.add_constraint("pin", name="hold", joint="lwrist", position=goal, weight=30.0, frames=(100, 160))
    s.settle()  # frame 0: the pin is not in force, the wrist stays
    off = np.linalg.norm(s.pose.positions[wrist] - start)
    s.go_to(130)
    s.settle()
    on = np.linalg.norm(s.pose.positions[wrist] - goal)
    assert off < 0.03 and on < 0.08, (off, on)
