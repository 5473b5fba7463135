"""The studio's tracker set: ``session.sensors``, a sub-model with its own events.

A :class:`SensorSet` is a read-only mapping of joint to frozen
:class:`~engine.sensors.Sensor`, in preset order, plus the edits the studio makes to it.
Every edit (a preset, a tracker's settings, a drag offset, a simulated failure)
replaces the joint's sensor and fires one ``events.changed``
(:class:`~engine.studio.events.SensorsChanged`) that says what changed. It knows nothing
of engines or clips: the :class:`~engine.studio.session.Session` that owns it sends the
new set to its engine, re-emits the event as ``session.events.sensors``, and does the
edits that need the clip (a drag to a world position, a failure from the current frame).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from psygnal import Signal, SignalGroup

from engine import skeleton as sk
from engine.errors import UserError
from engine.sensors import Sensor
from engine.studio.clips import sensor_presets
from engine.studio.events import SensorsChanged


class SensorSetEvents(SignalGroup):
    """``changed``: one :class:`~engine.studio.events.SensorsChanged` per edit."""

    changed = Signal(SensorsChanged)


class SensorSet(Mapping[str, Sensor]):
    """Active trackers by joint, in preset order; see the module doc.

    Attributes
    ----------
    preset : str
        The preset the set is ("" once it was edited into a custom set).
    events : SensorSetEvents
        ``events.changed`` fires after every edit.
    """

    def __init__(self) -> None:
        self._sensors: dict[str, Sensor] = {}
        self.preset = ""
        self.events = SensorSetEvents()

    # -- reading ---------------------------------------------------------------------
    def __getitem__(self, joint: str) -> Sensor:
        return self._sensors[joint]

    def __iter__(self) -> Iterator[str]:
        return iter(self._sensors)

    def __len__(self) -> int:
        return len(self._sensors)

    def __repr__(self) -> str:
        return f"SensorSet({', '.join(self._sensors)}; preset {self.preset!r})"

    @staticmethod
    def presets() -> dict[str, tuple[Sensor, ...]]:
        """The named sensor sets, in the order the studio lists them."""
        return sensor_presets()

    def require(self, joint: str) -> Sensor:
        """The sensor on ``joint``; :class:`UserError` naming the active ones when absent."""
        if joint not in self._sensors:
            raise UserError(f"no sensor on joint {joint!r}; active: {', '.join(self._sensors)}")
        return self._sensors[joint]

    # -- editing ---------------------------------------------------------------------
    def set_preset(self, name: str) -> None:
        presets = sensor_presets()
        if name not in presets:
            raise UserError(f"unknown sensor preset {name!r}; known: {', '.join(presets)}")
        self.set_all(presets[name], name)

    def set_text(self, text: str) -> None:
        """A preset name or a ``--sensors`` list such as ``"root,lwrist:3,rwrist"``."""
        from engine.tracking import parse_sensors

        self.set_all(parse_sensors(text), text if text in sensor_presets() else "")

    def set_all(self, sensors: Sequence[Sensor], preset: str = "") -> None:
        """Replace the whole set (a preset, or an undo of one)."""
        old_set, old_preset = tuple(self._sensors.values()), self.preset
        self._sensors = {s.joint: s for s in sensors}
        self.preset = preset
        self._changed(old_set=old_set, old_preset=old_preset)

    def edit(self, joint: str, **changes: Any) -> None:
        """Change settings of one tracker: ``enabled``, ``dof``, ``weight``, ``offset``,
        ``failures`` (see :class:`~engine.sensors.Sensor`); nothing fires when nothing
        changed."""
        old = self.require(joint)
        new = old.edited(**changes)
        if new == old:
            return
        self._sensors[joint] = new
        self._changed(joint=joint, old=old, new=new)

    def add(self, joint: str, dof: int = 6) -> None:
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        if joint in self._sensors:
            return
        new = Sensor(joint).edited(dof=dof)
        self._sensors[joint] = new
        self.preset = ""
        self._changed(joint=joint, new=new)

    def remove(self, joint: str) -> None:
        old = self.require(joint)
        del self._sensors[joint]
        self.preset = ""
        self._changed(joint=joint, old=old)

    def reset_offsets(self, joint: str | None = None) -> None:
        """Clear drag offsets and simulated failures of ``joint`` (None: every sensor)."""
        if joint is not None:
            self.edit(joint, offset=(0.0, 0.0, 0.0), failures=())
            return
        self.set_all([s.edited(offset=(0.0, 0.0, 0.0), failures=()) for s in self._sensors.values()], self.preset)

    def _changed(self, **change: Any) -> None:
        self.events.changed.emit(SensorsChanged(tuple(self._sensors.values()), self.preset, **change))
