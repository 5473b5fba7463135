"""widgets/field_editing.py in both panels: a refresh does not overwrite the field being
typed into, and the typed number is emitted once, on commit."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest


def _focus(qtbot, holder, spin):
    holder.show()
    holder.activateWindow()
    spin.setFocus()
    qtbot.waitUntil(spin.hasFocus, timeout=5000)
    if hasattr(spin, "selectAll"):
        spin.selectAll()


def test_the_optimizer_panel_keeps_a_half_typed_number_through_refreshes(qtbot):
    from widgets.optimizer_panel import OptimizerPanel, SettingField

    field = SettingField("temporal_weight", "Temporal prior weight", "float", 0.01, lo=0, hi=1e6, step=0.1)
    p = OptimizerPanel(["ik"], (field,))
    qtbot.addWidget(p)
    p.set_state("ik", (), {"temporal_weight": 0.01})
    seen = []
    p.settingChanged.connect(lambda n, v: seen.append((n, v)))
    spin = p.editors["temporal_weight"]
    _focus(qtbot, p, spin)
    for ch in "0.02":
        QTest.keyClick(spin, ch)
        p.set_state("ik", (), {"temporal_weight": 0.01})  # the engine's refresh, mid-typing
    assert spin.text() == "0.02" and seen == []
    QTest.keyClick(spin, Qt.Key.Key_Tab)
    assert seen == [("temporal_weight", pytest.approx(0.02))]
    p.set_state("ik", (), {"temporal_weight": 0.5})  # not being edited any more: shown
    assert spin.value() == pytest.approx(0.5)


def test_the_constraint_editor_keeps_a_half_typed_distance_through_refreshes(qtbot):
    from widgets.constraint_panel import ConstraintEditor

    fields = [("joint_a", "joint", "lwrist"), ("joint_b", "joint", "rwrist"), ("distance", "float", 0.5)]
    e = ConstraintEditor(fields, {"weight": 1.0, "distance": 0.5})
    qtbot.addWidget(e)
    seen = []
    e.changed.connect(seen.append)
    spin = e.inputs["distance"]
    _focus(qtbot, e, spin)
    for ch in "0.3":
        QTest.keyClick(spin, ch)
        e.set_values({"distance": 0.5, "weight": 2.0})
    assert spin.text() == "0.3" and seen == []
    assert e.inputs["weight"].value() == pytest.approx(2.0)  # the other fields still follow
    QTest.keyClick(spin, Qt.Key.Key_Return)
    assert seen == [{"distance": pytest.approx(0.3)}]


def test_a_check_box_with_the_focus_still_shows_an_undo(qtbot):
    """Clicking a check box leaves the focus on it; its click was sent at once, so the next
    refresh (an undo, a loaded scene) must show there, not be kept out as a half-typed
    number is."""
    from widgets.optimizer_panel import OptimizerPanel, SettingField

    field = SettingField("heading_network", "Heading network", "bool", True)
    p = OptimizerPanel(["ik"], (field,))
    qtbot.addWidget(p)
    p.set_state("ik", (), {"heading_network": True})
    box = p.editors["heading_network"]
    seen = []
    p.settingChanged.connect(lambda n, v: seen.append((n, v)))
    _focus(qtbot, p, box)
    QTest.keyClick(box, Qt.Key.Key_Space)  # as a user toggles the focused box
    assert seen == [("heading_network", False)] and box.hasFocus()
    p.set_state("ik", (), {"heading_network": True})  # the session after Undo
    assert box.isChecked() and seen == [("heading_network", False)]
