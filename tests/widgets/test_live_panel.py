"""The live panel and the connect dialog, headless (pytest-qt)."""

from __future__ import annotations

from dataclasses import dataclass

from widgets.live_panel import DEFAULT_MAPPING, LIGHT, ConnectDialog, LivePanel, light_state


@dataclass(frozen=True)
class Status:
    address: str = "127.0.0.1:39539"
    packets: int = 120
    frames: int = 118
    malformed: int = 1
    duplicates: int = 2
    late: int = 0
    packet_rate_hz: float = 60.0
    age_s: float | None = 0.01
    recording: str | None = None
    calibration_phase: str = ""
    calibration_left_s: float = 0.0
    calibration: str = ""


def test_light_follows_the_age_of_the_newest_packet():
    assert light_state(None) == "off"
    assert light_state(Status(age_s=None)) == "silent"
    assert light_state(Status(age_s=0.1)) == "ok"
    assert light_state(Status(age_s=1.0)) == "stale"
    assert light_state(Status(age_s=5.0)) == "silent"


def test_panel_shows_figures_and_asks_through_signals(qtbot):
    panel = LivePanel()
    qtbot.addWidget(panel)
    assert not panel.record.isEnabled() and "not connected" in panel.address.text()
    panel.show_status(Status(), latency_ms=21.4)
    assert LIGHT["ok"] in panel.light.styleSheet()
    assert "60 packets/s" in panel.figures.text() and "latency 21 ms" in panel.figures.text()
    assert "malformed 1, duplicate 2" in panel.figures.text()
    with qtbot.waitSignal(panel.recordRequested) as rec:
        panel.record.click()
    assert rec.args == [True] and panel.record.text() == "Stop"
    with qtbot.waitSignal(panel.calibrateRequested) as cal:
        panel.calibrate.click()
    assert cal.args == [3.0, 2.0]
    panel.show_status(Status(calibration_phase="countdown", calibration_left_s=2.2))
    assert "get into the pose: 2 s" in panel.calibration.text() and not panel.calibrate.isEnabled()
    panel.show_status(Status(calibration_phase="done", calibration="calibrated (tpose, 120 frames): height 1.700 m"))
    assert "height 1.700 m" in panel.calibration.text() and panel.calibrate.isEnabled()
    panel.set_recording(False)
    assert panel.record.text() == "Record"


def test_connect_dialog_values(qtbot):
    dlg = ConnectDialog(port=40000)
    qtbot.addWidget(dlg)
    dlg.host.setText("127.0.0.1")
    assert dlg.values() == {"host": "127.0.0.1", "port": 40000, "mapping": DEFAULT_MAPPING, "convention": "unity"}
    again = ConnectDialog(port=40000, mapping="Head=upperneck", host="127.0.0.1", convention="openxr")
    qtbot.addWidget(again)
    assert again.values() == {"host": "127.0.0.1", "port": 40000, "mapping": "Head=upperneck", "convention": "openxr"}
    # the default mapping is readable whole
    assert dlg.mapping.width() >= dlg.mapping.fontMetrics().horizontalAdvance(DEFAULT_MAPPING)


def test_the_record_button_stays_put_when_recording_starts(qtbot):
    """A line added above the buttons while recording would move Stop from under the pointer."""
    panel = LivePanel()
    qtbot.addWidget(panel)
    panel.resize(360, 300)
    panel.show()
    qtbot.waitExposed(panel)
    panel.show_status(Status())
    qtbot.wait(20)
    before = panel.record.mapTo(panel, panel.record.rect().topLeft())
    panel.show_status(Status(recording="/tmp/trackers.jsonl"))
    qtbot.wait(20)
    assert "recording to /tmp/trackers.jsonl" in panel.figures.text()
    assert panel.record.mapTo(panel, panel.record.rect().topLeft()) == before
