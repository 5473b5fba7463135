"""The studio's Qt-free model: what is loaded, which sensors and constraints are active.

A :class:`Session` lives on the GUI thread. Views read its attributes and change it only
through its methods; every change is announced to subscribers (``callback(event, data)``)
and, when a worker is attached, forwarded to the engine thread as a plain command
(:mod:`engine.worker`). The engine thread never touches the session: it works on copies
carried by the commands, so no lock is needed.

Events
------
``"motion"`` (new clip loaded), ``"sensors"`` (preset, toggle, dof, weight, failure,
offset), ``"constraints"`` (list or one constraint changed), ``"settings"`` (optimizer
parameter), ``"frame"`` (current frame), ``"playing"``, ``"method"``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.motion import Motion
from engine.session_sources import (  # noqa: F401  (re-exported)
    FALLBACK_PRESETS, _preset_dofs, load_clip, sensor_presets,
)

Callback = Callable[[str, Any], None]

@dataclass(frozen=True)
class SensorConfig:
    """How one tracker is used: an immutable value passed to the engine thread.

    Attributes
    ----------
    joint : str
        Canonical joint the tracker is attached to.
    enabled : bool
        Whether the method receives it at all.
    dof : int
        6 (position + rotation) or 3 (position only).
    weight : float
        Relative weight of its loss terms (methods that support it).
    failures : tuple of (int, int)
        Frame windows ``[start, stop)`` where the tracker is simulated as lost.
    offset : tuple of float
        Drag offset added to the tracked position, metres (world).
    """

    joint: str
    enabled: bool = True
    dof: int = 6
    weight: float = 1.0
    failures: tuple[tuple[int, int], ...] = ()
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def lost_at(self, frame: int) -> bool:
        return any(a <= frame < b for a, b in self.failures)


def default_settings() -> dict[str, Any]:
    """The optimizer's own defaults (one source of truth: ``OptimizerSettings``)."""
    from engine.optimizer import OptimizerSettings

    d = OptimizerSettings()
    return {"mode": d.mode, "iterations": d.iterations, "lr": d.lr, "temporal_weight": d.temporal_weight}


@dataclass
class Session:
    """Everything the studio shows and edits; see the module docstring.

    Attributes
    ----------
    motion : Motion or None
        Ground-truth clip the sensors are simulated from.
    sensors : dict of str to SensorConfig
        Active preset's trackers, by joint, in preset order.
    constraints : list
        :class:`engine.constraints.base.Constraint` objects the optimizer adds to the sensors.
    settings : dict
        Optimizer parameters by name (``mode``, ``iterations``, ``lr``, ``temporal_weight``...).
    method : str
        Reconstruction method name; ``ghosts`` are other methods drawn alongside it.
    frame : int
        Current frame (the engine's, mirrored by :meth:`note_frame`).
    """

    motion: Motion | None = None
    path: Path | None = None
    preset: str = ""
    sensors: dict[str, SensorConfig] = field(default_factory=dict)
    constraints: list[Any] = field(default_factory=list)
    settings: dict[str, Any] = field(default_factory=lambda: default_settings())
    method: str = "ik"
    ghosts: tuple[str, ...] = ()
    frame: int = 0
    playing: bool = False
    speed: float = 1.0
    loop: bool = True
    sink: Callable[[Any], None] | None = None
    _subscribers: list[Callback] = field(default_factory=list, repr=False)

    # -- observers -------------------------------------------------------------------

    def subscribe(self, callback: Callback) -> Callable[[], None]:
        """Call ``callback(event, data)`` on every change; returns the unsubscriber."""
        self._subscribers.append(callback)
        return lambda: self.unsubscribe(callback)

    def unsubscribe(self, callback: Callback) -> None:
        if callback in self._subscribers:
            self._subscribers.remove(callback)

    def _emit(self, event: str, data: Any = None, command: Any = None) -> None:
        if command is not None and self.sink is not None:
            self.sink(command)
        for cb in list(self._subscribers):
            cb(event, data)

    def attach(self, sink: Callable[[Any], None] | None) -> None:
        """Forward every change to ``sink`` (the worker's ``submit``) and sync it now."""
        self.sink = sink
        if sink is None:
            return
        from engine import worker as w

        sink(w.SetMethod(self.method, self.ghosts))
        sink(w.SetSettings(dict(self.settings)))
        if self.motion is not None:
            sink(w.SetMotion(self.motion))
        sink(w.SetSensors(tuple(self.sensors.values())))
        sink(w.SetConstraints(tuple(c.to_dict() for c in self.constraints)))
        sink(w.Seek(self.frame))

    # -- clip ------------------------------------------------------------------------

    @property
    def num_frames(self) -> int:
        return 0 if self.motion is None else len(self.motion)

    def open(self, path: str | Path) -> None:
        """Load a BVH; on failure raise :class:`UserError` and leave the session as it was."""
        motion = load_clip(path)
        self.set_motion(motion, Path(path))

    def set_motion(self, motion: Motion, path: Path | None = None) -> None:
        from engine import worker as w

        self.motion, self.path, self.frame = motion, path, 0
        self._emit("motion", motion, w.SetMotion(motion))
        self._emit("frame", 0, w.Seek(0))
        if not self.sensors:
            self.set_preset(next(iter(sensor_presets())))

    # -- sensors ---------------------------------------------------------------------

    def set_preset(self, name: str) -> None:
        presets = sensor_presets()
        if name not in presets:
            raise UserError(f"unknown sensor preset {name!r}; known: {', '.join(presets)}")
        self.preset = name
        dofs = _preset_dofs(name)
        self.sensors = {j: SensorConfig(j, dof=dofs.get(j, 6)) for j in presets[name]}
        self._sensors_changed()

    def set_sensor_text(self, text: str) -> None:
        """A preset name or a ``--sensors`` list such as ``"root,lwrist:3,rwrist"``."""
        if text in sensor_presets():
            self.set_preset(text)
            return
        try:
            from engine.tracking import parse_sensors  # type: ignore[attr-defined]
        except ImportError as exc:
            raise UserError(f"unknown sensor preset {text!r}") from exc
        specs = parse_sensors(text)
        self.preset = ""
        self.sensors = {sp.joint: SensorConfig(sp.joint, dof=int(sp.dof)) for sp in specs}
        self._sensors_changed()

    def update_sensor(self, joint: str, **changes: Any) -> None:
        """Change fields of one tracker (``enabled``, ``dof``, ``weight``, ``offset``...)."""
        if joint not in self.sensors:
            raise UserError(f"no sensor on joint {joint!r}; active: {', '.join(self.sensors)}")
        if "offset" in changes:
            changes["offset"] = tuple(float(v) for v in changes["offset"])
        if "dof" in changes and changes["dof"] not in (3, 6):
            raise UserError(f"sensor {joint}: dof must be 3 or 6, got {changes['dof']}")
        self.sensors[joint] = dataclasses.replace(self.sensors[joint], **changes)
        self._sensors_changed()

    def add_sensor(self, joint: str) -> None:
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        self.sensors.setdefault(joint, SensorConfig(joint))
        self._sensors_changed()

    def simulate_failure(self, joint: str, frames: int, start: int | None = None) -> None:
        """Make ``joint``'s tracker lost for ``frames`` frames from ``start`` (default: now)."""
        start = self.frame if start is None else int(start)
        cfg = self.sensors[joint]
        self.update_sensor(joint, failures=cfg.failures + ((start, start + int(frames)),))

    def drag_target(self, joint: str, world_pos: np.ndarray) -> None:
        """Move a tracker's target to ``world_pos`` (metres) by setting its drag offset."""
        base = self.tracked_position(joint, self.frame)
        self.update_sensor(joint, offset=np.asarray(world_pos, float) - base)

    def reset_offsets(self, joint: str | None = None) -> None:
        for j in [joint] if joint else list(self.sensors):
            self.sensors[j] = dataclasses.replace(self.sensors[j], offset=(0.0, 0.0, 0.0), failures=())
        self._sensors_changed()

    def tracked_position(self, joint: str, frame: int) -> np.ndarray:
        """Ground-truth position (3,) of ``joint`` at ``frame``, before any drag offset."""
        if self.motion is None:
            return np.zeros(3)
        frame = int(np.clip(frame, 0, len(self.motion) - 1))
        m = self.motion.slice(frame, frame + 1)
        return m.positions()[0, sk.JOINT_INDEX[joint]]

    def _sensors_changed(self) -> None:
        from engine import worker as w

        self._emit("sensors", self.sensors, w.SetSensors(tuple(self.sensors.values())))

    # -- constraints -----------------------------------------------------------------

    def add_constraint(self, constraint: Any) -> None:
        names = {c.name for c in self.constraints}
        if not constraint.name or constraint.name in names:
            base = constraint.name or constraint.kind
            i = 1
            while f"{base}{i}" in names:
                i += 1
            constraint.name = f"{base}{i}"
        self.constraints.append(constraint)
        self._constraints_changed()

    def remove_constraint(self, name: str) -> None:
        self.constraints = [c for c in self.constraints if c.name != name]
        self._constraints_changed()

    def update_constraint(self, name: str, **changes: Any) -> None:
        """Set fields (``weight``, ``enabled`` or any parameter) of the named constraint."""
        for c in self.constraints:
            if c.name == name:
                for k, v in changes.items():
                    if not hasattr(c, k):
                        raise UserError(f"constraint {name!r} ({c.kind}) has no field {k!r}")
                    setattr(c, k, np.asarray(v, float) if isinstance(getattr(c, k), np.ndarray) else v)
                self._constraints_changed()
                return
        raise UserError(f"no constraint named {name!r}")

    def _constraints_changed(self) -> None:
        from engine import worker as w

        cmd = w.SetConstraints(tuple(c.to_dict() for c in self.constraints))
        self._emit("constraints", self.constraints, cmd)

    # -- optimizer, method, playback -------------------------------------------------

    def set_setting(self, name: str, value: Any) -> None:
        from engine import worker as w

        self.settings[name] = value
        self._emit("settings", dict(self.settings), w.SetSettings({name: value}))

    def set_method(self, name: str, ghosts: tuple[str, ...] | None = None) -> None:
        from engine import worker as w

        self.method = name
        if ghosts is not None:
            self.ghosts = tuple(g for g in ghosts if g != name)
        self._emit("method", name, w.SetMethod(name, self.ghosts))

    def seek(self, frame: int) -> None:
        from engine import worker as w

        frame = int(np.clip(frame, 0, max(self.num_frames - 1, 0)))
        self.frame = frame
        self._emit("frame", frame, w.Seek(frame))

    def note_frame(self, frame: int) -> None:
        """Mirror the engine's frame while playing (no command is sent back)."""
        if frame != self.frame:
            self.frame = frame
            self._emit("frame", frame)

    def step(self, delta: int = 1) -> None:
        self.pause()
        self.seek(self.frame + delta)

    def play(self) -> None:
        from engine import worker as w

        self.playing = True
        self._emit("playing", True, w.Play(self.speed, self.loop))

    def pause(self) -> None:
        from engine import worker as w

        if self.playing:
            self.playing = False
            self._emit("playing", False, w.Pause())

    def set_playback(self, speed: float | None = None, loop: bool | None = None) -> None:
        self.speed = self.speed if speed is None else float(speed)
        self.loop = self.loop if loop is None else bool(loop)
        if self.playing:
            self.play()

    # -- scenes ----------------------------------------------------------------------

    def to_scene(self) -> dict[str, Any]:
        """Plain-JSON description of the sensors, constraints and settings."""
        return {
            "clip": str(self.path) if self.path else None,
            "method": self.method,
            "preset": self.preset,
            "sensors": [dataclasses.asdict(s) for s in self.sensors.values()],
            "constraints": [c.to_dict() for c in self.constraints],
            "settings": dict(self.settings),
            "frame": self.frame,
        }

    def apply_scene(self, scene: dict[str, Any]) -> None:
        """Restore :meth:`to_scene` output (the clip is loaded by the caller)."""
        from engine.constraints.base import from_dict

        try:
            sensors = {
                s["joint"]: SensorConfig(
                    s["joint"], bool(s.get("enabled", True)), int(s.get("dof", 6)),
                    float(s.get("weight", 1.0)),
                    tuple(tuple(int(v) for v in w) for w in s.get("failures", ())),
                    tuple(float(v) for v in s.get("offset", (0, 0, 0))),
                )  # fmt: skip
                for s in scene.get("sensors", [])
            }
        except (KeyError, TypeError, ValueError) as exc:
            raise UserError(f"scene: bad sensor entry ({exc})") from exc
        constraints = [from_dict(dict(c)) for c in scene.get("constraints", [])]
        self.preset = scene.get("preset", self.preset)
        self.sensors = sensors
        self.constraints = constraints
        self.settings.update(scene.get("settings", {}))
        self._emit("settings", dict(self.settings), _settings_cmd(self.settings))
        self._sensors_changed()
        self._constraints_changed()
        if scene.get("method") and scene["method"] != self.method:
            self.set_method(scene["method"])
        self.seek(int(scene.get("frame", 0)))


def _settings_cmd(settings: dict[str, Any]) -> Any:
    from engine import worker as w

    return w.SetSettings(dict(settings))
