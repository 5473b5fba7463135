"""Help ▸ Keyboard and mouse: every shortcut of the window, read from its actions."""

from __future__ import annotations

from PyQt6.QtWidgets import QDialog, QDialogButtonBox, QLabel, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget

#: Mouse gestures of the studio's 3D view (not actions, so listed here).
MOUSE = (
    ("Left drag", "Rotate the camera"),
    ("Right drag / wheel", "Zoom"),
    ("Middle drag", "Pan"),
    ("Drag a yellow sphere", "Move that sensor's target (kept until Reset)"),
    ("Ctrl + drag a joint", "Pin the joint there (a sensor's joint moves its target)"),
    ("Click a joint", "Select it: its motion path (View > Motion paths)"),
    ("Drag a cyan handle", "Edit a constraint (point, box, look-at target)"),
    ("Drop a .bvh file", "Open it"),
)

#: Mouse gestures of the pose window's 3D view and key timeline: a plain drag on the body
#: poses it there, where the studio's turns the camera.
POSE_MOUSE = (
    ("Drag a joint", "Put a target on it: the body follows (a hand dropped on another joint touches it)"),
    ("Drag a yellow sphere", "Move that target"),
    ("Drag the hips", "Move the whole body; down: a squat, the feet planted"),
    ("Shift + drag the hips", "Move only the pelvis, the feet planted flat (a squat)"),
    ("Click a joint", "Select it: its rotation rings and its motion path (View > Motion paths)"),
    (
        "Drag a ring",
        "Turn the selected joint about that axis (red X, green Y, blue Z) by whole degrees, with Ctrl "
        "held by 5 degrees; the status bar reads the angle",
    ),
    ("Alt + drag a joint", "Turn it by the angle the mouse sweeps around it"),
    ("Drag a cyan handle", "Edit a constraint (point, box, look-at target)"),
    ("Left drag off the body", "Rotate the camera"),
    ("Right drag / wheel", "Zoom (the wheel toward the mouse)"),
    ("Middle drag", "Pan"),
    ("Click or drag on the key timeline", "Go to that frame; drag a key's mark to move the key"),
)


class HelpDialog(QDialog):
    """A table of ``(keys, what)`` rows: the window's shortcuts, then its ``mouse``
    gestures (:data:`MOUSE`, the studio's, or :data:`POSE_MOUSE`)."""

    def __init__(
        self,
        shortcuts: list[tuple[str, str]],
        parent: QWidget | None = None,
        mouse: tuple[tuple[str, str], ...] = MOUSE,
    ) -> None:
        super().__init__(parent)
        self.setWindowTitle("Keyboard and mouse")
        rows = [(keys, what) for keys, what in shortcuts if keys] + list(mouse)
        self.table = QTableWidget(len(rows), 2)
        self.table.setHorizontalHeaderLabels(["Keys", "Does"])
        self.table.verticalHeader().setVisible(False)
        for i, (keys, what) in enumerate(rows):
            self.table.setItem(i, 0, QTableWidgetItem(keys))
            self.table.setItem(i, 1, QTableWidgetItem(what))
        self.table.resizeColumnsToContents()
        self.table.horizontalHeader().setStretchLastSection(True)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(
            QLabel(
                "Shortcuts work anywhere in the window (not while typing in a field); "
                "the camera keys (Home, 1, 3, 7) work over the 3D view even then."
            )
        )
        layout.addWidget(self.table)
        layout.addWidget(buttons)
        self.resize(520, 560)

    def rows(self) -> list[tuple[str, str]]:
        return [(self.table.item(i, 0).text(), self.table.item(i, 1).text()) for i in range(self.table.rowCount())]
