"""Optimizer settings: method, ghosts, and the settings the engine's schema marks for
the panel (mode, iterations, learning rate, temporal prior, update rule, root anchor...).

The fields, their labels, ranges and choices come from the engine as plain
:class:`SettingField` values (``app/schema.py`` builds them from
:class:`engine.solver.OptimizerSettings`), so this module needs no torch and repeats no
range.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from PyQt6.QtCore import pyqtSignal
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QLabel,
    QSpinBox,
    QWidget,
)

from widgets.field_editing import commit_only, is_editing

#: Ghost check boxes per row.
GHOSTS_PER_ROW = 3
#: Decimals of a number field; an open lower bound shows as its smallest step above it.
DECIMALS = 4


@dataclass(frozen=True)
class SettingField:
    """One optimizer setting as the panel shows it.

    Attributes
    ----------
    name, label, help : str
        Field name (as the engine's), form label, tooltip.
    kind : str
        ``"choice"``, ``"int"``, ``"float"`` or ``"bool"``.
    default : object
        The engine's default, shown until the session sets the field.
    lo, hi : float
        Allowed range of a number, in ``unit``; ``open_lo``: ``lo`` itself is not allowed.
    step : float
        Spin-box step.
    choices : tuple of str
        Values of a choice field.
    """

    name: str
    label: str
    kind: str
    default: Any
    help: str = ""
    lo: float = 0.0
    hi: float = 0.0
    open_lo: bool = False
    step: float = 1.0
    unit: str = ""
    choices: tuple[str, ...] = ()

    def minimum(self) -> float:
        """The spin box's minimum: ``lo``, or one displayed step above an open ``lo``."""
        if not self.open_lo:
            return self.lo
        return self.lo + (1 if self.kind == "int" else 10.0**-DECIMALS)


def _editor(f: SettingField) -> Any:
    """The control of one field (not yet connected)."""
    if f.kind == "choice":
        w: Any = QComboBox()
        w.addItems([str(v) for v in f.choices])
    elif f.kind == "bool":
        w = QCheckBox()
    elif f.kind == "int":
        w = commit_only(QSpinBox(minimum=int(f.minimum()), maximum=int(f.hi), singleStep=max(int(f.step), 1)))
    else:
        w = commit_only(QDoubleSpinBox(minimum=f.minimum(), maximum=f.hi, singleStep=f.step, decimals=DECIMALS))
    if f.unit and f.kind in ("int", "float"):
        w.setSuffix(f" {f.unit}")
    w.setToolTip(f.help)
    return w


class OptimizerPanel(QWidget):
    """Signals ``settingChanged(name, value)``, ``methodChanged(str)``, ``ghostsChanged(tuple)``.

    Parameters
    ----------
    methods : list of str
        Method names for the method combo and the ghost checkboxes.
    fields : sequence of SettingField
        The settings to show, in order, given by the engine; a choice field without
        values gets no control, so the panel only offers settings the engine knows.
    """

    settingChanged = pyqtSignal(str, object)
    methodChanged = pyqtSignal(str)
    ghostsChanged = pyqtSignal(tuple)

    def __init__(self, methods: list[str], fields: Sequence[SettingField] = (), parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._updating = False
        form = QFormLayout(self)
        self.method = QComboBox()
        self.method.addItems(methods)
        self.method.currentTextChanged.connect(lambda m: None if self._updating else self.methodChanged.emit(m))
        form.addRow("Method", self.method)
        # in rows of three: one row of every method would widen the dock, and with it the
        # window, past a 1366-pixel screen
        ghosts = QGridLayout()
        ghosts.setContentsMargins(0, 0, 0, 0)
        self.ghost_boxes: dict[str, QCheckBox] = {}
        for i, m in enumerate(methods):
            box = QCheckBox(m, toolTip=f"Also run {m} and draw it as a ghost")
            box.toggled.connect(self._ghosts_edited)
            ghosts.addWidget(box, i // GHOSTS_PER_ROW, i % GHOSTS_PER_ROW)
            self.ghost_boxes[m] = box
        holder = QWidget()
        holder.setLayout(ghosts)
        form.addRow("Ghosts", holder)
        #: Says when the settings do not apply to the shown method (:meth:`set_settings_apply`).
        self.settings_note = QLabel(wordWrap=True)
        self.settings_note.setVisible(False)
        form.addRow(self.settings_note)
        self.fields = {f.name: f for f in fields if f.kind != "choice" or f.choices}
        self.editors: dict[str, QWidget] = {}
        for name, f in self.fields.items():
            w = _editor(f)
            if f.kind == "choice":
                w.currentTextChanged.connect(lambda v, n=name: self._edit(n, v))
            elif f.kind == "bool":
                w.toggled.connect(lambda v, n=name: self._edit(n, bool(v)))
            elif f.kind == "int":
                w.valueChanged.connect(lambda v, n=name: self._edit(n, int(v)))
            else:
                w.valueChanged.connect(lambda v, n=name: self._edit(n, float(v)))
            self.editors[name] = w
            form.addRow(f.label, w)

    def _edit(self, name: str, value: Any) -> None:
        if not self._updating:
            self.settingChanged.emit(name, value)

    def _ghosts_edited(self) -> None:
        if not self._updating:
            self.ghostsChanged.emit(tuple(m for m, b in self.ghost_boxes.items() if b.isChecked()))

    def set_settings_apply(self, applies: bool, method: str) -> None:
        """Say under the ghosts, while the shown ``method`` takes no optimizer settings,
        that they wait for a method that does (they belong to the scene and stay
        editable, to be set before switching)."""
        note = (
            "" if applies else f"{method} takes no optimizer settings: they apply when a latent-space method is shown."
        )
        if note != self.settings_note.text():  # called on every drawn snapshot: only changes
            self.settings_note.setText(note)
            self.settings_note.setVisible(not applies)

    def set_state(self, method: str, ghosts: tuple[str, ...], settings: dict[str, Any]) -> None:
        """Show the session's method, ghosts and settings without emitting; a field the
        user is editing keeps what is typed there (it is sent when committed)."""
        self._updating = True
        try:
            self.method.setCurrentText(method)
            for m, box in self.ghost_boxes.items():
                box.setChecked(m in ghosts)
                box.setEnabled(m != method)
            for name, w in self.editors.items():
                if name not in settings or is_editing(w):
                    continue
                v = settings[name]
                if isinstance(w, QComboBox):
                    if w.findText(str(v)) < 0:  # e.g. another anchor joint from a scene file
                        w.addItem(str(v))
                    w.setCurrentText(str(v))
                elif isinstance(w, QCheckBox):
                    w.setChecked(bool(v))
                else:
                    w.setValue(v)
        finally:
            self._updating = False
