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
    assert t.rows["upperneck"]["label"].text() == "upperneck (+rotation)" and t.rows["upperneck"]["weight"].value() == 4.0
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
    for sig in (k.frameChanged, k.addRequested, k.deleteRequested, k.moveRequested, k.lengthChanged, k.fpsChanged,
                k.interpolationChanged):  # fmt: skip
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
