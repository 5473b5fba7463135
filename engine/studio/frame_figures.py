"""The figures a studio snapshot reports of one solve: the per-iteration losses and the
timings, derived from a method's :class:`~engine.methods.base.FrameResult`, and the
constraints' gizmos posed on the solved pose."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.gizmos import Gizmo
from engine.methods.base import FrameResult
from engine.sensors import SensorFrame


def losses_of(res: FrameResult | None, sf: SensorFrame) -> tuple[dict[str, float], ...]:
    """The method's per-iteration losses; for methods without any (classical IK), one
    "iteration" of squared position errors to every connected target, so the plots and
    tests can compare methods on the same terms."""
    if res is None:
        return ()
    if res.losses:
        return tuple(dict(d) for d in res.losses)
    errs = {
        f"pos:{j}": float(np.sum((res.positions[sk.JOINT_INDEX[j]] - r.position) ** 2))
        for j, r in sf.connected().items()
    }
    errs["total"] = float(sum(errs.values()))
    return (errs,)


def timing_of(res: FrameResult | None, ms: float, latency_ms: float | None = None) -> dict[str, float]:
    """The solve's timing figures, ms: wall time per frame and per iteration, overridden
    by the method's own per-iteration breakdown when its result carries one (a
    ``timings`` dict: ``ms_per_iteration``, ``decoder``, ``fk_losses``, ``backward``,
    ``step``, as DragPoser reports them); for a live source ``latency_ms``, from the
    frame's packet arriving to its solved pose."""
    if res is None:
        return {}
    out = {"ms_per_frame": float(ms)}
    if latency_ms is not None:
        out["latency_ms"] = float(latency_ms)
    if res.iterations:
        out["ms_per_iteration"] = float(ms) / res.iterations
    out.update({str(k): float(v) for k, v in res.timings.items() if isinstance(v, (int, float))})
    return out


def gizmos_of(
    constraints: Iterable[Any], positions: np.ndarray, report: Callable[[str], None], frame: int | None = None
) -> tuple[tuple[str, Gizmo], ...]:
    """``(name, shape)`` of the enabled constraints that draw one, posed on
    ``positions`` (22, 3), metres (distance, balance and look-at draw lines between
    current joints). With ``frame``, a constraint that does not act there (outside its
    ``frames`` and their blends: ``activity(frame) == 0``) draws nothing, so a pin for
    frames 100-160 is not seen holding on frame 50. A constraint whose ``gizmo`` raises
    is left out and ``report`` ed, not hidden."""
    out = []
    for c in constraints:
        if not c.enabled or (frame is not None and c.activity(frame) <= 0.0):
            continue
        try:
            g = c.gizmo(positions)
        except Exception as exc:
            report(f"constraint {c.name!r}: cannot draw its gizmo ({exc})")
            continue
        if g is not None:
            out.append((c.name, g))
    return tuple(out)
