"""Numbers typed into the optimizer panel and the constraint editor while the clip plays:
a refresh from the engine never writes into the field being edited, and the value is
applied once, when it is committed (Tab)."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QCursor
from PyQt6.QtTest import QTest

pytestmark = pytest.mark.gui  # the real window, VTK view included


def _type_while_playing(qtbot, studio, spin, text: str) -> None:
    """Select the field's text, type ``text`` key by key with snapshots arriving between
    the keys, then Tab out."""
    from PyQt6.QtWidgets import QApplication

    studio.activateWindow()
    QApplication.setActiveWindow(studio)  # Xvfb has no window manager to activate it
    spin.setFocus()
    qtbot.waitUntil(spin.hasFocus, timeout=5000)
    # the pointer left over the 3D view, where 1, 3 and 7 are camera keys: the field keeps them
    QCursor.setPos(studio.viewport.mapToGlobal(studio.viewport.rect().center()))
    spin.selectAll()
    seq = studio.session.latest.seq
    for ch in text:
        QTest.keyClick(spin, ch)
        qtbot.waitUntil(lambda s=seq: studio.session.latest.seq > s, timeout=5000)  # a snapshot came in
        seq = studio.session.latest.seq
        qtbot.wait(20)  # and the window drew it
    QTest.keyClick(spin, Qt.Key.Key_Tab)
    qtbot.wait(50)


@pytest.fixture
def playing(studio, qtbot):
    studio.session.set_playing(True)
    yield studio
    studio.session.set_playing(False)


def test_a_temporal_weight_typed_while_playing_is_applied_once_as_typed(playing, qtbot):
    studio = playing
    seen = []
    studio.session.events.settings.connect(lambda e: seen.append(e.changed.get("temporal_weight")))
    spin = studio.optimizer_panel.editors["temporal_weight"]
    assert spin.value() == pytest.approx(0.01)
    _type_while_playing(qtbot, studio, spin, "0.02")
    assert studio.session.settings["temporal_weight"] == pytest.approx(0.02)
    assert spin.value() == pytest.approx(0.02) and not spin.hasFocus()
    assert [v for v in seen if v is not None] == [pytest.approx(0.02)]  # once, when committed


def test_a_distance_typed_while_playing_is_applied_once_as_typed(playing, qtbot):
    studio = playing
    name = studio.session.constraints.add("distance", joint_a="lwrist", joint_b="rwrist", distance=0.5)
    qtbot.waitUntil(
        lambda: studio.constraint_panel.current_name() == name and studio.constraint_panel.editor is not None
    )
    edits = []
    studio.session.events.constraints.connect(lambda e: edits.append(studio.session.constraints.named(name).distance))
    spin = studio.constraint_panel.editor.inputs["distance"]
    _type_while_playing(qtbot, studio, spin, "0.3")
    assert studio.session.constraints.named(name).distance == pytest.approx(0.3)
    assert spin.value() == pytest.approx(0.3)
    assert edits == [pytest.approx(0.3)]  # once, when committed
