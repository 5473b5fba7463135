"""Some optimizer settings by name, each checked against its setting: a partial edit.

:func:`check_values` checks and converts a mapping of settings (a sensor-set profile's);
:class:`SettingsEdit` is such a mapping, checked when made and never changed after: what
the studio sets explicitly and publishes to the engine.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

from engine.errors import UserError
from engine.solver.settings import SETTINGS
from engine.validation import check_value, shown


def check_values(values: Mapping[str, Any], where: str = "optimizer settings") -> dict[str, Any]:
    """Some settings by name, each checked and converted by its
    :class:`~engine.solver.setting_schema.Setting` (for a partial edit; a whole
    :class:`~engine.solver.settings.OptimizerSettings` checks itself).

    Raises
    ------
    UserError
        One line naming ``where`` and the unknown or bad field (with its range).
    """
    unknown = sorted(set(values) - set(SETTINGS))
    if unknown:
        raise UserError(f"{where}: unknown setting(s) {', '.join(map(shown, unknown))}; known: {', '.join(SETTINGS)}")
    return {k: check_value(SETTINGS[k], v, where, k) for k, v in values.items()}


class SettingsEdit(Mapping[str, Any]):
    """Some optimizer settings by name, checked when made and never changed after: what
    the studio sets explicitly (the others stay to the method's profile) and publishes to
    the engine. ``a | b`` is ``a`` with ``b``'s values; ``dict(edit)`` the plain form.

    Raises
    ------
    UserError
        On construction, naming ``where`` and the unknown or bad field (one line).
    """

    def __init__(self, values: Mapping[str, Any] | None = None, where: str = "optimizer settings") -> None:
        self._values = check_values(dict(values or {}), where)

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __or__(self, other: Mapping[str, Any]) -> SettingsEdit:
        merged = SettingsEdit()
        merged._values = {**self._values, **(other._values if isinstance(other, SettingsEdit) else check_values(other))}
        return merged

    def __repr__(self) -> str:
        return f"SettingsEdit({self._values!r})"
