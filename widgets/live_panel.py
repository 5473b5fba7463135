"""Live tracker source: the connect dialog, and a panel with a status light, packet
rate and latency, Record / Stop and a Calibrate button with a countdown.

Qt only: the panel reads a status object duck-typed (the fields of
``engine.tracker_io.live_source.LiveStatus``) and says what the user asked through signals.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

#: The sender's tracker names -> joints (``engine.tracker_io.trackers.DEFAULT_SLOTS``).
DEFAULT_MAPPING = "head=upperneck, left_hand=lwrist, right_hand=rwrist, hips=root, left_foot=lankle, right_foot=rankle"
#: What Connect offers first: every interface, the VMC port (``engine.tracker_io.receiver.DEFAULT_PORT``)
#: and the axes VMC senders use.
DEFAULT_HOST, DEFAULT_PORT, DEFAULT_CONVENTION = "0.0.0.0", 39539, "unity"

#: Status-light colours: receiving, stale (nothing for a moment), silent, not connected.
LIGHT = {"ok": "#4cd964", "stale": "#ffd60a", "silent": "#ff3b30", "off": "#5a6070"}


class ConnectDialog(QDialog):
    """Asks for the address to listen on, the tracker mapping and the axes convention."""

    def __init__(
        self,
        parent: QWidget | None = None,
        port: int = DEFAULT_PORT,
        mapping: str = DEFAULT_MAPPING,
        host: str = DEFAULT_HOST,
        convention: str = DEFAULT_CONVENTION,
    ) -> None:
        super().__init__(parent)
        self.setWindowTitle("Connect live source (VMC over UDP)")
        form = QFormLayout(self)
        self.host = QLineEdit(host)
        self.host.setToolTip("0.0.0.0 listens on every network interface; 127.0.0.1 on this machine only")
        self.port = QSpinBox(minimum=1, maximum=65535, value=port)
        self.mapping = QLineEdit(mapping)
        self.mapping.setToolTip("tracker name = joint, comma separated; :3 after the joint = position only")
        # the whole default mapping readable without scrolling the field
        self.mapping.setMinimumWidth(self.mapping.fontMetrics().horizontalAdvance(DEFAULT_MAPPING) + 24)
        self.convention = QComboBox()
        self.convention.addItems(["unity", "openxr", "project"])
        self.convention.setCurrentText(convention)
        self.convention.setToolTip("axes of the incoming poses; VMC senders use unity (see docs/trackers.md)")
        form.addRow("Listen on", self.host)
        form.addRow("Port", self.port)
        form.addRow("Tracker mapping", self.mapping)
        form.addRow("Axes", self.convention)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def values(self) -> dict[str, Any]:
        return {
            "host": self.host.text().strip() or DEFAULT_HOST,
            "port": self.port.value(),
            "mapping": self.mapping.text(),
            "convention": self.convention.currentText(),
        }


def light_state(status: Any) -> str:
    """``ok`` / ``stale`` / ``silent`` / ``off`` from a status (None = not connected)."""
    if status is None:
        return "off"
    if status.age_s is None or status.age_s > 2.0:
        return "silent"
    return "ok" if status.age_s <= 0.25 else "stale"


class LivePanel(QWidget):
    """Status light, figures and the live controls.

    Signals
    -------
    recordRequested(bool)
        True: start recording (the app asks where); False: stop.
    calibrateRequested(float, float)
        Countdown and capture window, seconds.
    disconnectRequested()
    """

    recordRequested = pyqtSignal(bool)
    calibrateRequested = pyqtSignal(float, float)
    disconnectRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        outer = QVBoxLayout(self)
        top = QHBoxLayout()
        self.light = QLabel()
        self.light.setFixedSize(14, 14)
        top.addWidget(self.light)
        self.address = QLabel("not connected")
        top.addWidget(self.address, 1)
        outer.addLayout(top)
        self.figures = QLabel("-")
        self.figures.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        outer.addWidget(self.figures)
        row = QHBoxLayout()
        self.record = QPushButton("Record")
        self.record.setCheckable(True)
        self.record.toggled.connect(self._record_toggled)
        row.addWidget(self.record)
        self.calibrate = QPushButton("Calibrate")
        self.calibrate.setToolTip("count down, then stand still (T-pose or standing) while the trackers are averaged")
        self.calibrate.clicked.connect(
            lambda: self.calibrateRequested.emit(self.countdown.value(), self.window.value())
        )
        row.addWidget(self.calibrate)
        self.disconnect = QPushButton("Disconnect")
        self.disconnect.clicked.connect(self.disconnectRequested.emit)
        row.addWidget(self.disconnect)
        outer.addLayout(row)
        form = QFormLayout()
        self.countdown = QDoubleSpinBox(minimum=0.0, maximum=30.0, value=3.0, suffix=" s")
        self.window = QDoubleSpinBox(minimum=0.2, maximum=30.0, value=2.0, suffix=" s")
        form.addRow("Countdown", self.countdown)
        form.addRow("Hold still for", self.window)
        outer.addLayout(form)
        self.calibration = QLabel("")
        self.calibration.setWordWrap(True)
        outer.addWidget(self.calibration)
        outer.addStretch(1)
        self._texts: dict[str, str] = {}
        self.show_status(None)

    def _record_toggled(self, on: bool) -> None:
        self.record.setText("Stop" if on else "Record")
        self.recordRequested.emit(on)

    def set_recording(self, on: bool) -> None:
        """Reflect the recording state without asking for it again."""
        self.record.blockSignals(True)
        self.record.setChecked(on)
        self.record.setText("Stop" if on else "Record")
        self.record.blockSignals(False)

    def _set(self, label: QLabel, key: str, text: str) -> None:
        if self._texts.get(key) != text:  # setting a label's text is not free
            self._texts[key] = text
            label.setText(text)

    def show_status(self, status: Any, latency_ms: float | None = None) -> None:
        """Show a status (``LiveStatus`` fields) and the latest latency, ms."""
        state = light_state(status)
        if self._texts.get("light") != state:
            self._texts["light"] = state
            self.light.setStyleSheet(f"background: {LIGHT[state]}; border-radius: 7px;")
        self.light.setToolTip(
            {"ok": "receiving", "stale": "no packet for a moment", "silent": "no packets", "off": "not connected"}[
                state
            ]
        )
        connected = status is not None
        for w in (self.record, self.calibrate, self.disconnect):
            w.setEnabled(connected)
        if status is None:
            self._set(self.address, "address", "not connected (File > Connect live source)")
            self._set(self.figures, "figures", "-")
            self._set(self.calibration, "cal", "")
            return
        self._set(self.address, "address", f"listening on {status.address}")
        lat = "-" if latency_ms is None else f"{latency_ms:.0f} ms"
        self._set(
            self.figures,
            "figures",
            f"{status.packet_rate_hz:.0f} packets/s, {status.frames} frames, latency {lat}\n"
            f"malformed {status.malformed}, duplicate {status.duplicates}, late {status.late}"
            # always three lines, so that the Record button stays under the pointer when a
            # recording starts and the click that stops it lands
            + (f"\nrecording to {status.recording}" if status.recording else "\nnot recording"),
        )
        if status.calibration_phase == "countdown":
            cal = f"get into the pose: {status.calibration_left_s:.0f} s"
        elif status.calibration_phase == "capturing":
            cal = f"hold still: {status.calibration_left_s:.1f} s"
        else:
            cal = status.calibration
        self._set(self.calibration, "cal", cal)
        self.calibrate.setEnabled(status.calibration_phase not in ("countdown", "capturing"))
