"""Constraint panel: add, remove, enable and weight constraints; edit their parameters.

The panel knows constraint kinds only through a *schema* (built by the app from the
engine's catalog, so this module stays free of torch): for each kind, a list of
``(field name, tag, default[, choices])`` with tags ``float``, ``int``, ``bool``,
``joint``, ``joints`` (several joints), ``choice`` (one of ``choices``), ``vec3``,
``str``, ``frames`` (the frame range with its blends: :mod:`widgets.frame_range`). The
window says how many frames there are and which range to offer (:attr:`ConstraintPanel.frame_count`,
:attr:`ConstraintPanel.default_range`) and draws the selected constraint's range on its
timeline (``selected``, :meth:`ConstraintPanel.span`). The editor sits in a scroll area, so a kind with many fields never grows the
window, and it follows edits made elsewhere (a gizmo drag, undo) without emitting.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QFrame,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMenu,
    QPushButton,
    QScrollArea,
    QSizePolicy,
    QSpinBox,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from engine.skeleton import JOINT_NAMES
from widgets.field_editing import commit_only, is_editing
from widgets.frame_range import FRAME_FIELDS, FrameRangeEditor, Span, span_of

Schema = dict[str, list[Sequence[Any]]]
_BASE_FIELDS = ("name", "weight", "enabled")


def _spin(value: float, lo: float = -100.0, hi: float = 100.0, step: float = 0.01) -> QDoubleSpinBox:
    w = commit_only(QDoubleSpinBox(minimum=lo, maximum=hi, singleStep=step, decimals=3))
    w.setValue(float(value) if np.isfinite(value) else 0.0)
    w.setMinimumWidth(60)
    return w


def row_text(c: dict[str, Any]) -> str:
    """A constraint's row in the list (``to_dict`` form): its name, and in brackets its
    kind, the joint it holds and its frames when it has them (*pin [pin: lwrist,
    100-160]*); the name and kind alone would read *pin [pin]* for every pin."""
    held = [str(c[k]) for k in ("joint", "joint_a", "joint_b") if isinstance(c.get(k), str)]
    frames = c.get("frames")
    where = held + ([f"{int(frames[0])}-{int(frames[1])}"] if frames is not None else [])
    return f"{c['name']}  [{c['kind']}{': ' + ', '.join(where) if where else ''}]"


class JointsButton(QToolButton):
    """Pick several joints from a menu of check boxes; ``picked(tuple)`` on every change."""

    picked = pyqtSignal(tuple)

    def __init__(self, joints: Sequence[str]) -> None:
        super().__init__()
        self.setPopupMode(QToolButton.ToolButtonPopupMode.InstantPopup)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        menu = QMenu(self)
        self.actions_by_joint: dict[str, QAction] = {}
        for j in JOINT_NAMES:
            act = menu.addAction(j)
            act.setCheckable(True)
            act.toggled.connect(self._toggled)
            self.actions_by_joint[j] = act
        self.setMenu(menu)
        self.set_joints(joints)

    def joints(self) -> tuple[str, ...]:
        return tuple(j for j, a in self.actions_by_joint.items() if a.isChecked())

    def set_joints(self, joints: Sequence[str]) -> None:
        """Tick exactly ``joints`` without emitting."""
        self.blockSignals(True)
        for j, act in self.actions_by_joint.items():
            act.setChecked(j in joints)
        self.blockSignals(False)
        self.setText(", ".join(self.joints()) or "(none)")

    def _toggled(self) -> None:
        self.setText(", ".join(self.joints()) or "(none)")
        if not self.signalsBlocked():
            self.picked.emit(self.joints())


class ConstraintEditor(QWidget):
    """Form for one constraint's fields; emits ``changed(dict)`` with one field at a time."""

    changed = pyqtSignal(dict)

    def __init__(self, fields: list[Sequence[Any]], values: dict[str, Any]) -> None:
        super().__init__()
        form = QFormLayout(self)
        form.setContentsMargins(0, 0, 0, 0)
        form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
        self.inputs: dict[str, Any] = {}
        self.tags: dict[str, str] = {"weight": "float"}
        weight = _spin(values.get("weight", 1.0), 0.0, 1000.0, 0.1)
        weight.valueChanged.connect(lambda v: self.changed.emit({"weight": float(v)}))
        form.addRow("weight", weight)
        self.inputs["weight"] = weight
        self.range: FrameRangeEditor | None = None
        for spec in fields:
            name, tag, default = spec[0], spec[1], spec[2]
            if name in _BASE_FIELDS or (name in FRAME_FIELDS and tag != "frames"):
                continue  # the blends are part of the frame range's row
            choices = tuple(spec[3]) if len(spec) > 3 else ()
            self.tags[name] = tag
            form.addRow(name, self._make(name, tag, values.get(name, default), choices))

    def _make(self, name: str, tag: str, value: Any, choices: tuple[str, ...]) -> QWidget:
        emit = lambda v, n=name: self.changed.emit({n: v})  # noqa: E731
        if tag == "frames":
            w: Any = FrameRangeEditor({"frames": value})
            w.changed.connect(self.changed.emit)
            self.range = w
        elif tag == "float":
            w: Any = _spin(value)
            w.valueChanged.connect(lambda v: emit(float(v)))
        elif tag == "int":
            w = commit_only(QSpinBox(minimum=-100000, maximum=100000, value=int(value)))
            w.valueChanged.connect(lambda v: emit(int(v)))
        elif tag == "bool":
            w = QCheckBox(checked=bool(value))
            w.toggled.connect(lambda v: emit(bool(v)))
        elif tag in ("joint", "choice"):
            w = QComboBox()
            w.addItems(JOINT_NAMES if tag == "joint" else choices)
            if w.findText(str(value)) < 0:  # a value from a scene file is shown, not dropped
                w.addItem(str(value))
            w.setCurrentText(str(value))
            w.currentTextChanged.connect(lambda v: emit(str(v)))
        elif tag == "joints":
            w = JointsButton(tuple(value))
            w.picked.connect(lambda v: emit(tuple(v)))
        elif tag == "vec3":
            w = QWidget()
            row = QHBoxLayout(w)
            row.setContentsMargins(0, 0, 0, 0)
            row.setSpacing(2)
            spins = [_spin(v) for v in np.asarray(value, float).reshape(3)]
            for s in spins:
                row.addWidget(s)
                s.valueChanged.connect(lambda _v, sp=spins: emit(np.array([x.value() for x in sp])))
            w.spins = spins  # type: ignore[attr-defined]
        elif tag == "str":
            w = QLineEdit(str(value))
            w.editingFinished.connect(lambda: emit(w.text()))
        else:  # shown, not editable here (e.g. a quaternion set by a sensor)
            w = QLabel(
                np.array2string(np.asarray(value), precision=3) if isinstance(value, np.ndarray) else repr(value)
            )
            w.setWordWrap(True)
            w.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.inputs[name] = w
        return w

    def set_values(self, values: dict[str, Any]) -> None:
        """Show ``values`` (edited elsewhere) without emitting ``changed``; a field the
        user is editing keeps what is typed there."""
        for name, w in self.inputs.items():
            tag = self.tags.get(name, "")
            if tag == "frames":  # keeps a number being typed itself; a saved form leaves out a range of every frame
                w.set_values(values)
                continue
            if name not in values or is_editing(w):
                continue
            v = values[name]
            widgets = w.spins if tag == "vec3" else [w]
            for x in widgets:
                x.blockSignals(True)
            try:
                if tag in ("float", "int"):
                    w.setValue(v)
                elif tag == "bool":
                    w.setChecked(bool(v))
                elif tag in ("joint", "choice"):
                    w.setCurrentText(str(v))
                elif tag == "joints":
                    w.set_joints(tuple(v))
                elif tag == "vec3":
                    for s, x in zip(w.spins, np.asarray(v, float).reshape(3)):
                        s.setValue(float(x) if np.isfinite(x) else 0.0)
                elif tag == "str":
                    w.setText(str(v))
            finally:
                for x in widgets:
                    x.blockSignals(False)


class ConstraintPanel(QWidget):
    """Signals ``addRequested(kind)``, ``removeRequested(name)``, ``changed(name, dict)``."""

    addRequested = pyqtSignal(str)
    removeRequested = pyqtSignal(str)
    changed = pyqtSignal(str, dict)
    #: The constraint whose editor shows changed, or its fields did ("" for none).
    selected = pyqtSignal(str)

    def __init__(self, schema: Schema, parent: QWidget | None = None, empty_hint: str = "") -> None:
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
        self.remove_button.setEnabled(False)  # until there is a constraint
        outer.addLayout(top)
        if not schema:
            self.kinds.addItem("(no constraint kinds available yet)")
            self.setEnabled(False)
        self.list = QListWidget()
        self.list.setMaximumHeight(110)
        self.list.currentRowChanged.connect(lambda _r: self._show_editor())
        self.list.itemChanged.connect(self._item_toggled)
        outer.addWidget(self.list)
        # the editor scrolls inside the dock: its size never reaches the window's layout
        self.scroll = QScrollArea()
        self.scroll.setWidgetResizable(True)
        self.scroll.setFrameShape(QFrame.Shape.NoFrame)
        self.scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.scroll.setMinimumHeight(60)
        outer.addWidget(self.scroll, 1)
        # what the empty editor area says: how to get a constraint, or how to edit one
        self.hint = QLabel(wordWrap=True, margin=8)
        self.hint.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
        self.hint.setStyleSheet("color: palette(mid);")
        #: What the editor area says while there is no constraint.
        self.empty_hint = empty_hint or "No constraints yet: pick a kind above and press Add."
        self.scroll.setWidget(self.hint)
        self.hint.setText(self.empty_hint)
        self.editor: ConstraintEditor | None = None
        self.constraints: list[dict[str, Any]] = []
        self._updating = False
        #: ``() -> frames`` of the clip or animation (bounds the frame range's fields).
        self.frame_count: Callable[[], int] = lambda: 61
        #: ``() -> (start, end)``: the range offered when *only frames* is ticked.
        self.default_range: Callable[[], tuple[int, int]] = lambda: (0, 60)

    def frames_changed(self) -> None:
        """The clip or the animation changed length: bound the open range editor by it."""
        if self.editor is not None and self.editor.range is not None:
            self.editor.range.set_frame_count(self.frame_count())

    def span(self) -> Span | None:
        """The selected constraint's frame range and blends, None for none or every frame."""
        data = next((c for c in self.constraints if c["name"] == self.current_name()), None)
        return None if data is None else span_of(data)

    def set_constraints(self, constraints: list[dict[str, Any]]) -> None:
        """Show the session's constraints (``to_dict`` form) without emitting.

        A constraint that was not there before is selected (the one just added); the
        open editor takes the new values of its constraint.
        """
        selected = self.current_name()
        before = {c["name"] for c in self.constraints}
        structure = [(c["name"], c["kind"]) for c in constraints]
        rebuild = structure != [(c["name"], c["kind"]) for c in self.constraints]
        self.constraints = [dict(c) for c in constraints]
        names = [c["name"] for c in constraints]
        added = [n for n in names if n not in before]
        self._updating = True
        try:
            if rebuild:
                self.list.clear()
                for c in constraints:
                    item = QListWidgetItem(row_text(c))
                    item.setData(Qt.ItemDataRole.UserRole, c["name"])
                    item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                    self.list.addItem(item)
                pick = added[-1] if added else selected
                self.list.setCurrentRow(names.index(pick) if pick in names else len(names) - 1)
            for i, c in enumerate(constraints):
                state = Qt.CheckState.Checked if c.get("enabled", True) else Qt.CheckState.Unchecked
                item = self.list.item(i)
                item.setCheckState(state)
                text = row_text(c)
                if item.text() != text:
                    item.setText(text)
        finally:
            self._updating = False
        self.remove_button.setEnabled(bool(constraints))  # nothing to remove in an empty list
        if rebuild:
            self._show_editor()
        else:
            if self.editor is not None:
                data = next((c for c in self.constraints if c["name"] == self.current_name()), None)
                if data is not None:
                    self.editor.set_values(data)
                self.frames_changed()
            self.selected.emit(self.current_name())

    def current_name(self) -> str:
        item = self.list.currentItem()
        return item.data(Qt.ItemDataRole.UserRole) if item else ""

    def _show_editor(self) -> None:
        if self.editor is not None:
            self.scroll.takeWidget()
            self.editor.deleteLater()
            self.editor = None
        name = self.current_name()
        data = next((c for c in self.constraints if c["name"] == name), None)
        if data is None:
            self.hint.setText(self.empty_hint if not self.constraints else "Select a constraint above to edit it.")
            if self.scroll.widget() is not self.hint:
                self.scroll.setWidget(self.hint)
                self.hint.show()
        else:
            if self.scroll.widget() is self.hint:  # kept for the next empty list (setWidget deletes)
                self.scroll.takeWidget()
                self.hint.setParent(self)
                self.hint.hide()
            self.editor = ConstraintEditor(self.schema.get(data["kind"], []), data)
            self.editor.changed.connect(lambda changes, n=name: self.changed.emit(n, changes))
            if self.editor.range is not None:
                self.editor.range.set_frame_count(self.frame_count())
                self.editor.range.default_range = lambda: self.default_range()
            self.scroll.setWidget(self.editor)
        self.selected.emit(name if data is not None else "")

    def _item_toggled(self, item: QListWidgetItem) -> None:
        if not self._updating:
            enabled = item.checkState() == Qt.CheckState.Checked
            self.changed.emit(item.data(Qt.ItemDataRole.UserRole), {"enabled": enabled})

    def _remove_selected(self) -> None:
        if name := self.current_name():
            self.removeRequested.emit(name)
