"""Small things a new user meets: save dialogs suggest a name, plot axes with one
frame, a point per drawn frame in the method errors."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PyQt6.QtWidgets import QFileDialog

pytestmark = pytest.mark.gui


def test_save_dialogs_suggest_a_name_beside_the_clip(studio, monkeypatch, tmp_path, synthetic_motion):
    from engine.motion.bvh import save_motion_bvh

    clip = tmp_path / "walk.bvh"
    save_motion_bvh(clip, synthetic_motion.slice(0, 30))
    assert studio.files.open_path(str(clip))
    offered = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (offered.append(a[2]), ("", ""))[1])
    studio.files.save_scene()
    studio.files.export_screenshot()
    assert offered == [str(tmp_path / "walk_scene.json"), str(tmp_path / "walk_studio.png")]


def test_frame_axes_with_one_solved_frame_span_a_few_frames(studio, qtbot):
    s = studio.session
    s.seek(30)
    qtbot.waitUntil(lambda: s.latest.frame == 30, timeout=5000)
    s.seek(10)  # back: the histories start again, with one frame
    qtbot.waitUntil(lambda: s.latest.frame == 10 and len(s.latest.history) == 1, timeout=5000)
    studio.plots.update_cost(s.latest)
    studio.plots.update_history(s.latest)
    studio.method_errors.update_snapshot(s.latest)
    for plot in (studio.plots.cost_plot, studio.plots.history_plot, studio.method_errors.plot):
        lo, hi = plot.getPlotItem().getViewBox().viewRange()[0]
        assert lo <= 10 <= hi and hi - lo <= 6, (lo, hi)


def test_frame_axes_span_a_few_frames_when_the_frame_before_a_seek_back_was_not_drawn(studio, qtbot):
    """The window draws only the newest snapshot: frame 30 is published and superseded
    by frame 10 without the event loop running in between, so the window never sees 30."""
    s = studio.session
    published = {30: threading.Event(), 10: threading.Event()}
    # called on the engine thread, so waiting for it runs no Qt event and draws nothing
    studio.engine.listeners.append(lambda snap: snap.frame in published and published[snap.frame].set())
    s.seek(30)
    assert published[30].wait(10), "the engine never solved frame 30"
    s.seek(10)
    assert published[10].wait(10), "the engine never solved frame 10"
    with qtbot.waitSignal(studio.snapshotDrawn, timeout=10000, check_params_cb=lambda f: f == 10):
        pass
    assert s.latest.frame == 10 and len(s.latest.history) == 1
    studio.method_errors.update_snapshot(s.latest)
    assert sorted(studio.method_errors.data[s.latest.method]) == [10]
    lo, hi = studio.method_errors.plot.getPlotItem().getViewBox().viewRange()[0]
    assert lo <= 10 <= hi and hi - lo <= 6, (lo, hi)


def test_method_errors_get_a_point_per_drawn_frame(studio, qtbot):
    s = studio.session
    s.set_playback(loop=False)  # a loop starts the curves again
    s.seek(0)
    qtbot.waitUntil(lambda: s.latest.frame == 0, timeout=5000)
    drawn = []
    studio.snapshotDrawn.connect(drawn.append)
    s.set_playing(True)
    qtbot.waitUntil(lambda: len(drawn) >= 40 or not s.latest.playing, timeout=20000)
    s.pause()
    series = studio.method_errors.data[s.latest.method]
    seen = [f for f in set(drawn) if f in series]
    assert len(seen) >= 0.9 * len(set(drawn)), (len(seen), len(set(drawn)))
    assert np.all(np.isfinite(list(series.values())))


def test_the_loading_notice_fits_in_the_view(studio, qtbot):
    studio.resize(1600, 1000)
    qtbot.wait(200)
    studio.busy.begin("dragposer", 10**9, "Opening the clip with")
    img = studio.viewport.grab_image()
    w, h = img.width(), img.height()
    arr = np.frombuffer(img.constBits().asstring(img.sizeInBytes()), np.uint8).reshape(h, img.bytesPerLine())
    arr = arr[:, : 3 * w].reshape(h, w, 3).astype(int)
    yellow = (arr[..., 0] > 200) & (arr[..., 1] > 180) & (arr[..., 2] < 140)
    cols = np.flatnonzero(yellow[h - 80 :].any(axis=0))
    assert cols.size, "no notice drawn"
    assert cols.min() > 4 and cols.max() < w - 5, (cols.min(), cols.max(), w)


def test_the_three_plots_are_tall_and_side_by_side_at_1600_by_1000(studio, qtbot):
    studio.resize(1600, 1000)
    qtbot.wait(300)
    p = studio.plots
    boxes = [w.geometry() for w in (p.iteration_plot, p.cost_plot, p.history_plot)]
    assert min(b.height() for b in boxes) >= 180, [b.height() for b in boxes]
    for a, b in zip(boxes, boxes[1:]):
        assert not a.intersects(b)
    for plot in (p.iteration_plot, p.cost_plot, p.history_plot):  # no plot is wider than its widget
        assert plot.getPlotItem().geometry().width() <= plot.viewport().width() + 1


def test_follow_is_a_button_beside_the_play_controls(studio):
    button = studio.follow_button
    assert button.isVisible() and "Follow" in button.text()
    button.click()
    assert not studio.viewport.follow and not studio.actions_by_name["follow"].isChecked()


def test_the_studio_starts_playing(studio, qtbot):
    from app.main import start_playing

    studio.session.pause()
    start_playing(studio)
    qtbot.waitUntil(lambda: studio.session.latest.playing and studio.timeline.play_button.isChecked(), timeout=5000)


def test_a_new_clip_shows_at_once_while_the_method_loads(studio, qtbot, tmp_path, synthetic_motion):
    import dataclasses
    import time

    from engine.motion.bvh import save_motion_bvh
    from tests.stand_ins import RestPoseMethod

    class SlowToLoad(RestPoseMethod):
        name = "slow"

        def reset(self, *args, **kwargs) -> None:
            time.sleep(1.5)  # as if a first frame were solved offline
            super().reset(*args, **kwargs)

    inner = studio.engine._factory
    studio.engine._factory = lambda name: SlowToLoad() if name == "slow" else inner(name)
    studio.session.set_method("slow")
    qtbot.waitUntil(lambda: studio.session.latest.method == "slow", timeout=10000)
    studio.undo.set_clean()  # the switch is a scene edit (a scene stores its method): saved, no prompt
    far = dataclasses.replace(synthetic_motion, root_pos=synthetic_motion.root_pos + [6.0, 0.0, 0.0])
    clip = tmp_path / "far.bvh"
    save_motion_bvh(clip, far.slice(0, 30))
    seq = studio.session.latest.seq
    assert studio.files.open_path(str(clip))
    assert studio.session.latest.seq == seq, "drawn before the engine solved the new clip"
    first = studio.session.motion.slice(0, 1).positions()[0]
    assert np.allclose(studio.viewport.ground_truth.mesh.points[: len(first)], first, atol=1e-6)


def test_save_dialogs_avoid_read_only_folders_and_the_studio_assets(studio, monkeypatch, tmp_path, synthetic_motion):
    """Export video opened in a read-only data folder with no name; Save scene offered a
    file inside the studio's own assets/."""
    from pathlib import Path

    from app.authoring_actions import export_video
    from app.main import EXAMPLE_CLIP
    from engine.motion.bvh import save_motion_bvh

    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setattr(Path, "home", staticmethod(lambda: home))
    offered = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (offered.append(a[2]), ("", ""))[1])
    shared = tmp_path / "shared"
    shared.mkdir()
    save_motion_bvh(shared / "run.bvh", synthetic_motion.slice(0, 30))
    import app.save_folder as sf

    # the tests run as root, who may write anywhere: the folder reads as read-only to the studio
    monkeypatch.setattr(sf.os, "access", lambda p, mode: Path(p) != shared)
    assert studio.files.open_path(str(shared / "run.bvh"))
    from PyQt6.QtWidgets import QDialog

    from app.export_video_dialog import ExportVideoDialog

    monkeypatch.setattr(ExportVideoDialog, "exec", lambda self: QDialog.DialogCode.Accepted)
    export_video(studio)
    studio.files.save_scene()
    assert studio.files.open_path(str(EXAMPLE_CLIP))
    studio.files.save_scene()
    assert offered == [str(home / "run_video.mp4"), str(home / "run_scene.json"), str(home / "example_scene.json")]


def test_the_new_pose_dialog_starts_at_the_canonical_height_in_plain_words(studio):
    from app.new_pose_dialog import NewPoseDialog
    from engine import skeleton as sk

    dialog = NewPoseDialog(studio, has_clip=True)
    assert dialog.height_m.value() == pytest.approx(sk.Skeleton.canonical().height(), abs=0.005)
    offered = [dialog.start.itemText(i) for i in range(dialog.start.count())]
    assert offered == ["a neutral standing pose", "the clip's current frame"]
    dialog.deleteLater()
