"""The pose window's naturalness readout (app/pose_naturalness.py): the benchmark's distance
to the nearest real pose for the pose shown, the spread's verdict once its worker is done,
and a worker that never outlives the window."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring import pose_reference as R
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk

pytestmark = pytest.mark.gui
LW = sk.JOINT_INDEX["lwrist"]


def spread_workers() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "naturalness-spread" and t.is_alive()]


def test_the_readout_measures_the_pose_shown_and_says_when_it_is_within_real_poses(pose_window, qtbot):
    w = pose_window
    readout = w.naturalness
    offsets = w.mode.character.skeleton.offsets
    reference = R.load_shipped(offsets)
    assert readout.distance_cm == pytest.approx(100 * reference.nearest(w.mode.pose.positions), abs=1e-6)
    assert readout.text().startswith(f"Natural: {readout.distance_cm:.1f} cm")
    qtbot.waitUntil(lambda: readout.within is not None, timeout=60000)  # the spread's worker, ~1 s idle
    p95 = reference.spread_summary()["p95_cm"]
    assert readout.spread[1] == pytest.approx(p95)
    assert readout.within and readout.text().endswith("within real poses")  # the standing start pose
    assert "validation files" in readout.toolTip() and f"{p95:.1f} cm" in readout.toolTip()
    assert f"the nearest is from {R.take_label(readout.take)}." in readout.toolTip() and "/" in R.take_label(
        readout.take
    )

    before = readout.distance_cm
    start = w.mode.pose.positions[LW].copy()
    w.drag_joint("lwrist", start + [0.0, 0.0, 0.5])  # the hand raised: another pose, another distance
    assert readout.distance_cm != pytest.approx(before)
    assert readout.distance_cm == pytest.approx(100 * reference.nearest(w.mode.pose.positions), abs=1e-6)

    rng = np.random.default_rng(3)  # every joint turned at random: no real pose is near it
    aa = rng.normal(0.0, 1.2, (sk.NUM_JOINTS, 3))
    angle = np.linalg.norm(aa, axis=-1)
    contorted = fk(QN.from_axis_angle(aa / angle[:, None], angle), np.zeros(3), offsets)[0]
    w.show_positions(contorted)
    assert readout.within is False and readout.text().endswith("beyond real poses")
    assert readout.distance_cm > p95


def test_closing_the_window_stops_the_spread_worker(vae, qtbot):
    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession
    from tests.app.gui_helpers import close_now

    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.6)))
    w.show()
    assert w.naturalness.worker is not None  # started for this skeleton on the first pose shown
    close_now(w)
    assert not spread_workers() and w.naturalness.worker is None


def _takes(tmp_path, offsets) -> list:
    """Two short BVH takes on the pose window's skeleton: one standing still, one with an
    arm raised (synthetic, so the test needs no shared data)."""
    from engine.motion.bvh import save_motion_bvh
    from engine.motion.clip import Motion

    skeleton = sk.Skeleton(offsets.copy())
    files = []
    for name, lift in (("still", 0.0), ("arm_up", 2.5)):
        rot = np.tile([1.0, 0.0, 0.0, 0.0], (8, sk.NUM_JOINTS, 1))
        rot[:, sk.JOINT_INDEX["lshoulder"]] = QN.from_axis_angle(np.array([0.0, 1.0, 0.0]), lift)
        path = tmp_path / f"{name}.bvh"
        save_motion_bvh(path, Motion(rot, np.tile([0.0, 0.0, 1.0], (8, 1)), skeleton, 30.0, name))
        files.append(path)
    return files


def test_motion_files_chosen_in_the_view_menu_become_the_real_poses(pose_window, qtbot, monkeypatch, tmp_path):
    from PyQt6.QtWidgets import QFileDialog

    w = pose_window
    readout, acts = w.naturalness, w.actions_by_name
    offsets = w.mode.character.skeleton.offsets
    files = _takes(tmp_path, offsets)
    assert acts["reference_shipped"].isChecked() and not acts["reference_files"].isChecked()
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([str(f) for f in files], ""))
    acts["reference_files"].trigger()
    qtbot.waitUntil(lambda: readout.within is not None, timeout=30000)
    want = R.load_files(files, offsets, kind="files")
    assert readout.distance_cm == pytest.approx(100 * want.nearest(w.mode.pose.positions), abs=1e-6)
    assert readout.take in [str(f) for f in files] and "2 files" in readout.toolTip()
    assert readout.spread[1] == pytest.approx(want.spread_summary()["p95_cm"])
    assert acts["reference_files"].isChecked() and "2 in use" in acts["reference_files"].text()
    # a drag is measured against the files too
    w.drag_joint("lwrist", w.mode.pose.positions[LW] + [0.0, 0.0, 0.4])
    assert readout.distance_cm == pytest.approx(100 * want.nearest(w.mode.pose.positions), abs=1e-6)
    acts["reference_shipped"].trigger()  # back to the shipped poses, at once
    shipped = R.load_shipped(offsets)
    assert readout.files is None and "validation files" in readout.toolTip()
    assert readout.distance_cm == pytest.approx(100 * shipped.nearest(w.mode.pose.positions), abs=1e-6)


def test_a_single_file_or_an_unreadable_one_leaves_the_shipped_poses_and_says_why(
    pose_window, qtbot, monkeypatch, tmp_path
):
    from PyQt6.QtWidgets import QFileDialog, QMessageBox

    w = pose_window
    readout, acts = w.naturalness, w.actions_by_name
    files = _takes(tmp_path, w.mode.character.skeleton.offsets)
    warnings = []
    monkeypatch.setattr(QMessageBox, "warning", lambda _parent, _title, text, *a: warnings.append(text))
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([str(files[0])], ""))
    acts["reference_files"].trigger()
    assert "at least two motion files" in warnings[-1]
    assert acts["reference_shipped"].isChecked() and readout.files is None
    broken = tmp_path / "broken.bvh"
    broken.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n")
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([str(files[0]), str(broken)], ""))
    acts["reference_files"].trigger()
    qtbot.waitUntil(lambda: len(warnings) == 2, timeout=30000)
    assert str(broken) in warnings[-1] and "shipped validation poses" in warnings[-1]
    assert acts["reference_shipped"].isChecked() and readout.files is None
    qtbot.waitUntil(lambda: readout.within is not None, timeout=60000)
    assert "validation files" in readout.toolTip()
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([], ""))  # a cancelled dialog
    acts["reference_files"].trigger()
    assert acts["reference_shipped"].isChecked() and len(warnings) == 2
    # with files in use, an unreadable choice goes back to them, not to the shipped poses
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([str(f) for f in files], ""))
    acts["reference_files"].trigger()
    qtbot.waitUntil(lambda: readout.within is not None and "2 files" in readout.toolTip(), timeout=30000)
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: ([str(files[0]), str(broken)], ""))
    acts["reference_files"].trigger()
    qtbot.waitUntil(lambda: len(warnings) == 3, timeout=30000)
    assert "the 2 files chosen before" in warnings[-1] and acts["reference_files"].isChecked()
    assert readout.files == files
    qtbot.waitUntil(lambda: readout.within is not None and "2 files" in readout.toolTip(), timeout=30000)
