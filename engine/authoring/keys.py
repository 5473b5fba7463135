"""Keys of an authored animation and the in-between rules.

A :class:`Key` is a pose wish at one frame: targets by joint, optionally the latent the
studio solved for it, and where the body stands (``root`` xy, ``heading``). Between two
keys every quantity (latent, target positions, root placement) follows the same
interpolation scheme (:data:`SCHEMES`):

* ``linear``: straight blend;
* ``spherical``: latents along the great circle between them with their length
  blended (latents are Gaussian-distributed, so this keeps an in-between at a typical
  distance from the mean where a straight blend shrinks towards it); positions linear;
* ``cubic`` (default): a cubic Hermite spline with tangents from the neighbouring keys
  (Catmull-Rom, for uneven key spacing) and zero tangents at the first and last key, so
  motion eases in and out and has no velocity kink at a key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from engine.authoring.targets import JointTarget

SCHEMES = ("linear", "spherical", "cubic")
#: Foot joints that stay planted where they stand until the user drags that foot.
PLANTED = ("lankle", "ltoe", "rankle", "rtoe")


@dataclass
class Animation:
    """Length and rate of an authored animation.

    Attributes
    ----------
    fps : float
        Frames per second.
    frames : int
        Frame count (frames 0 .. frames - 1).
    interpolation : str
        One of :data:`SCHEMES`.
    """

    fps: float = 30.0
    frames: int = 61
    interpolation: str = "cubic"


@dataclass
class Key:
    """One key.

    Attributes
    ----------
    frame : int
    targets : dict joint -> JointTarget
    latent : ndarray (L,) or None
        The solved latent; None: posed by pose mode from the mean pose when baked
        (its targets dragged there, :meth:`engine.authoring.pose_mode.PoseMode.pose_key`).
    root : ndarray (2,)
        Root's horizontal position, metres.
    heading : float
        Facing, degrees about +Z from the canonical -Y.
    feet : dict joint -> ndarray (3,)
        Where the :data:`PLANTED` foot joints stand, metres, for a key whose pelvis was
        dragged alone (a ``pelvis_only`` target on ``root``): its legs reach them when it
        is posed; empty otherwise (the feet stand where the latent puts them).
    """

    frame: int
    targets: dict[str, JointTarget] = field(default_factory=dict)
    latent: np.ndarray | None = None
    root: np.ndarray = field(default_factory=lambda: np.zeros(2))
    heading: float = 0.0
    feet: dict[str, np.ndarray] = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Scene JSON of the key (a plain position target as ``[x, y, z]``)."""
        targets = {j: t.to_dict() for j, t in self.targets.items()}
        out: dict = {
            "frame": int(self.frame),
            "targets": {j: (d["position"] if set(d) == {"position"} else d) for j, d in targets.items()},
        }
        if self.latent is not None:
            out["latent"] = [float(x) for x in np.asarray(self.latent).ravel()]
        if np.any(self.root != 0):
            out["root"] = [float(x) for x in self.root]
        if self.heading:
            out["heading"] = float(self.heading)
        if self.feet:
            out["feet"] = {j: [float(x) for x in p] for j, p in self.feet.items()}
        return out


def segment(frames: list[float], t: float) -> tuple[int, float]:
    """Index ``i`` of the key at or before time ``t`` and the fraction ``s`` in [0, 1]
    towards key ``i + 1`` (``s == 0`` on a key, before the first and after the last)."""
    if t <= frames[0] or len(frames) == 1:
        return 0, 0.0
    if t >= frames[-1]:
        return len(frames) - 1, 0.0
    i = int(np.searchsorted(frames, t, side="right")) - 1
    return i, (t - frames[i]) / (frames[i + 1] - frames[i])


def interpolate(times: list[float], values: list[np.ndarray], t: float, scheme: str) -> np.ndarray:
    """Value at time ``t`` of the keyed ``values`` (each ``(D,)``) at ``times``."""
    i, s = segment(times, t)
    a = np.asarray(values[i], float)
    if s == 0.0:
        return a.copy()
    b = np.asarray(values[i + 1], float)
    if scheme == "linear":
        return (1 - s) * a + s * b
    if scheme == "spherical":
        return slerp_vectors(a, b, s)
    h = times[i + 1] - times[i]
    m0 = _tangent(times, values, i) * h
    m1 = _tangent(times, values, i + 1) * h
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * a + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * b + (s3 - s2) * m1


def eased(times: list[float], t: float, scheme: str) -> tuple[int, float]:
    """Segment index and blend fraction for quantities blended pairwise (rotations):
    the fraction itself, or its smoothstep for ``cubic``."""
    i, s = segment(times, t)
    return i, (s * s * (3 - 2 * s) if scheme == "cubic" else s)


def slerp_vectors(a: np.ndarray, b: np.ndarray, s: float) -> np.ndarray:
    """Great-circle blend of the directions of ``a`` and ``b (D,)`` with their lengths
    blended linearly; a straight blend when either is near zero or they are parallel."""
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if na < 1e-8 or nb < 1e-8:
        return (1 - s) * a + s * b
    ua, ub = a / na, b / nb
    omega = math.acos(min(max(float(ua @ ub), -1.0), 1.0))
    if omega < 1e-6 or math.pi - omega < 1e-6:
        return (1 - s) * a + s * b
    u = (math.sin((1 - s) * omega) * ua + math.sin(s * omega) * ub) / math.sin(omega)
    return u * ((1 - s) * na + s * nb)


def slerp_quaternion(a: np.ndarray, b: np.ndarray, s: float) -> np.ndarray:
    """Shortest-arc blend of unit quaternions ``(4,)``."""
    b = b if float(a @ b) >= 0 else -b
    q = slerp_vectors(a, b, s)
    return q / np.linalg.norm(q)


def _tangent(times: list[float], values: list[np.ndarray], i: int) -> np.ndarray:
    if i == 0 or i == len(times) - 1:
        return np.zeros_like(np.asarray(values[i], float))
    return (np.asarray(values[i + 1], float) - np.asarray(values[i - 1], float)) / (times[i + 1] - times[i - 1])
