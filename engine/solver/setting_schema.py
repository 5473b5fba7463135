"""What one optimizer setting is: its label, help, allowed values and place in the panel.

A settings dataclass declares each field with :func:`setting`, which keeps the field's
:class:`Setting` in its metadata under :data:`META`; :mod:`engine.solver.settings`
generates the checks, the documentation and the panel's fields from it; the generic part
of that (reading the fields' settings, the documentation's table and attribute list) is here.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from engine.validation import Choice, Spec

#: Key of a field's :class:`Setting` in its ``dataclasses.field`` metadata.
META = "setting"


@dataclass(frozen=True)
class Setting:
    """What one optimizer setting is, for every place that shows or checks it.

    Attributes
    ----------
    label : str
        Short name for a form ("Adam learning rate").
    help : str
        One or two sentences: what it does, in which units (also the panel's tooltip).
    spec : Num, Choice or Flag
        The allowed values (:mod:`engine.validation`); a number's unit is ``spec.unit``.
    panel : bool
        Shown in the studio's optimizer panel.
    step : float
        The panel's spin-box step (numbers only).
    offered : tuple of str
        Values the panel's list offers when not all of ``spec.options`` (a joint name).
    """

    label: str
    help: str
    spec: Spec
    panel: bool = False
    step: float = 0.0
    offered: tuple[str, ...] = ()


def setting(default: Any, label: str, help: str, spec: Spec, **kw: Any) -> Any:
    """A dataclass field with ``default`` and its :class:`Setting` as metadata."""
    return dataclasses.field(default=default, metadata={META: Setting(label, help, spec, **kw)})


def settings_of(cls: type) -> Iterator[tuple[dataclasses.Field, Setting]]:
    """Every field of the settings dataclass ``cls`` with its :class:`Setting`, in order.

    Raises
    ------
    TypeError
        For a field declared without :func:`setting` (so nothing could check or show it).
    """
    for f in dataclasses.fields(cls):
        info = f.metadata.get(META)
        if not isinstance(info, Setting):
            raise TypeError(f"{cls.__name__}.{f.name}: declare it with setting(default, label, help, spec)")
        yield f, info


def _default_text(f: dataclasses.Field) -> str:
    d = f.default
    return str(d).lower() if isinstance(d, bool) else f"{d:g}" if isinstance(d, float) else str(d)


def _allowed_text(info: Setting) -> str:
    spec = info.spec
    if isinstance(spec, Choice) and not spec.summary:
        return ", ".join(f"`{v}`" for v in spec.options)
    return spec.describe()


def settings_table(cls: type) -> str:
    """A Markdown table of ``cls``'s settings (name, default, allowed, meaning)."""
    rows = ["| name | default | allowed | meaning |", "|---|---|---|---|"]
    rows += [
        f"| `{f.name}` | {_default_text(f)} | {_allowed_text(info)} | {info.help} |" for f, info in settings_of(cls)
    ]
    return "\n".join(rows) + "\n"


def attributes_doc(cls: type) -> str:
    """The numpydoc ``Attributes`` section of ``cls``'s settings (appended to its docstring)."""
    lines = ["", "    Attributes", "    ----------"]
    for f, info in settings_of(cls):
        lines += [
            f"    {f.name} : {f.type}",
            f"        {info.help} Default {_default_text(f)}; {info.spec.describe()}.",
        ]
    return "\n".join(lines) + "\n"
