"""F1 in the pose window lists the pose window's mouse, not the studio's: a left drag on
the body makes a target there, Ctrl + drag pins nothing and the yellow spheres are
targets, not sensors. The rows come from the dialog the Help menu's F1 entry opens."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def _f1_rows(window) -> dict[str, str]:
    """Help > Keyboard and mouse (F1), triggered from the window's own menu."""
    (help_menu,) = [a.menu() for a in window.menuBar().actions() if a.text() == "&Help"]
    (entry,) = [a for a in help_menu.actions() if a.text().startswith("&Keyboard and mouse")]
    assert entry.shortcut().toString() == "F1"
    entry.trigger()
    dialog = window.help_dialog
    try:
        assert dialog.isVisible()
        return dict(dialog.rows())
    finally:
        dialog.close()


def test_f1_in_the_pose_window_says_what_its_mouse_does(pose_window):
    rows = _f1_rows(pose_window)
    assert "target" in rows["Drag a joint"]
    assert "squat" in rows["Drag the hips"]
    assert "pelvis" in rows["Shift + drag the hips"]
    assert "rotation rings" in rows["Click a joint"]
    assert "Turn" in rows["Drag a ring"]
    text = " ".join(rows.values()).lower()
    assert "sensor" not in text and "pin the joint" not in text
    assert "Drop a .bvh file" not in rows
    assert rows["Left drag off the body"] == "Rotate the camera"


def test_f1_in_the_studio_keeps_the_studio_s_mouse(studio):
    rows = _f1_rows(studio)
    assert rows["Ctrl + drag a joint"].startswith("Pin the joint")
    assert "sensor" in rows["Drag a yellow sphere"]
    assert not any("hips" in keys for keys in rows), "the hips gestures are the pose window's"
