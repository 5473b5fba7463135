"""What one optimizer setting is: its label, help, allowed values and place in the panel.

A settings dataclass declares each field with :func:`setting`, which keeps the field's
:class:`Setting` in its metadata under :data:`META`; :mod:`engine.solver.settings`
generates the checks, the documentation and the panel's fields from it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from engine.validation import Spec

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
