"""How every caller runs a reconstruction method: reset, configure, step, check.

``evaluate``, ``reconstruct``, ``bench``, ``live``, the studio's engine thread and its
export all drive a :class:`~engine.methods.base.Method` the same way, through these
functions:

1. :func:`reset` for a clip, with the ground-truth clip when the method
   :attr:`~engine.methods.base.Method.needs_ground_truth`;
2. :func:`configure`, :func:`set_constraints` and :func:`set_sensor_weights`, which hand
   the edits to the methods that offer the matching capability
   (:class:`~engine.methods.base.Configurable`, ...) and say whether it did;
3. :func:`step` per frame, with the frame's deadline when the method
   :attr:`~engine.methods.base.Method.takes_deadline`, raising on a non-finite pose (or
   :func:`solve_clip` for the whole clip, when the method can).

:func:`start` is steps 1 and 2 together.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.methods.base import Configurable, Constrainable, FrameResult, Method, SensorWeighted, SolvesClips
from engine.sensors import Sensor, SensorFrame

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.motion.clip import Motion


def reset(method: Method, skeleton: sk.Skeleton, fps: float, reference: Motion | None = None) -> None:
    """Start a clip: ``method.reset(skeleton, fps)``, plus ``reference=`` for a method that
    needs the ground truth.

    Raises
    ------
    UserError
        When the method needs the ground-truth clip and ``reference`` is None (live
        trackers have none).
    """
    if method.needs_ground_truth:
        if reference is None:
            raise UserError(f"method {method.name!r} needs the ground-truth clip")
        method.reset(skeleton, fps, reference=reference)
    else:
        method.reset(skeleton, fps)


def configure(method: Method, values: Mapping[str, Any]) -> bool:
    """Give a :class:`Configurable` method optimizer settings by name; False (nothing
    done) for a method without settings. The method's own errors propagate."""
    if not isinstance(method, Configurable):
        return False
    if values:
        method.configure(**values)
    return True


def set_constraints(method: Method, constraints: Iterable[Constraint]) -> bool:
    """Give a :class:`Constrainable` method the user's constraints (shared, not copied);
    False for a method that takes none. The method's own errors propagate."""
    if not isinstance(method, Constrainable):
        return False
    method.set_constraints(list(constraints))
    return True


def set_sensor_weights(method: Method, sensors: Iterable[Sensor]) -> bool:
    """Give a :class:`SensorWeighted` method each sensor's ``weight``; False for a method
    that weights no tracker. The method's own errors propagate."""
    if not isinstance(method, SensorWeighted):
        return False
    for s in sensors:
        method.set_sensor_weight(s.joint, float(s.weight))
    return True


def start(
    method: Method,
    skeleton: sk.Skeleton,
    fps: float,
    *,
    reference: Motion | None = None,
    settings: Mapping[str, Any] | None = None,
    constraints: Sequence[Constraint] = (),
    sensors: Iterable[Sensor] = (),
) -> list[str]:
    """:func:`reset`, then the settings, constraints and sensor weights.

    Returns
    -------
    list of str
        What the method ignored (constraints given to a method that takes none, settings
        to one without settings), one readable line each.
    """
    reset(method, skeleton, fps, reference)
    ignored = []
    if settings and not configure(method, settings):
        ignored.append(f"{method.name} has no optimizer settings")
    if not set_constraints(method, constraints) and constraints:
        ignored.append(f"{method.name} ignores constraints")
    set_sensor_weights(method, sensors)
    return ignored


def step(method: Method, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
    """Solve one frame; ``deadline`` (``time.perf_counter`` time) reaches only methods that
    take one.

    Raises
    ------
    FloatingPointError
        When the pose has a non-finite joint position.
    """
    if deadline is not None and method.takes_deadline:
        res = method.step(sensors, deadline=deadline)
    else:
        res = method.step(sensors)
    if not np.all(np.isfinite(res.positions)):
        raise FloatingPointError(f"method {method.name!r} returned a non-finite pose at frame {sensors.frame}")
    return res


def solve_clip(method: Method, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
    """The whole clip solved at once by a :class:`SolvesClips` method right after
    :func:`reset`, or None when the method (or this clip) goes frame by frame.

    Raises
    ------
    FloatingPointError
        When a frame's pose has a non-finite joint position.
    """
    results = method.solve_clip(frames) if isinstance(method, SolvesClips) else None
    for f, res in zip(frames, results or ()):
        if not np.all(np.isfinite(res.positions)):
            raise FloatingPointError(f"method {method.name!r} returned a non-finite pose at frame {f.frame}")
    return results
