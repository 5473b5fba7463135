"""Sensor panel: preset, and per tracker: on/off, 6/3-DoF, weight, failure, reset offset."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)
from superqt import QLabeledDoubleSlider

#: Friendlier labels for the joints trackers are usually worn on.
LABELS = {
    "upperneck": "head",
    "root": "hips",
    "lwrist": "left hand",
    "rwrist": "right hand",
    "lankle": "left foot",
    "rankle": "right foot",
}


class SensorPanel(QWidget):
    """Edits the session's sensor set; every edit is a signal, state comes back via
    :meth:`set_sensors`.

    Signals
    -------
    presetChanged(str)
    sensorChanged(str, dict)
        Joint and the fields changed (``enabled``, ``dof``, ``weight``).
    failureRequested(str, int)
        Joint and number of frames it is lost for, from the current frame.
    resetRequested(str)
        Reset drag offset and failures of a joint ("" = all).
    """

    presetChanged = pyqtSignal(str)
    sensorChanged = pyqtSignal(str, dict)
    failureRequested = pyqtSignal(str, int)
    resetRequested = pyqtSignal(str)

    def __init__(self, presets: dict[str, tuple[str, ...]], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        outer = QVBoxLayout(self)
        top = QHBoxLayout()
        top.addWidget(QLabel("Preset"))
        self.preset = QComboBox()
        self.preset.addItems(list(presets))
        self.preset.currentTextChanged.connect(self._preset_chosen)
        top.addWidget(self.preset, 1)
        outer.addLayout(top)
        self.grid = QGridLayout()
        self.grid.setColumnStretch(2, 1)  # the weight slider takes the spare width
        outer.addLayout(self.grid)
        fail = QHBoxLayout()
        fail.addWidget(QLabel("Failure length"))
        self.fail_frames = QSpinBox(minimum=1, maximum=100000, value=60, suffix=" frames")
        fail.addWidget(self.fail_frames)
        reset_all = QPushButton("Reset all offsets")
        reset_all.clicked.connect(lambda: self.resetRequested.emit(""))
        fail.addWidget(reset_all)
        outer.addLayout(fail)
        outer.addStretch(1)
        self.rows: dict[str, dict[str, Any]] = {}
        self._updating = False

    def _preset_chosen(self, name: str) -> None:
        if not self._updating:
            self.presetChanged.emit(name)

    def set_sensors(self, preset: str, sensors: Mapping[str, Any]) -> None:
        """Show ``sensors`` (joint -> ``engine.sensors.Sensor``) without emitting."""
        self._updating = True
        try:
            if preset and self.preset.currentText() != preset:
                self.preset.setCurrentText(preset)
            if list(sensors) != list(self.rows):
                self._build_rows(list(sensors))
            for j, cfg in sensors.items():
                self._show_row(j, cfg)
        finally:
            self._updating = False

    def set_sensor(self, joint: str, cfg: Any) -> None:
        """Show one edited sensor (a drag moves one target many times a second)."""
        if joint not in self.rows:
            return
        self._updating = True
        try:
            self._show_row(joint, cfg)
        finally:
            self._updating = False

    def _show_row(self, j: str, cfg: Any) -> None:
        """Set only what differs: each setter repaints, and a drag calls this per mouse move."""
        r = self.rows[j]
        if r["enabled"].isChecked() != cfg.enabled:
            r["enabled"].setChecked(cfg.enabled)
        if r["dof"].currentIndex() != (0 if cfg.dof == 6 else 1):
            r["dof"].setCurrentIndex(0 if cfg.dof == 6 else 1)
        if abs(r["weight"].value() - cfg.weight) > 1e-9:
            r["weight"].setValue(cfg.weight)
        moved = any(abs(v) > 1e-9 for v in cfg.offset)
        if r["reset"].isEnabled() != (moved or bool(cfg.failures)):
            r["reset"].setEnabled(moved or bool(cfg.failures))
        label = LABELS.get(j, j) + (" *" if moved else "")
        if r["label"].text() != label:
            r["label"].setText(label)

    def set_failure_left(self, joint: str, left: int | None) -> None:
        """Show ``left`` frames of a simulated failure on ``joint``'s Fail button (None:
        no failure running)."""
        r = self.rows.get(joint)
        if r is None:
            return
        r["fail"].setText("Fail" if left is None else f"Lost {left}")

    def _build_rows(self, joints: list[str]) -> None:
        while self.grid.count():
            item = self.grid.takeAt(0)
            if item.widget():
                item.widget().deleteLater()
        self.rows = {}
        for col, title in enumerate(("Sensor", "DoF", "Weight", "", "")):
            self.grid.addWidget(QLabel(f"<b>{title}</b>"), 0, col)
        for i, j in enumerate(joints, start=1):
            enabled = QCheckBox(toolTip=f"Send the {LABELS.get(j, j)} tracker ({j}) to the method")
            label = QLabel(LABELS.get(j, j))
            box = QHBoxLayout()
            holder = QWidget()
            holder.setLayout(box)
            box.setContentsMargins(0, 0, 0, 0)
            box.addWidget(enabled)
            box.addWidget(label, 1)
            dof = QComboBox()
            dof.addItems(["6-DoF", "3-DoF"])
            weight = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
            weight.setRange(0.0, 5.0)
            weight.setValue(1.0)
            weight.setMinimumWidth(110)
            fail = QPushButton("Fail", toolTip="Simulate losing this tracker from the current frame")
            fail.setMinimumWidth(fail.fontMetrics().horizontalAdvance("Lost 99999") + 16)  # no relayout per frame
            reset = QPushButton("Reset", toolTip="Reset drag offset and simulated failures")
            enabled.toggled.connect(lambda v, j=j: self._edit(j, enabled=bool(v)))
            dof.currentIndexChanged.connect(lambda k, j=j: self._edit(j, dof=6 if k == 0 else 3))
            weight.valueChanged.connect(lambda v, j=j: self._edit(j, weight=float(v)))
            fail.clicked.connect(lambda _=False, j=j: self.failureRequested.emit(j, self.fail_frames.value()))
            reset.clicked.connect(lambda _=False, j=j: self.resetRequested.emit(j))
            for col, w in enumerate((holder, dof, weight, fail, reset)):
                self.grid.addWidget(w, i, col)
            self.rows[j] = dict(enabled=enabled, label=label, dof=dof, weight=weight, fail=fail, reset=reset)

    def _edit(self, joint: str, **changes: Any) -> None:
        if not self._updating:
            self.sensorChanged.emit(joint, changes)
