"""Constraint panel: add, remove, enable and weight constraints; edit their parameters.

The panel knows constraint kinds only through a *schema* (built by the app from the
engine's registry, so this module stays free of torch): for each kind, a list of
``(field name, tag, default)`` with tags ``float``, ``int``, ``bool``, ``joint``,
``vec3``, ``str``. One editor per kind is built from its fields.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtWidgets import (
    QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QHBoxLayout, QLabel, QLineEdit,
    QListWidget, QListWidgetItem, QPushButton, QSpinBox, QVBoxLayout, QWidget,
)  # fmt: skip

from engine.skeleton import JOINT_NAMES

Schema = dict[str, list[tuple[str, str, Any]]]
_BASE_FIELDS = ("name", "weight", "enabled")


def _spin(value: float, lo: float = -100.0, hi: float = 100.0, step: float = 0.01) -> QDoubleSpinBox:
    w = QDoubleSpinBox(minimum=lo, maximum=hi, singleStep=step, decimals=3)
    w.setValue(float(value))
    return w


class ConstraintEditor(QWidget):
    """Form for one constraint's fields; emits ``changed(dict)`` with one field at a time."""

    changed = pyqtSignal(dict)

    def __init__(self, fields: list[tuple[str, str, Any]], values: dict[str, Any]) -> None:
        super().__init__()
        form = QFormLayout(self)
        form.setContentsMargins(0, 0, 0, 0)
        self.inputs: dict[str, Any] = {}
        weight = _spin(values.get("weight", 1.0), 0.0, 1000.0, 0.1)
        weight.valueChanged.connect(lambda v: self.changed.emit({"weight": float(v)}))
        form.addRow("weight", weight)
        self.inputs["weight"] = weight
        for name, tag, default in fields:
            if name in _BASE_FIELDS:
                continue
            value = values.get(name, default)
            form.addRow(name, self._make(name, tag, value))

    def _make(self, name: str, tag: str, value: Any) -> QWidget:
        emit = lambda v, n=name: self.changed.emit({n: v})  # noqa: E731
        if tag == "float":
            w: Any = _spin(value)
            w.valueChanged.connect(lambda v: emit(float(v)))
        elif tag == "int":
            w = QSpinBox(minimum=-100000, maximum=100000, value=int(value))
            w.valueChanged.connect(lambda v: emit(int(v)))
        elif tag == "bool":
            w = QCheckBox(checked=bool(value))
            w.toggled.connect(lambda v: emit(bool(v)))
        elif tag == "joint":
            w = QComboBox()
            w.addItems(JOINT_NAMES)
            w.setCurrentText(str(value))
            w.currentTextChanged.connect(lambda v: emit(str(v)))
        elif tag == "vec3":
            w = QWidget()
            row = QHBoxLayout(w)
            row.setContentsMargins(0, 0, 0, 0)
            spins = [_spin(v) for v in np.asarray(value, float).reshape(3)]
            for s in spins:
                row.addWidget(s)
                s.valueChanged.connect(lambda _v, sp=spins: emit(np.array([x.value() for x in sp])))
            w.spins = spins  # type: ignore[attr-defined]
        elif tag == "str":
            w = QLineEdit(str(value))
            w.editingFinished.connect(lambda: emit(w.text()))
        else:
            w = QLabel(repr(value))
        self.inputs[name] = w
        return w


class ConstraintPanel(QWidget):
    """Signals ``addRequested(kind)``, ``removeRequested(name)``, ``changed(name, dict)``."""

    addRequested = pyqtSignal(str)
    removeRequested = pyqtSignal(str)
    changed = pyqtSignal(str, dict)

    def __init__(self, schema: Schema, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.schema = schema
        outer = QVBoxLayout(self)
        top = QHBoxLayout()
        self.kinds = QComboBox()
        self.kinds.addItems(sorted(schema))
        self.add_button = QPushButton("Add")
        self.add_button.clicked.connect(lambda: self.addRequested.emit(self.kinds.currentText()))
        self.remove_button = QPushButton("Remove")
        self.remove_button.clicked.connect(self._remove_selected)
        for w in (self.kinds, self.add_button, self.remove_button):
            top.addWidget(w)
        outer.addLayout(top)
        if not schema:
            self.kinds.addItem("(no constraint kinds available yet)")
            self.setEnabled(False)
        self.list = QListWidget()
        self.list.setMaximumHeight(110)
        self.list.currentRowChanged.connect(lambda _r: self._show_editor())
        self.list.itemChanged.connect(self._item_toggled)
        outer.addWidget(self.list)
        self.editor_holder = QVBoxLayout()
        outer.addLayout(self.editor_holder)
        outer.addStretch(1)
        self.editor: ConstraintEditor | None = None
        self.constraints: list[dict[str, Any]] = []
        self._updating = False

    def set_constraints(self, constraints: list[dict[str, Any]]) -> None:
        """Show the session's constraints (``to_dict`` form) without emitting."""
        selected = self.current_name()
        structure = [(c["name"], c["kind"]) for c in constraints]
        rebuild = structure != [(c["name"], c["kind"]) for c in self.constraints]
        self.constraints = [dict(c) for c in constraints]
        self._updating = True
        try:
            if rebuild:
                self.list.clear()
                for c in constraints:
                    item = QListWidgetItem(f"{c['name']}  [{c['kind']}]")
                    item.setData(Qt.ItemDataRole.UserRole, c["name"])
                    item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                    self.list.addItem(item)
                names = [c["name"] for c in constraints]
                self.list.setCurrentRow(names.index(selected) if selected in names else len(names) - 1)
            for i, c in enumerate(constraints):
                state = Qt.CheckState.Checked if c.get("enabled", True) else Qt.CheckState.Unchecked
                self.list.item(i).setCheckState(state)
        finally:
            self._updating = False
        if rebuild:
            self._show_editor()

    def current_name(self) -> str:
        item = self.list.currentItem()
        return item.data(Qt.ItemDataRole.UserRole) if item else ""

    def _show_editor(self) -> None:
        if self.editor is not None:
            self.editor.deleteLater()
            self.editor = None
        name = self.current_name()
        data = next((c for c in self.constraints if c["name"] == name), None)
        if data is None:
            return
        self.editor = ConstraintEditor(self.schema.get(data["kind"], []), data)
        self.editor.changed.connect(lambda changes, n=name: self.changed.emit(n, changes))
        self.editor_holder.addWidget(self.editor)

    def _item_toggled(self, item: QListWidgetItem) -> None:
        if not self._updating:
            enabled = item.checkState() == Qt.CheckState.Checked
            self.changed.emit(item.data(Qt.ItemDataRole.UserRole), {"enabled": enabled})

    def _remove_selected(self) -> None:
        if name := self.current_name():
            self.removeRequested.emit(name)
