"""Constraints on a frame, and pins against targets: one rule for the bake and the pose window.

:func:`active_constraints` is what acts on a frame (each weight times its activity
there). :func:`pinned_targets` settles a pin on a joint that a target also holds: the
target goes from its place to the pin's by the pin's activity on that frame, and the pin
acts through that target only. The bake (:mod:`engine.authoring.bake`) poses its keys
and in-betweens with it, and every solve of the pose window
(:class:`engine.authoring.pose_solve.PoseSolving`) aims at the targets it gives, so a
frame shows what the bake gives there. :func:`pinned_places` is the same rule for the
planted feet's places.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from engine.authoring.targets import JointTarget
from engine.constraints.base import Constraint
from engine.constraints.pin import PinConstraint


def active_constraints(constraints: list[Constraint], frame: int) -> list[Constraint]:
    """Copies of the enabled ``constraints`` acting on ``frame``, each weight times its
    :meth:`~engine.constraints.base.Constraint.activity` there and without a range (so a
    solver that honours ranges itself does not apply it twice)."""
    out = []
    for c in constraints:
        a = c.activity(frame) if c.enabled else 0.0
        if a > 0:
            out.append(dataclasses.replace(c, weight=c.weight * a, frames=None, blend_in=0, blend_out=0))
    return out


def holding_pins(constraints: list[Constraint], frame: int) -> dict[str, PinConstraint]:
    """Per joint, the enabled pin with a set place that holds it most on ``frame`` (the
    largest :meth:`~engine.constraints.base.Constraint.activity` there)."""
    out: dict[str, PinConstraint] = {}
    for c in constraints:
        if not isinstance(c, PinConstraint) or not c.enabled or c.follow_previous:
            continue
        a = c.activity(frame)
        if a > 0 and np.all(np.isfinite(c.position)) and (c.joint not in out or a > out[c.joint].activity(frame)):
            out[c.joint] = c
    return out


def held_pins(constraints: list[Constraint], frame: int) -> dict[str, tuple[np.ndarray, float]]:
    """Per joint, where the pins acting on ``frame`` hold it and how much
    (:func:`holding_pins`: that pin's place and activity there)."""
    return {j: (np.asarray(c.position, float), c.activity(frame)) for j, c in holding_pins(constraints, frame).items()}


def pinned_targets(
    targets: list[JointTarget],
    constraints: list[Constraint],
    frame: int,
    shift: np.ndarray | None = None,
    free: Mapping[str, np.ndarray] | None = None,
) -> tuple[list[JointTarget], list[Constraint]]:
    """``targets`` with a pin on the same joint winning on ``frame``, and the constraints
    left to act there as terms (:func:`active_constraints`).

    A pinned joint's target goes from its own place towards the pin's by the pin's
    activity there (all the way inside its range, along its blends outside), and that
    pin acts through the target only. Kept as a term against a target, a pin (weight 30)
    pulls the latent's joint to its place while the exact limb step puts the joint back
    on the target: the latent bends the trunk by 60-75 degrees for a wrist that does not
    move. ``shift (3,)`` metres is added to each pin's place: the targets of a solve of
    the body where it stood under a pelvis-only target come moved by the pelvis's
    offset (:meth:`engine.authoring.pose_solve.PoseSolving._inputs`), and a pin's place
    is moved with them.

    ``free`` (joint -> (3,) metres) is where joints that no target holds are without
    their pins (the bake's in-betweens: the frame solved without those pins). A pin on
    such a joint (other than the root) gets a target there, moved to its place by its
    activity, and acts through it only, as over a target: kept as a term, its weight of
    30 takes the joint to the pin in the first frames of the blend and shakes it by up to
    11 cm a frame over the range."""
    pins = held_pins(constraints, frame)
    if shift is not None:
        pins = {j: (place + np.asarray(shift, float), a) for j, (place, a) in pins.items()}
    out, won = [], set()
    for t in targets:
        if t.joint in pins and t.active:
            t = dataclasses.replace(t, position=_toward(t.position, *pins[t.joint]))
            won.add(t.joint)
        out.append(t)
    for j, pin in pins.items():
        if free is None or j not in free or j == "root" or any(t.joint == j for t in targets):
            continue
        out.append(JointTarget(j, _toward(free[j], *pin)))
        won.add(j)
    rest = [c for c in constraints if not (isinstance(c, PinConstraint) and c.joint in won and c.joint in pins)]
    return out, active_constraints(rest, frame)


def pinned_places(
    places: Mapping[str, np.ndarray], constraints: list[Constraint], frame: int
) -> tuple[dict[str, np.ndarray], set[str]]:
    """``places`` (joint -> (3,) metres: where the planted feet stand) with a pin acting
    on ``frame`` winning on its joint as over a target (:func:`pinned_targets`), and the
    joints whose pin won."""
    pins = held_pins(constraints, frame)
    out = {j: _toward(p, *pins[j]) if j in pins else np.array(p, float) for j, p in places.items()}
    return out, set(pins) & set(places)


def _toward(x: np.ndarray, place: np.ndarray, a: float) -> np.ndarray:
    """``x (3,)`` moved to a pin's ``place`` by its activity ``a`` (a new array)."""
    return (1.0 - a) * np.asarray(x, float) + a * place
