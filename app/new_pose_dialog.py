"""The New pose dialog: the character's height and the pose to start from.

The studio's File ▸ New pose (:mod:`app.authoring_actions`) offers a neutral standing pose
or the loaded clip's current frame; the pose window's (:mod:`app.pose_files`) starts over in
the same window and offers the neutral pose only.
"""

from __future__ import annotations

from PyQt6.QtWidgets import QComboBox, QDialog, QDialogButtonBox, QDoubleSpinBox, QFormLayout, QWidget

from engine import skeleton as sk

#: The starting poses offered: the pose model's average pose (its latent zero) or a clip frame.
MEAN, CLIP = "a neutral standing pose", "the clip's current frame"


class NewPoseDialog(QDialog):
    """Height (metres) and starting pose (the studio's New pose; the pose window's offers
    only the neutral pose, ``has_clip`` False)."""

    def __init__(self, parent: QWidget | None, has_clip: bool, height: float | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("New pose")
        form = QFormLayout(self)
        # offered: ``height`` metres, else the canonical subject's (a scene that gives
        # none is baked at it too)
        offered = round(height if height is not None else sk.Skeleton.canonical().height(), 2)
        self.height_m = QDoubleSpinBox(
            minimum=0.5, maximum=2.5, decimals=2, singleStep=0.05, value=offered, suffix=" m"
        )
        self.start = QComboBox()
        self.start.addItems([MEAN, CLIP] if has_clip else [MEAN])
        form.addRow("Height", self.height_m)
        form.addRow("Start from", self.start)
        box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        box.accepted.connect(self.accept)
        box.rejected.connect(self.reject)
        form.addRow(box)
