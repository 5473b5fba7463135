"""The sensor: one type for a tracker, wherever it appears in the engine.

A :class:`Sensor` names the joint a tracker sits on and how it is used (degrees of
freedom, weight, whether it is enabled, the studio's drag offset and simulated
failures). Read at a frame, the same type carries the sample: ``position``,
``rotation`` and ``connected``. Presets, ``--sensors`` lists, the studio's sensor
panel, the engine thread and every method pass this one type around; a
:class:`SensorFrame` groups the readings of one frame.

This module sits low in the layering: it imports only numpy and the skeleton.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError

Offset = tuple[float, float, float]


@dataclass(frozen=True)
class Sensor:
    """One tracker on a canonical joint; its settings, and its sample once read.

    Attributes
    ----------
    joint : str
        Canonical joint (``upperneck`` = head, ``lwrist``/``rwrist`` = hands,
        ``lankle``/``rankle`` = feet, ``root`` = hips).
    position : ndarray (3,) or None
        World position read at a frame, metres (Z-up); None for a sensor not read.
    rotation : ndarray (4,) or None
        World rotation read at a frame (w, x, y, z); None for a sensor not read.
    dof : int
        6 (position + rotation) or 3 (position only).
    connected : bool
        False while the tracker is lost; a method must then ignore the sample.
    enabled : bool
        Whether the method receives the tracker at all (studio toggle).
    weight : float
        Relative weight of its loss terms (methods that support it).
    offset : tuple of 3 float
        Drag offset added to the tracked position, metres (world).
    failures : tuple of (int, int)
        Frame windows ``[start, stop)`` in which the tracker is simulated as lost.
    """

    joint: str
    position: np.ndarray | None = None
    rotation: np.ndarray | None = None
    dof: int = 6
    connected: bool = True
    enabled: bool = True
    weight: float = 1.0
    offset: Offset = (0.0, 0.0, 0.0)
    failures: tuple[tuple[int, int], ...] = ()

    def lost_at(self, frame: int) -> bool:
        """Whether a simulated failure covers ``frame``."""
        return any(a <= frame < b for a, b in self.failures)

    def read(self, position: np.ndarray, rotation: np.ndarray, connected: bool = True) -> Sensor:
        """This sensor with a sample: ``position`` (3,) metres, ``rotation`` (4,) wxyz."""
        return dataclasses.replace(self, position=position, rotation=rotation, connected=bool(connected))

    def edited(self, **changes: Any) -> Sensor:
        """A copy with ``changes`` (settings fields) applied and checked.

        Raises
        ------
        UserError
            For an unknown field, a DoF other than 3 or 6, a bad weight or offset.
        """
        known = {f.name for f in dataclasses.fields(self)} - {"joint", "position", "rotation", "connected"}
        for key in changes:
            if key not in known:
                raise UserError(f"sensor {self.joint}: unknown field {key!r}; fields: {', '.join(sorted(known))}")
        out = dict(changes)
        if "dof" in out:
            out["dof"] = int(out["dof"])
            if out["dof"] not in (3, 6):
                raise UserError(f"sensor {self.joint}: field 'dof' must be 3 or 6, got {changes['dof']}")
        if "weight" in out:
            w = float(out["weight"])
            if not np.isfinite(w) or w < 0:
                raise UserError(f"sensor {self.joint}: field 'weight' must be finite and >= 0, got {w}")
            out["weight"] = w
        if "offset" in out:
            off = np.asarray(out["offset"], float).ravel()
            if off.shape != (3,) or not np.all(np.isfinite(off)):
                raise UserError(f"sensor {self.joint}: field 'offset' needs 3 finite numbers (metres)")
            out["offset"] = (float(off[0]), float(off[1]), float(off[2]))
        if "failures" in out:
            out["failures"] = tuple((int(a), int(b)) for a, b in out["failures"])
        if "enabled" in out:
            out["enabled"] = bool(out["enabled"])
        return dataclasses.replace(self, **out)

    def to_dict(self) -> dict[str, Any]:
        """Plain-JSON settings (no sample): what a scene file stores."""
        return {
            "joint": self.joint,
            "dof": self.dof,
            "enabled": self.enabled,
            "weight": self.weight,
            "offset": list(self.offset),
            "failures": [list(w) for w in self.failures],
        }

    @classmethod
    def from_dict(cls, data: Any, where: str = "sensor") -> Sensor:
        """Inverse of :meth:`to_dict`; errors name ``where`` and the field."""
        if not isinstance(data, dict) or "joint" not in data:
            raise UserError(f"{where}: expected an object with a 'joint' field")
        joint = data["joint"]
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"{where}: field 'joint': unknown joint {joint!r}")
        try:
            return cls(joint).edited(**{k: v for k, v in data.items() if k != "joint"})
        except (TypeError, ValueError, UserError) as exc:
            raise UserError(f"{where}: {exc}") from exc


@dataclass(frozen=True)
class SensorFrame:
    """All sensor readings of one frame, keyed by joint name (read :class:`Sensor` s)."""

    frame: int
    readings: dict[str, Sensor]

    def connected(self) -> dict[str, Sensor]:
        return {k: r for k, r in self.readings.items() if r.connected}
