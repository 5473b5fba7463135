"""Optimizer settings: method, ghosts, mode, iterations, learning rate, temporal prior
(its weight and source), latent update rule and root anchor."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from PyQt6.QtCore import pyqtSignal
from PyQt6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QHBoxLayout, QSpinBox, QWidget

#: name -> (label, kind, min, max, step); kinds: "choice", "int", "float". A choice
#: field's values come from the engine (``choices``), so this module needs no torch.
FIELDS: dict[str, tuple[str, str, float, float, float]] = {
    "mode": ("Mode", "choice", 0, 0, 0),
    "iterations": ("Iterations / frame", "int", 1, 200, 1),
    "optimizer": ("Latent update", "choice", 0, 0, 0),
    "lr": ("Adam learning rate", "float", 1e-4, 1.0, 0.005),
    "step_size": ("Gradient step size", "float", 1e-3, 5.0, 0.05),
    "temporal_weight": ("Temporal prior weight", "float", 0.0, 10.0, 0.1),
    "prior": ("Prior from (sparse sets: trackers)", "choice", 0, 0, 0),
    "tracker_prior_weight": ("Tracker prior weight", "float", 0.0, 10.0, 0.1),
    "root_anchor": ("Root anchor (no hip tracker)", "choice", 0, 0, 0),
    "sensor_blend": ("Sensor blend-in (s)", "float", 0.0, 2.0, 0.1),
}
#: Values of the choice fields when the caller gives none.
DEFAULT_CHOICES: dict[str, tuple[str, ...]] = {"mode": ("realtime", "offline")}


class OptimizerPanel(QWidget):
    """Signals ``settingChanged(name, value)``, ``methodChanged(str)``, ``ghostsChanged(tuple)``.

    Parameters
    ----------
    methods : list of str
        Method names for the method combo and the ghost checkboxes.
    choices : mapping, optional
        Values of each choice field (``mode``, ``optimizer``, ``root_anchor``), given by
        the engine; a choice field without values gets no control, so the panel only
        offers settings the engine knows.
    """

    settingChanged = pyqtSignal(str, object)
    methodChanged = pyqtSignal(str)
    ghostsChanged = pyqtSignal(tuple)

    def __init__(self, methods: list[str], choices: Mapping[str, Sequence[str]] | None = None,
                 parent: QWidget | None = None) -> None:  # fmt: skip
        super().__init__(parent)
        choices = {**DEFAULT_CHOICES, **(choices or {})}
        form = QFormLayout(self)
        self.method = QComboBox()
        self.method.addItems(methods)
        self.method.currentTextChanged.connect(lambda m: None if self._updating else self.methodChanged.emit(m))
        form.addRow("Method", self.method)
        ghosts = QHBoxLayout()
        self.ghost_boxes: dict[str, QCheckBox] = {}
        for m in methods:
            box = QCheckBox(m, toolTip=f"Also run {m} and draw it as a ghost")
            box.toggled.connect(self._ghosts_edited)
            ghosts.addWidget(box)
            self.ghost_boxes[m] = box
        holder = QWidget()
        holder.setLayout(ghosts)
        form.addRow("Ghosts", holder)
        self.editors: dict[str, QWidget] = {}
        for name, (label, kind, lo, hi, step) in FIELDS.items():
            if kind == "choice":
                if not choices.get(name):
                    continue
                w: Any = QComboBox()
                w.addItems([str(v) for v in choices[name]])
                w.currentTextChanged.connect(lambda v, n=name: self._edit(n, v))
            elif kind == "int":
                w = QSpinBox(minimum=int(lo), maximum=int(hi), singleStep=int(step))
                w.valueChanged.connect(lambda v, n=name: self._edit(n, int(v)))
            else:
                w = QDoubleSpinBox(minimum=lo, maximum=hi, singleStep=step, decimals=4)
                w.valueChanged.connect(lambda v, n=name: self._edit(n, float(v)))
            self.editors[name] = w
            form.addRow(label, w)
        self._updating = False

    def _edit(self, name: str, value: Any) -> None:
        if not self._updating:
            self.settingChanged.emit(name, value)

    def _ghosts_edited(self) -> None:
        if not self._updating:
            self.ghostsChanged.emit(tuple(m for m, b in self.ghost_boxes.items() if b.isChecked()))

    def set_state(self, method: str, ghosts: tuple[str, ...], settings: dict[str, Any]) -> None:
        """Show the session's method, ghosts and settings without emitting."""
        self._updating = True
        try:
            self.method.setCurrentText(method)
            for m, box in self.ghost_boxes.items():
                box.setChecked(m in ghosts)
                box.setEnabled(m != method)
            for name, w in self.editors.items():
                if name not in settings:
                    continue
                v = settings[name]
                if isinstance(w, QComboBox):
                    if w.findText(str(v)) < 0:  # e.g. another anchor joint from a scene file
                        w.addItem(str(v))
                    w.setCurrentText(str(v))
                else:
                    w.setValue(v)
        finally:
            self._updating = False
