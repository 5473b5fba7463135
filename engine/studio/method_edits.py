"""How the engine thread builds methods and pushes the studio's edits into them.

Methods differ in what they accept (DragPoser takes constraints and optimizer settings,
classical IK takes neither): each edit goes through :mod:`engine.methods.driver`, which
applies it where the method offers the matching capability. The functions here return
readable problems instead of raising, and the engine thread reports them in its
snapshots.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from engine.constraints.base import Constraint
from engine.methods import driver, get_method
from engine.methods.base import Method
from engine.sensors import Sensor

#: Factory options of the studio's methods. The studio shows its first frame and then
#: waits for the user, so DragPoser leaves the pose bank's tables and combinations that
#: frame does not use (about 1.3 CPU s) until after it.
STUDIO_OPTIONS: dict[str, dict[str, Any]] = {"dragposer": {"prepare_bank": False}}


def make_method(name: str) -> Method:
    """The registered method ``name`` (:func:`engine.methods.get_method`) with the
    studio's options (:data:`STUDIO_OPTIONS`)."""
    return get_method(name, **STUDIO_OPTIONS.get(name, {}))


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
