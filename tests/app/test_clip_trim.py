"""Edit ▸ Trim clip to selection in the studio: the entry's states, the trim as one undo
step with the scene's frame ranges, and the trimmed clip saved."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def test_the_entry_names_the_selected_frames_and_is_off_without_a_part_of_a_clip(
    studio, qtbot, synthetic_motion, tmp_path
):
    from engine.tracker_io.recording import write_recording
    from engine.tracker_io.sender import plan_stream
    from engine.tracker_io.trackers import TrackerSample

    act = studio.actions_by_name["trim_clip"]
    assert act in studio.menuBar().actions()[1].menu().actions()  # in the Edit menu
    assert not act.isEnabled() and "Shift-drag" in act.toolTip()  # nothing selected
    studio.timeline.set_selection(0, len(studio.session.motion) - 1)
    assert not act.isEnabled() and "whole clip" in act.toolTip()
    studio.timeline.set_selection(89, 110)
    assert act.isEnabled() and act.text().replace("&", "") == "Trim clip to frames 89-110"
    studio.timeline.set_selection(None)
    assert not act.isEnabled()
    # a tracker recording has no clip to cut, even with frames selected
    plan = plan_stream(synthetic_motion.slice(0, 40), "6")
    samples = [TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan)) for n, p, r in plan.frame(i)]
    write_recording(tmp_path / "rec.jsonl", samples, 60.0)
    assert studio.live.open_recording(tmp_path / "rec.jsonl")
    studio.timeline.set_selection(5, 20)
    assert not act.isEnabled() and "Tracker input" in act.toolTip()
    act.trigger()  # a shortcut or a stale menu: nothing happens but a note
    assert studio.session.motion is None and studio.undo.history.count() == 0
    qtbot.waitUntil(lambda: studio.session.latest is not None, timeout=10000)


def test_trimming_keeps_the_frames_moves_the_scene_and_undo_gives_the_whole_clip_back(studio, qtbot, monkeypatch):
    from engine.constraints import PinConstraint

    session = studio.session
    original = session.motion
    rot, root = original.local_rot.copy(), original.root_pos.copy()
    session.set_constraints(
        [
            PinConstraint(name="inside", joint="lwrist", frames=(40, 50), blend_in=3),
            PinConstraint(name="partly", joint="rwrist", frames=(20, 35)),
            PinConstraint(name="after", joint="lankle", frames=(80, 90)),
        ]
    )
    session.simulate_failure("lwrist", 10, start=55)
    scene = tuple(session.constraints), tuple(session.sensors.values())
    studio.undo.set_clean()
    steps = studio.undo.history.count()
    session.seek(45)
    studio.timeline.set_selection(30, 59)
    studio.actions_by_name["trim_clip"].trigger()

    m = session.motion
    assert len(m) == 30 and m.start == 30
    assert np.array_equal(m.local_rot, rot[30:60]) and np.array_equal(m.root_pos, root[30:60])
    assert session.frame == 15 and studio.timeline.slider.value() == 15  # the same frame on screen
    assert studio.timeline.slider.maximum() == 29 and studio.timeline.selection() is None
    got = {c.name: c for c in session.constraints}
    assert got["inside"].frames == (10, 20) and got["partly"].frames == (0, 5)
    assert got["after"].frames == (29, 29) and not got["after"].enabled  # wholly cut: off, and said
    assert "after" in studio.statusBar().currentMessage()
    assert session.sensors["lwrist"].failures == ((25, 30),)
    assert studio.undo.history.count() == steps + 1 and not studio.undo.is_clean()  # one step
    assert "trim" in studio.actions_by_name["undo"].text().lower()
    qtbot.waitUntil(lambda: (s := session.latest) is not None and s.num_frames == 30, timeout=20000)
    # the engine shows the trimmed clip: its ground truth at frame 15 is the old frame 45
    qtbot.waitUntil(lambda: session.latest.frame == 15, timeout=20000)
    assert np.allclose(session.latest.ground_truth, original.positions()[45], atol=1e-6)

    from PyQt6.QtWidgets import QMessageBox

    from app.clip_saving import clip_edited, confirm_discard

    asked = []
    monkeypatch.setattr(
        QMessageBox, "question", lambda *a, **k: asked.append(a[2]) or QMessageBox.StandardButton.Cancel
    )
    assert clip_edited(studio) and not confirm_discard(studio, "quitting")
    assert "the trimmed clip" in asked[-1]  # the prompt knows the clip was edited

    studio.undo.history.undo()
    assert session.motion is original and np.array_equal(session.motion.local_rot, rot)
    assert session.frame == 45 and studio.timeline.selection() == (30, 59)
    assert (tuple(session.constraints), tuple(session.sensors.values())) == scene
    assert studio.undo.is_clean() and not clip_edited(studio)
    studio.undo.history.redo()
    assert session.motion is m and session.frame == 15 and session.constraints.named("after").enabled is False
    qtbot.waitUntil(lambda: (s := session.latest) is not None and s.num_frames == 30, timeout=20000)


def test_the_trimmed_clip_is_saved_with_its_frames_canonical_and_on_the_source_rig(studio, qtbot, tmp_path):
    from app.clip_saving import save_clip
    from app.clip_trim import trim_to
    from engine.motion.bvh import load_bvh
    from engine.studio.clips import load_clip
    from tests.engine.rig_fixtures import write_family_bvh

    src = write_family_bvh(tmp_path / "mixamo.bvh", "mixamo", frames=120)
    assert studio.files.open_path(src)
    trim_to(studio, 40, 71)
    canon = tmp_path / "trimmed.bvh"
    save_clip(studio, canon)
    assert load_bvh(canon).frames == 32
    on_rig = tmp_path / "trimmed_rig.bvh"
    note = save_clip(studio, on_rig, on_source_rig=True)
    raw, back = load_bvh(src), load_bvh(on_rig)
    assert back.frames == 32 and back.names == raw.names
    # the source's frames 40-71, not its first 32
    whole = load_clip(src).positions()
    assert np.allclose(load_clip(on_rig).positions(), whole[40:72], atol=1e-3)
    assert "frame i + 40" in note
    qtbot.waitUntil(lambda: studio.session.latest is not None, timeout=10000)


def test_a_closed_studio_leaves_no_trim_entry_subscribed_to_its_session(studio):
    """The entry follows the session's clip and source events while the window is open,
    and the window's close drops them, as its other views do."""
    session, entry = studio.session, studio.trim_entry

    def subscribed() -> bool:
        return any(
            getattr(cb, "__self__", None) is entry or getattr(getattr(cb, "__func__", None), "__self__", None) is entry
            for signal in (session.events.motion, session.events.source)
            for cb in _callbacks(signal)
        )

    assert subscribed()
    studio.undo.set_clean()
    studio.close()
    assert not subscribed()


def _callbacks(signal):
    """The callables a psygnal signal instance would call now."""
    return [slot.dereference() for slot in signal._slots]
