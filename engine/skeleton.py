"""The canonical 22-joint skeleton every motion is retargeted to.

It is the rig of DragPoser's example motion (``../shared/data/mocap/dragposer``):
same joint names, order and hierarchy, SMPL-like proportions.

Conventions (used everywhere in the project)
---------------------------------------------
* Units: metres. Frame rate: 60 fps.
* Axes: **Z is up**. In the rest pose (all local rotations identity) the
  character faces **-Y** and its left side points to **+X** (so +X is the
  character's left, -Y its forward). The floor is the plane ``z = 0``.
* Quaternions are ``(w, x, y, z)`` (upc-pymotion's order), unit length.
* Rest pose: a T-pose with palms facing down (-Z), thumbs forward (-Y).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

JOINT_NAMES: tuple[str, ...] = (
    "root",
    "lhip",
    "lknee",
    "lankle",
    "ltoe",
    "rhip",
    "rknee",
    "rankle",
    "rtoe",
    "lowerback",
    "upperback",
    "chest",
    "lowerneck",
    "upperneck",
    "lclavicle",
    "lshoulder",
    "lelbow",
    "lwrist",
    "rclavicle",
    "rshoulder",
    "relbow",
    "rwrist",
)

NUM_JOINTS = len(JOINT_NAMES)
JOINT_INDEX: dict[str, int] = {n: i for i, n in enumerate(JOINT_NAMES)}

#: Parent index of each joint; the root's parent is -1.
PARENTS: tuple[int, ...] = (
    -1,
    0,
    1,
    2,
    3,
    0,
    5,
    6,
    7,
    0,
    9,
    10,
    11,
    12,
    11,
    14,
    15,
    16,
    11,
    18,
    19,
    20,
)

#: Rest offsets (metres) of each joint from its parent, from DragPoser's example rig.
REST_OFFSETS = np.array(
    [
        [0.000000, 0.000000, 0.000000],
        [0.066152, 0.030878, -0.099811],
        [0.058426, 0.012118, -0.400245],
        [-0.048370, 0.039177, -0.426108],
        [0.050446, -0.122773, -0.061035],
        [-0.071632, 0.025913, -0.110620],
        [-0.047018, 0.020329, -0.384108],
        [0.017452, 0.026265, -0.434078],
        [-0.040670, -0.123290, -0.061146],
        [-0.003737, 0.027151, 0.117781],
        [0.011300, 0.004014, 0.139511],
        [-0.012409, -0.033590, 0.054514],
        [-0.013029, 0.035040, 0.175711],
        [0.025767, -0.021543, 0.169235],
        [0.048163, 0.007552, 0.090392],
        [0.126088, 0.016601, 0.063680],
        [0.267955, 0.045501, -0.079029],
        [0.264990, 0.002704, 0.026215],
        [-0.050200, 0.013987, 0.089761],
        [-0.108410, 0.014538, 0.059109],
        [-0.286152, 0.027551, -0.040153],
        [-0.262080, 0.016349, -0.004308],
    ],
    dtype=np.float64,
)

#: End-site offsets (metres) of the leaf joints: toes, head (upperneck), wrists.
END_SITES: dict[str, np.ndarray] = {
    "ltoe": np.array([0.050446, -0.122773, -0.061035]),
    "rtoe": np.array([-0.040670, -0.123290, -0.061146]),
    "upperneck": np.array([0.025767, -0.021543, 0.169235]),
    "lwrist": np.array([0.264990, 0.002704, 0.026215]),
    "rwrist": np.array([-0.262080, 0.016349, -0.004308]),
}

#: Left/right joint pairs (used for mirroring).
MIRROR_PAIRS: tuple[tuple[str, str], ...] = (
    ("lhip", "rhip"),
    ("lknee", "rknee"),
    ("lankle", "rankle"),
    ("ltoe", "rtoe"),
    ("lclavicle", "rclavicle"),
    ("lshoulder", "rshoulder"),
    ("lelbow", "relbow"),
    ("lwrist", "rwrist"),
)

#: Index permutation that swaps left and right joints.
MIRROR_INDEX: tuple[int, ...] = tuple(
    JOINT_INDEX[dict(MIRROR_PAIRS + tuple((b, a) for a, b in MIRROR_PAIRS)).get(n, n)] for n in JOINT_NAMES
)

#: Each foot's ankle and toe joint, by side.
FEET: dict[str, tuple[str, str]] = {"left": ("lankle", "ltoe"), "right": ("rankle", "rtoe")}

#: End effectors in the field's sense (head, hands, feet); feet are the ankles as in DragPoser.
END_EFFECTORS: tuple[str, ...] = ("upperneck", "lwrist", "rwrist", "lankle", "rankle")

#: Joints used to measure the character's height above the ground (temporal predictor input).
HEIGHT_JOINTS: tuple[str, ...] = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")

FPS = 60.0
UP_AXIS = 2  # Z
FORWARD = np.array([0.0, -1.0, 0.0])  # rest-pose facing direction
LEFT = np.array([1.0, 0.0, 0.0])


def children(joint: int) -> list[int]:
    """Indices of the direct children of ``joint``."""
    return [j for j, p in enumerate(PARENTS) if p == joint]


@dataclass(frozen=True)
class Skeleton:
    """A canonical skeleton instance: the 22 canonical joints with given bone offsets.

    Every clip keeps its subject's size: offsets are :data:`REST_OFFSETS` scaled by
    ``scale`` (1.0 = DragPoser's example subject).

    Attributes
    ----------
    offsets : ndarray, shape (22, 3)
        Offset of every joint from its parent, metres. Row 0 is zero.
    """

    offsets: np.ndarray

    @classmethod
    def canonical(cls, scale: float = 1.0) -> "Skeleton":
        return cls(offsets=REST_OFFSETS * float(scale))

    @property
    def parents(self) -> tuple[int, ...]:
        return PARENTS

    @property
    def names(self) -> tuple[str, ...]:
        return JOINT_NAMES

    @property
    def scale(self) -> float:
        """Size relative to the canonical rest skeleton (ratio of leg lengths)."""
        leg = [1, 2, 3]
        return float(
            np.linalg.norm(self.offsets[leg], axis=-1).sum() / np.linalg.norm(REST_OFFSETS[leg], axis=-1).sum()
        )

    def rest_positions(self) -> np.ndarray:
        """World positions (22, 3) of the joints in the rest pose, root at the origin."""
        pos = np.zeros((NUM_JOINTS, 3))
        for j in range(1, NUM_JOINTS):
            pos[j] = pos[PARENTS[j]] + self.offsets[j]
        return pos

    def height(self) -> float:
        """Standing height in metres: lowest foot point to the top of the head, rest pose."""
        pos = self.rest_positions()
        s = self.scale
        head_top = pos[JOINT_INDEX["upperneck"]] + END_SITES["upperneck"] * s
        toe_tip = pos[JOINT_INDEX["ltoe"]] + END_SITES["ltoe"] * s
        lowest = min(pos[:, 2].min(), toe_tip[2])
        return float(head_top[2] - lowest)
