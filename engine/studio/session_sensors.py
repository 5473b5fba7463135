"""Editing the studio's tracker set: the sensor half of :class:`~engine.studio.session.Session`.

Sensors are frozen :class:`~engine.sensors.Sensor` s: every edit (a preset, a drag of a
target, a simulated tracker failure) replaces the joint's sensor, sends the whole new
set to the engine and fires one ``sensors`` event that says what changed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.motion.clip import Motion
from engine.sensors import Sensor
from engine.studio import commands as cmd
from engine.studio import events as ev
from engine.studio.clips import sensor_presets
from engine.studio.snapshot import Snapshot


class SensorEditing:
    """Sensor methods of the session. The class using it provides ``sensors`` (dict of
    joint to :class:`~engine.sensors.Sensor`, in preset order), ``preset``, ``frame``,
    ``motion``, ``source``, ``latest`` (the engine's newest snapshot), ``events`` (with a
    ``sensors`` signal) and ``_send(command)``."""

    sensors: dict[str, Sensor]
    preset: str
    frame: int
    motion: Motion | None
    source: Any
    events: Any

    @property
    def latest(self) -> Snapshot | None:  # pragma: no cover - provided by Session
        raise NotImplementedError

    def _send(self, command: Any) -> None:  # pragma: no cover - provided by Session
        raise NotImplementedError

    @staticmethod
    def sensor_presets() -> dict[str, tuple[Sensor, ...]]:
        return sensor_presets()

    def set_preset(self, name: str) -> None:
        presets = sensor_presets()
        if name not in presets:
            raise UserError(f"unknown sensor preset {name!r}; known: {', '.join(presets)}")
        self.set_sensors(presets[name], name)

    def set_sensor_text(self, text: str) -> None:
        """A preset name or a ``--sensors`` list such as ``"root,lwrist:3,rwrist"``."""
        from engine.tracking import parse_sensors

        self.set_sensors(parse_sensors(text), text if text in sensor_presets() else "")

    def set_sensors(self, sensors: tuple[Sensor, ...] | list[Sensor], preset: str = "") -> None:
        """Replace the whole sensor set (a preset, or an undo of one)."""
        old_set, old_preset = tuple(self.sensors.values()), self.preset
        self.sensors = {s.joint: s for s in sensors}
        self.preset = preset
        self._sensors_changed(old_set=old_set, old_preset=old_preset)

    def update_sensor(self, joint: str, **changes: Any) -> None:
        """Change settings of one tracker: ``enabled``, ``dof``, ``weight``, ``offset``,
        ``failures`` (see :class:`~engine.sensors.Sensor`)."""
        old = self.sensor(joint)
        new = old.edited(**changes)
        if new == old:
            return
        self.sensors[joint] = new
        self._sensors_changed(joint=joint, old=old, new=new)

    def add_sensor(self, joint: str, dof: int = 6) -> None:
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        if joint in self.sensors:
            return
        new = Sensor(joint).edited(dof=dof)
        self.sensors[joint] = new
        self.preset = ""
        self._sensors_changed(joint=joint, new=new)

    def remove_sensor(self, joint: str) -> None:
        old = self.sensor(joint)
        del self.sensors[joint]
        self.preset = ""
        self._sensors_changed(joint=joint, old=old)

    def sensor(self, joint: str) -> Sensor:
        if joint not in self.sensors:
            raise UserError(f"no sensor on joint {joint!r}; active: {', '.join(self.sensors)}")
        return self.sensors[joint]

    def simulate_failure(self, joint: str, frames: int, start: int | None = None) -> None:
        """Make ``joint``'s tracker lost for ``frames`` frames from ``start`` (default: now)."""
        start = self.frame if start is None else int(start)
        cfg = self.sensor(joint)
        self.update_sensor(joint, failures=cfg.failures + ((start, start + int(frames)),))

    def drag_target(self, joint: str, world_pos: np.ndarray) -> None:
        """Move a tracker's target to ``world_pos`` (metres) by setting its drag offset."""
        base = self.tracked_position(joint, self.frame)
        self.update_sensor(joint, offset=np.asarray(world_pos, float) - base)

    def reset_offsets(self, joint: str | None = None) -> None:
        """Clear drag offsets and simulated failures of ``joint`` (None: every sensor)."""
        if joint is not None:
            self.update_sensor(joint, offset=(0.0, 0.0, 0.0), failures=())
            return
        cleared = [s.edited(offset=(0.0, 0.0, 0.0), failures=()) for s in self.sensors.values()]
        self.set_sensors(cleared, self.preset)

    def tracked_position(self, joint: str, frame: int) -> np.ndarray:
        """Ground-truth position (3,) of ``joint`` at ``frame``, before any drag offset.

        Read from the engine's newest snapshot when it shows ``frame`` (no kinematics on
        the caller's thread); otherwise from the clip's forward kinematics of that frame.
        """
        snap = self.latest
        j = sk.JOINT_INDEX[joint]
        if snap is not None and snap.frame == frame and np.all(np.isfinite(snap.ground_truth[j])):
            return np.array(snap.ground_truth[j])
        if self.source is not None:  # no ground truth: the tracker's own reading
            r = self.source.frame(frame).readings.get(joint)
            if r is None:
                return np.zeros(3)
            return np.asarray(r.position, float) - np.asarray(self.sensors[joint].offset if joint in self.sensors else 0.0)
        if self.motion is None:
            return np.zeros(3)
        frame = int(np.clip(frame, 0, len(self.motion) - 1))
        return self.motion.slice(frame, frame + 1).positions()[0, j]

    def _sensors_changed(self, **change: Any) -> None:
        sensors = tuple(self.sensors.values())
        self._send(cmd.SetSensors(sensors))
        self.events.sensors.emit(ev.SensorsChanged(sensors, self.preset, **change))
