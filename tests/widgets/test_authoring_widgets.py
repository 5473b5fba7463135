"""The target list and the key strip: edits become signals, state is shown without echo."""

from __future__ import annotations

from PyQt6.QtCore import Qt

from widgets.key_strip import KeyStrip
from widgets.target_list import TargetList


def test_target_list_rows_emit_their_edits_and_set_targets_is_silent(qtbot):
    t = TargetList()
    qtbot.addWidget(t)
    seen = []
    for sig in (t.enabledChanged, t.weightChanged, t.turnHeld, t.clearRequested):
        sig.connect(lambda *a: seen.append(a))
    t.clearAllRequested.connect(lambda: seen.append(("all",)))
    t.set_targets({"lwrist": (True, 1.0, False), "upperneck": (False, 4.0, True)})
    assert seen == [] and list(t.rows) == ["lwrist", "upperneck"]
    assert (
        t.rows["upperneck"]["label"].text() == "upperneck (+rotation)" and t.rows["upperneck"]["weight"].value() == 4.0
    )
    t.rows["lwrist"]["enabled"].setChecked(False)
    t.rows["lwrist"]["weight"].setValue(7.5)
    assert t.rows["upperneck"]["turn"].isChecked()
    t.rows["lwrist"]["turn"].setChecked(True)
    t.rows["upperneck"]["clear"].click()
    t.clear_all.click()
    assert seen == [("lwrist", False), ("lwrist", 7.5), ("lwrist", True), ("upperneck",), ("all",)]
    t.rows["lwrist"]["weight"].setValue(50.0)
    assert t.rows["lwrist"]["weight"].value() == 10.0  # the engine's range
    t.set_targets({})
    assert t.rows == {} and not t.clear_all.isEnabled()


def test_key_strip_add_move_delete_length_rate_preview(qtbot):
    k = KeyStrip()
    qtbot.addWidget(k)
    k.resize(600, 80)
    k.show()
    seen = []
    for sig in (
        k.frameChanged,
        k.addRequested,
        k.deleteRequested,
        k.moveRequested,
        k.lengthChanged,
        k.fpsChanged,
        k.interpolationChanged,
    ):
        sig.connect(lambda *a, s=sig: seen.append(a))
    k.previewRequested.connect(lambda: seen.append("preview"))
    k.set_state(61, 30.0, (0, 60), 0)
    assert seen == [] and k.delete.isEnabled() and "2 keys" in k.label.text()
    qtbot.mouseClick(k.strip, Qt.MouseButton.LeftButton, pos=k.strip.rect().center())
    assert seen[-1] == (30,) and not k.delete.isEnabled()  # frame 30 holds no key
    k.add.click()
    k.set_state(61, 30.0, (0, 30, 60), 30)
    k.move_to.setValue(40)
    k.move.click()
    k.delete.click()
    k.length.setValue(90)
    k.fps.setValue(24.0)
    k.interpolation.setCurrentText("linear")
    k.preview.click()
    assert seen[1:] == [(30,), (30, 40), (30,), (90,), (24.0,), ("linear",), "preview"]
    k.set_state(90, 24.0, (), 0, "spherical")
    assert k.interpolation.currentText() == "spherical" and seen[-1] == "preview"
    assert k.strip.frame_at(k.strip.x_of(45)) == 45


def test_the_strip_offers_exactly_the_engine_in_between_rules():
    from engine.authoring.keys import SCHEMES
    from widgets.key_strip import SCHEMES as OFFERED

    assert sorted(OFFERED) == sorted(SCHEMES)


def _mouse(widget, kind, x, buttons):
    from PyQt6.QtCore import QPointF
    from PyQt6.QtGui import QMouseEvent
    from PyQt6.QtWidgets import QApplication

    left = Qt.MouseButton.LeftButton
    button = left if kind != QMouseEvent.Type.MouseMove else Qt.MouseButton.NoButton
    y = widget.height() / 2
    event = QMouseEvent(
        kind, QPointF(x, y), widget.mapToGlobal(QPointF(x, y)), button, buttons, Qt.KeyboardModifier.NoModifier
    )
    QApplication.sendEvent(widget, event)


def drag_on(widget, x0: float, x1: float, steps: int = 5) -> None:
    """A left-button drag along ``widget`` from pixel ``x0`` to ``x1``."""
    from PyQt6.QtGui import QMouseEvent

    left, none = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    _mouse(widget, QMouseEvent.Type.MouseButtonPress, x0, left)
    for k in range(1, steps + 1):
        _mouse(widget, QMouseEvent.Type.MouseMove, x0 + (x1 - x0) * k / steps, left)
    _mouse(widget, QMouseEvent.Type.MouseButtonRelease, x1, none)


def test_the_key_timeline_scrubs_drags_keys_and_shows_the_last_frame(qtbot):
    k = KeyStrip()
    qtbot.addWidget(k)
    k.resize(700, 90)
    k.show()
    k.set_state(61, 30.0, (0, 20, 60), 5)
    scrubbed, moved = [], []
    k.frameChanged.connect(scrubbed.append)
    k.moveRequested.connect(lambda a, b: moved.append((a, b)))
    s = k.strip
    drag_on(s, s.x_of(8), s.x_of(14), steps=6)  # off the keys: scrubs through every frame on the way
    assert scrubbed == [8, 9, 10, 11, 12, 13, 14] and moved == []
    drag_on(s, s.x_of(20) + 2, s.x_of(33))  # a key's mark: dragged to frame 33
    assert moved == [(20, 33)] and scrubbed[-1] == 14
    drag_on(s, s.x_of(60), s.x_of(60), steps=1)  # a key pressed without moving: its frame
    assert scrubbed[-1] == 60 and moved == [(20, 33)]
    assert 0 < s.x_of(60) < s.width() - 4 and s.frame_at(s.x_of(60)) == 60  # the last frame's line is inside
    assert s.ruler_step() in (2, 5) and k.label.text().endswith("(key)")
    img = s.grab().toImage()
    x = int(round(s.x_of(60)))
    assert any(img.pixelColor(x + dx, img.height() - 3).name() == "#ff8a1f" for dx in (-1, 0, 1))
    k.set_state(61, 30.0, (0, 20, 60), 10)
    assert k.label.text().endswith("(in-between)")
    k.set_playing(True)
    assert k.preview.text() == "Stop"


def test_a_click_on_the_timeline_groove_jumps_to_the_click(qtbot):
    """QSlider paged by 10 frames towards a click on its groove."""
    from widgets.range_slider import RangeSlider

    s = RangeSlider()
    qtbot.addWidget(s)
    s.resize(400, 24)
    s.setRange(0, 200)
    s.show()
    qtbot.mouseClick(s, Qt.MouseButton.LeftButton, pos=s.point_of(150))
    assert abs(s.value() - 150) <= 1
    qtbot.mouseClick(s, Qt.MouseButton.LeftButton, pos=s.point_of(20))
    assert abs(s.value() - 20) <= 1
