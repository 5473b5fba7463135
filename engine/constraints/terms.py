"""What a constraint kind gives the solver's fast path: a numpy term with its own gradient.

The fast path (:mod:`engine.solver.fast`) evaluates a frame without autograd. Each
constraint kind builds, once per frame, a :class:`PoseTerm` from its parameters frozen
for that frame (:meth:`engine.constraints.base.Constraint.fast_term`). A term reads the
world joint positions ``P (22, 3)`` (metres, after the root anchor) and world rotation
matrices ``W (22, 3, 3)``, and adds the gradient of ``weight * loss`` w.r.t. them:

* ``g_pos (22, 3)``: d(weighted loss) / d ``P``;
* ``g_rot (22, 3)``: the rotation gradient of each joint in world axes: for a small
  world-frame turn ``a`` of joint ``j``'s own rotation (``W_j -> exp([a]x) W_j``, its
  position and its children left alone), the weighted loss changes by ``g_rot[j] . a``.

One call, :meth:`PoseTerm.evaluate`, gives the loss and adds the gradient (most of a
term's cost on a 22-joint pose is per numpy call, so loss and gradient share their
work). The fast path turns both gradients into the latent gradient (FK and decoder
reverse pass). The autograd reference path uses
:meth:`~engine.constraints.base.Constraint.loss` instead;
``tests/engine/test_fast_terms.py`` checks every kind's term against it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class FrameInputs:
    """What a term may depend on besides the pose being solved.

    Attributes
    ----------
    previous_positions : ndarray (22, 3) or None
        The previous frame's solved world positions, metres (None on the first frame).
    frame : int
        Frame index in the clip.
    """

    previous_positions: np.ndarray | None = None
    frame: int = 0


@runtime_checkable
class PoseTerm(Protocol):
    """One constraint's fast-path term for one frame (see the module doc).

    Attributes
    ----------
    name : str
        The constraint's name (loss reporting).
    weight : float
        The weight the term's loss is multiplied by (the solver sets it for the frame:
        the constraint's weight times its frame-range activity).
    turns : bool
        Whether the term may add to ``g_rot`` (it reads a joint's rotation).
    """

    name: str
    weight: float
    turns: bool

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        """The unweighted loss at positions ``pos (22, 3)`` and rotations ``world (22, 3,
        3)``; adds the gradient of ``weight * loss`` to ``g_pos (22, 3)`` and ``g_rot
        (22, 3)`` in place."""
        ...

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        """Whether the offline optimizer may stop on this term's account."""
        ...


class NativeTerm:
    """A term the fast path evaluates with its own batched arithmetic (the trackers and
    the temporal prior, :mod:`engine.solver.fast`): it carries its constraint.

    Parameters
    ----------
    constraint : Constraint
        The constraint (its parameters are read once per frame).
    weight : float
        Its weight for this frame.
    """

    def __init__(self, constraint, weight: float) -> None:
        self.constraint, self.name, self.weight = constraint, constraint.name, float(weight)


def axial(m: np.ndarray) -> np.ndarray:
    """Axial vector ``(M21 - M12, M02 - M20, M10 - M01)`` of ``m (3, 3)``: ``trace([a]x m) =
    -a . axial(m)``, which rotation gradients are made of."""
    return np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])


def unit_quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix ``(3, 3)`` of quaternion ``q (4,)`` (w, x, y, z), normalised first."""
    w, x, y, z = np.asarray(q, dtype=np.float64) / max(float(np.linalg.norm(q)), 1e-12)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def rotation_term(target: np.ndarray, world_j: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The sign-invariant rotation distance ``(3 - trace(T^T W)) / 4 = sin^2(angle / 2)``
    of ``base.rotation_distance``, from target matrix ``T (3, 3)`` and a joint's ``W (3, 3)``.

    Returns
    -------
    raw : float
        The distance before clamping to [0, 1].
    value : float
        Clamped to [0, 1] (the loss).
    grad : ndarray (3,)
        Its rotation gradient (zero where the clamp is active).
    """
    raw = (3.0 - float((target * world_j).sum())) * 0.25
    inside = 0.0 <= raw <= 1.0
    grad = -0.25 * axial(target @ world_j.T) if inside else np.zeros(3)
    return raw, min(max(raw, 0.0), 1.0), grad
