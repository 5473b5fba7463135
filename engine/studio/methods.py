"""How the engine thread builds methods and pushes the studio's edits into them.

Methods differ in what they accept (DragPoser takes constraints and optimizer settings,
classical IK takes neither): each edit goes through :mod:`engine.methods.driver`, which
applies it where the method offers the matching capability. The functions here return
readable problems instead of raising, and the engine thread reports them in its
snapshots.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from engine.constraints.base import Constraint
from engine.methods import driver, get_method
from engine.methods.base import Method
from engine.motion import Motion
from engine.sensors import Sensor
from engine.studio.source import ClipSource


def make_method(name: str) -> Method:
    """The registered method ``name`` (:func:`engine.methods.get_method`)."""
    return get_method(name)


def apply_settings(method: Method, values: Mapping[str, Any]) -> list[str]:
    """Give ``method`` optimizer settings by name; methods without settings skip them."""
    try:
        driver.configure(method, values)
    except Exception as exc:
        return [f"{method.name}: settings rejected ({exc})"]
    return []


def apply_constraints(method: Method, constraints: tuple[Constraint, ...]) -> list[str]:
    """Give ``method`` the session's constraint objects (shared, never copied: the
    session replaces an object instead of editing it, see :mod:`engine.studio.commands`)."""
    try:
        taken = driver.set_constraints(method, constraints)
    except Exception as exc:
        return [f"{method.name}: constraints rejected ({exc})"]
    return [] if taken or not constraints else [f"{method.name} ignores constraints"]


def apply_sensor_weights(method: Method, sensors: tuple[Sensor, ...]) -> list[str]:
    """Pass per-sensor weights to methods that weight their tracker terms."""
    try:
        driver.set_sensor_weights(method, sensors)
    except Exception as exc:
        return [f"{method.name}: sensor weights rejected ({exc})"]
    return []


def reconstruct_clip(motion: Motion, sensors: tuple[Sensor, ...], constraints: tuple[Constraint, ...],
                     settings: Mapping[str, Any], method_name: str, factory: Callable[[str], Method] | None = None,
                     progress: Callable[[int], bool | None] | None = None) -> Motion:  # fmt: skip
    """Run a fresh method over every frame of ``motion`` with the studio's sensor edits.

    ``motion`` is the ground truth of a method that needs one (the autoencoder).
    Returns the reconstruction as a :class:`engine.motion.Motion` (same skeleton and fps).
    ``progress(frame)`` is called after each frame and may return True to cancel.

    Raises
    ------
    UserError, FloatingPointError
        Settings the method rejects; a non-finite pose.
    """
    source = ClipSource(motion)
    source.set_sensors(tuple(sensors))
    constraints = copy.deepcopy(tuple(constraints))  # a separate run: its own pin captures
    method = (factory or make_method)(method_name)
    driver.start(method, motion.skeleton, motion.fps, reference=motion, settings=settings,
                 constraints=constraints, sensors=source.sensors)  # fmt: skip
    rots, roots = [], []
    for f in range(len(motion)):
        res = driver.step(method, source.frame(f))
        rots.append(np.asarray(res.local_rot, float))
        roots.append(np.asarray(res.root_pos, float))
        if progress is not None and progress(f):
            break
    return Motion(np.array(rots), np.array(roots), motion.skeleton, motion.fps, f"{motion.name} ({method_name})")
