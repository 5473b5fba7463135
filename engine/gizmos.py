"""What a constraint draws in the viewport: small frozen shapes of plain numpy data.

``Constraint.gizmo(positions)`` returns one of these (or None: nothing to draw). The
engine thread puts them in its snapshots next to the constraint's name; the viewport
draws each through the adapter registered for its class
(:mod:`widgets.viewport.gizmos`), and a shape without an adapter is a ``TypeError``
there, never silently skipped.

A shape's ``edit`` names the constraint field(s) a drag of its handle writes back;
without one the shape is drawn but not draggable. Arrays are copied at construction and
made read-only, so a shape published to the GUI thread never changes under it.

Adding a shape: a frozen dataclass here deriving from :class:`Gizmo`, and an adapter in
:mod:`widgets.viewport.gizmo_adapters` registered for it (a test checks that every
subclass of :class:`Gizmo` has one).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


def _points(value: Any, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    """``value`` as a read-only float64 copy of ``shape`` (None: any length), finite."""
    a = np.array(value, dtype=np.float64)
    if a.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, a.shape)):
        want = "x".join("N" if n is None else str(n) for n in shape)
        raise ValueError(f"{what}: expected shape ({want}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what}: not finite: {a.tolist()}")
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Gizmo:
    """Base of the drawable shapes; it is never drawn itself (it has no adapter)."""

    @property
    def edit_fields(self) -> tuple[str, ...]:
        """The constraint fields a drag of this shape writes (empty: not draggable)."""
        return ()

    def __setstate__(self, state: dict[str, Any]) -> None:
        # unpickled arrays (the engine process's snapshots) come back writeable
        for name, value in state.items():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(self, name, value)


@dataclass(frozen=True, eq=False)
class PointGizmo(Gizmo):
    """A point in the world.

    Attributes
    ----------
    position : ndarray (3,)
        Metres, world frame.
    edit : str
        The constraint field a drag of the point writes (a handle is drawn); '' for none.
    label : str
        Text drawn beside the point (e.g. the joint a pin holds); '' for none.
    anchor : ndarray (3,) or None
        Where a thin tether line to the point starts (the joint as it is now, showing
        the pull); None for no tether.
    """

    position: np.ndarray
    edit: str = ""
    label: str = ""
    anchor: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _points(self.position, (3,), "point gizmo position"))
        if self.anchor is not None:
            object.__setattr__(self, "anchor", _points(self.anchor, (3,), "point gizmo anchor"))

    @property
    def edit_fields(self) -> tuple[str, ...]:
        return (self.edit,) if self.edit else ()


@dataclass(frozen=True, eq=False)
class LineGizmo(Gizmo):
    """A polyline through ``points`` (N, 3), metres, N >= 2.

    ``edit`` names the constraint field a drag of the last point writes (the point a
    look-at aims at); '' when the line is not draggable.
    """

    points: np.ndarray
    edit: str = ""

    def __post_init__(self) -> None:
        pts = _points(self.points, (None, 3), "line gizmo points")
        if len(pts) < 2:
            raise ValueError(f"line gizmo points: need at least 2, got {len(pts)}")
        object.__setattr__(self, "points", pts)

    @property
    def edit_fields(self) -> tuple[str, ...]:
        return (self.edit,) if self.edit else ()


@dataclass(frozen=True, eq=False)
class BoxGizmo(Gizmo):
    """An axis-aligned box from ``lower`` (3,) to ``upper`` (3,), metres.

    ``edit`` is the pair of constraint fields a drag of the box's faces writes, its
    lower and upper corner (e.g. ``("box_min", "box_max")``); empty when not draggable.
    """

    lower: np.ndarray
    upper: np.ndarray
    edit: tuple[str, str] | tuple[()] = field(default=())

    def __post_init__(self) -> None:
        lo = _points(self.lower, (3,), "box gizmo lower corner")
        hi = _points(self.upper, (3,), "box gizmo upper corner")
        if np.any(lo > hi):
            raise ValueError(f"box gizmo: lower corner {lo.tolist()} above upper corner {hi.tolist()}")
        if len(self.edit) not in (0, 2):
            raise ValueError(f"box gizmo edit: expected (lower field, upper field), got {self.edit!r}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "edit", tuple(self.edit))

    @property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        """``(xmin, xmax, ymin, ymax, zmin, zmax)``, metres, the order VTK takes."""
        lo, hi = self.lower, self.upper
        return (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]), float(lo[2]), float(hi[2]))

    @property
    def edit_fields(self) -> tuple[str, ...]:
        return tuple(self.edit)


def gizmo_types() -> tuple[type[Gizmo], ...]:
    """Every drawable shape class: the subclasses of :class:`Gizmo`, at any depth."""
    out: list[type[Gizmo]] = []
    todo = list(Gizmo.__subclasses__())
    while todo:
        cls = todo.pop(0)
        out.append(cls)
        todo.extend(cls.__subclasses__())
    return tuple(out)
