"""How the engine thread builds methods and pushes the studio's edits into them.

Methods differ in what they accept (DragPoser takes constraints and optimizer settings,
classical IK takes neither), so each edit is applied only where the method offers the
matching hook; the functions return readable problems instead of raising, and the
engine thread reports them in its snapshots.
"""

from __future__ import annotations

import copy
import dataclasses
import time
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods import get_method
from engine.methods.base import FrameResult, Method
from engine.motion import Motion
from engine.sensors import Sensor, SensorFrame
from engine.studio.source import ClipSource


def make_method(name: str) -> Method:
    """The registered method ``name`` (:func:`engine.methods.get_method`)."""
    return get_method(name)


def apply_settings(method: Method, values: dict[str, Any]) -> list[str]:
    """Set optimizer parameters on ``method.settings`` (a dataclass) or ``configure()``."""
    if not values:
        return []
    configure = getattr(method, "configure", None)
    if callable(configure):
        try:
            configure(**values)
        except Exception as exc:
            return [f"{method.name}: settings rejected ({exc})"]
        return []
    settings = getattr(method, "settings", None)
    if settings is None:
        return []
    known = {f.name for f in dataclasses.fields(settings)} if dataclasses.is_dataclass(settings) else set()
    for key, value in values.items():
        if key in known:
            setattr(settings, key, value)
    return []


def apply_constraints(method: Method, constraints: tuple[Any, ...]) -> list[str]:
    """Give ``method`` the session's constraint objects (shared, never copied: the
    session replaces an object instead of editing it, see :mod:`engine.studio.commands`)."""
    setter = getattr(method, "set_constraints", None)
    add = getattr(method, "add_constraint", None)
    if setter is None and add is None:
        return [f"{method.name} ignores constraints"] if constraints else []
    problems, objs = [], list(constraints)
    try:
        if setter is not None:
            setter(objs)
        else:
            for c in list(getattr(method, "constraints", [])):
                method.remove_constraint(c.name)  # type: ignore[attr-defined]
            for c in objs:
                add(c)
    except Exception as exc:
        problems.append(f"{method.name}: constraints rejected ({exc})")
    return problems


def apply_sensor_weights(method: Method, sensors: tuple) -> list[str]:
    """Pass per-sensor weights to methods that weight their tracker terms."""
    setter = getattr(method, "set_sensor_weight", None)
    if setter is None:
        return []
    try:
        for s in sensors:
            setter(s.joint, float(s.weight))
    except Exception as exc:
        return [f"{method.name}: sensor weights rejected ({exc})"]
    return []


class RestPoseMethod(Method):
    """Placeholder: the rest pose carried by the hip (or head) tracker.

    Only used when :mod:`engine.methods` has no registry yet, so the studio runs end to
    end. Its loss terms are the squared position errors of every connected tracker.
    """

    name = "rest"

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS) -> None:
        self._offsets = skeleton.offsets
        self._rest = skeleton.rest_positions()
        self._root = np.array([0.0, 0.0, -self._rest[:, 2].min() + 0.05])
        self._rot = np.array([1.0, 0.0, 0.0, 0.0])

    def step(self, sensors: SensorFrame) -> FrameResult:
        t0 = time.perf_counter()
        conn = sensors.connected()
        if "root" in conn:
            self._root = np.asarray(conn["root"].position, float)
            if conn["root"].dof == 6:
                self._rot = np.asarray(conn["root"].rotation, float)
        elif "upperneck" in conn:
            head = self._rest[sk.JOINT_INDEX["upperneck"]]
            self._root = np.asarray(conn["upperneck"].position, float) - Q.rotate(self._rot, head)
        local = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (sk.NUM_JOINTS, 1))
        local[0] = self._rot
        pos, _ = fk(local, self._root, self._offsets)
        losses = {f"pos:{j}": float(np.sum((pos[sk.JOINT_INDEX[j]] - r.position) ** 2)) for j, r in conn.items()}
        losses["total"] = float(sum(losses.values()))
        return FrameResult(local, self._root.copy(), pos, 1, [losses], None, (time.perf_counter() - t0) * 1e3)


def reconstruct_clip(motion: Motion, sensors: tuple[Sensor, ...], constraints: tuple[Any, ...], settings: dict[str, Any],
                     method_name: str, factory: Any = None,
                     progress: Any = None) -> Any:  # fmt: skip
    """Run a fresh method over every frame of ``motion`` with the studio's sensor edits.

    Returns the reconstruction as a :class:`engine.motion.Motion` (same skeleton and fps).
    ``progress(frame)`` is called after each frame and may return True to cancel.
    """
    source = ClipSource(motion)
    source.set_sensors(tuple(sensors))
    constraints = copy.deepcopy(tuple(constraints))  # a separate run: its own pin captures
    method = (factory or make_method)(method_name)
    method.reset(motion.skeleton, motion.fps)
    apply_settings(method, settings)
    apply_constraints(method, constraints)
    apply_sensor_weights(method, source.sensors)
    rots, roots = [], []
    for f in range(len(motion)):
        res = method.step(source.frame(f))
        rots.append(np.asarray(res.local_rot, float))
        roots.append(np.asarray(res.root_pos, float))
        if progress is not None and progress(f):
            break
    return Motion(np.array(rots), np.array(roots), motion.skeleton, motion.fps, f"{motion.name} ({method_name})")
