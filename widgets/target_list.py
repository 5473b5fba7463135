"""The pose mode's joint target list: one row per target with enable, weight and clear,
and under them, on an in-between, the targets of one of its two keys only, which do not
act there."""

from __future__ import annotations

from PyQt6.QtCore import pyqtSignal
from PyQt6.QtWidgets import (
    QCheckBox,
    QDoubleSpinBox,
    QGridLayout,
    QLabel,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

#: Target weights the spin box offers (the engine accepts the same range).
WEIGHT_RANGE = (0.0, 10.0)


class TargetList(QWidget):
    """Shows targets; user edits become signals (the window changes the pose mode).

    Signals
    -------
    enabledChanged(str, bool), weightChanged(str, float)
        A row's checkbox or weight was edited (joint, value).
    turnHeld(str, bool)
        A row's "hold turn" box: keep the joint's current world rotation (True) or
        drop the rotation target (False).
    clearRequested(str)
        A row's Clear button.
    clearAllRequested()
        The Clear all button.
    """

    enabledChanged = pyqtSignal(str, bool)
    weightChanged = pyqtSignal(str, float)
    turnHeld = pyqtSignal(str, bool)
    clearRequested = pyqtSignal(str)
    clearAllRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        outer = QVBoxLayout(self)
        self.hint = QLabel(
            "Drag a joint to add a target; drag its sphere to move it; drag a ring to turn it. "
            "The hips move the whole body (dragged down: a squat); their ring turns it. "
            "Shift + drag the hips: the pelvis alone, the feet planted flat."
        )
        self.hint.setWordWrap(True)
        # the hint shows while there is no target; then its lines go to the rows (it
        # stays the panel's tooltip), and Clear all sits above the rows: the three
        # targets of a T-pose with a turned head fit the panel without scrolling
        self.setToolTip(self.hint.text())
        outer.addWidget(self.hint)
        self.clear_all = QPushButton("Clear all")
        self.clear_all.clicked.connect(self.clearAllRequested.emit)
        outer.addWidget(self.clear_all)
        self.grid_host = QWidget()
        self.grid = QGridLayout(self.grid_host)
        self.grid.setColumnStretch(4, 1)  # spare width goes right of the controls
        outer.addWidget(self.grid_host)
        self.key_only = QLabel()
        self.key_only.setWordWrap(True)
        self.key_only.setStyleSheet("color: #8a93a6;")  # a note, as the latent views' notes
        self.key_only.hide()
        outer.addWidget(self.key_only)
        outer.addStretch(1)
        self.rows: dict[str, dict[str, QWidget]] = {}

    def set_targets(self, targets: dict[str, tuple[bool, float, bool]]) -> None:
        """Show ``joint -> (enabled, weight, has rotation)`` without emitting signals."""
        if tuple(targets) != tuple(self.rows):
            self._rebuild(tuple(targets))
        for joint, (enabled, weight, rotation) in targets.items():
            row = self.rows[joint]
            for w in (row["enabled"], row["weight"], row["turn"]):
                w.blockSignals(True)
            row["enabled"].setChecked(bool(enabled))
            row["weight"].setValue(float(weight))
            row["turn"].setChecked(bool(rotation))
            row["label"].setText(f"{joint} (+rotation)" if rotation else joint)
            for w in (row["enabled"], row["weight"], row["turn"]):
                w.blockSignals(False)
        self.clear_all.setEnabled(bool(targets))
        self.hint.setVisible(not targets)

    def set_key_only(self, joints: dict[str, int]) -> None:
        """Show ``joint -> key frame``: the targets of one of the two keys around the frame
        shown, which the in-between does not take (none: hidden)."""
        names = ", ".join(f"{j} (key {f})" for j, f in sorted(joints.items(), key=lambda jf: (jf[1], jf[0])))
        self.key_only.setText(
            f"Not acting on this frame, on one key only: {names}. "
            "An in-between takes the targets both keys around it have; drag the joint to target it here."
            if joints
            else ""
        )
        self.key_only.setVisible(bool(joints))

    def _rebuild(self, joints: tuple[str, ...]) -> None:
        for row in self.rows.values():
            for w in row.values():
                self.grid.removeWidget(w)
                w.hide()  # at once: the deletion waits for the event loop
                w.deleteLater()
        self.rows = {}
        for i, joint in enumerate(joints):
            enabled = QCheckBox()
            enabled.toggled.connect(lambda on, j=joint: self.enabledChanged.emit(j, bool(on)))
            weight = QDoubleSpinBox(minimum=WEIGHT_RANGE[0], maximum=WEIGHT_RANGE[1], singleStep=0.5, decimals=2)
            weight.valueChanged.connect(lambda v, j=joint: self.weightChanged.emit(j, float(v)))
            turn = QCheckBox("hold turn")
            turn.setToolTip("Keep the joint turned as it is now (a rotation target)")
            turn.toggled.connect(lambda on, j=joint: self.turnHeld.emit(j, bool(on)))
            clear = QPushButton("Clear")
            clear.setMaximumWidth(clear.fontMetrics().horizontalAdvance("Clear") + 16)  # the row fits the panel
            clear.clicked.connect(lambda _=False, j=joint: self.clearRequested.emit(j))
            label = QLabel(joint)
            # two lines per target, so a long name and its controls fit the side panel
            self.grid.addWidget(enabled, 2 * i, 0)
            self.grid.addWidget(label, 2 * i, 1, 1, 3)
            for col, w in enumerate((weight, turn, clear), start=1):
                self.grid.addWidget(w, 2 * i + 1, col)
            self.rows[joint] = {"enabled": enabled, "label": label, "weight": weight, "turn": turn, "clear": clear}
