"""A canonical motion clip: the unit every part of the engine passes around."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics.fk import fk


@dataclass
class Motion:
    """Frame-indexed motion on the canonical 22-joint skeleton (Z-up, metres, 60 fps).

    Attributes
    ----------
    local_rot : ndarray (F, 22, 4)
        Local joint rotations (w, x, y, z); row 0 is the root's world rotation.
    root_pos : ndarray (F, 3)
        Root (pelvis) world position, metres; the floor is z = 0.
    skeleton : Skeleton
        Bone offsets of this subject.
    fps : float
        Frames per second (60 after retargeting).
    name : str
        Human-readable origin (usually the source file stem).
    start : int
        Frame of the clip as loaded from its file that this clip's frame 0 is (0 unless
        trimmed, :meth:`trim`); writing back onto the source rig maps frames with it.
    """

    local_rot: np.ndarray
    root_pos: np.ndarray
    skeleton: sk.Skeleton = field(default_factory=sk.Skeleton.canonical)
    fps: float = sk.FPS
    name: str = ""
    start: int = 0

    def __post_init__(self) -> None:
        self.local_rot = np.asarray(self.local_rot, dtype=np.float64)
        self.root_pos = np.asarray(self.root_pos, dtype=np.float64)
        f = self.local_rot.shape[0]
        if self.local_rot.shape != (f, sk.NUM_JOINTS, 4) or self.root_pos.shape != (f, 3):
            raise ValueError(
                f"Motion {self.name!r}: expected local_rot (F, 22, 4) and root_pos (F, 3), "
                f"got {self.local_rot.shape} and {self.root_pos.shape}"
            )

    def __len__(self) -> int:
        return self.local_rot.shape[0]

    @property
    def duration(self) -> float:
        """Seconds."""
        return len(self) / self.fps

    def fk(self) -> tuple[np.ndarray, np.ndarray]:
        """World joint positions (F, 22, 3) and rotations (F, 22, 4)."""
        return fk(self.local_rot, self.root_pos, self.skeleton.offsets)

    def positions(self) -> np.ndarray:
        return self.fk()[0]

    def slice(self, start: int = 0, stop: int | None = None) -> "Motion":
        """Frames ``start:stop`` (``start`` >= 0) as a new clip (copies); its :attr:`start`
        counts on from this clip's, so a part still knows which frames of its file it holds."""
        return Motion(
            self.local_rot[start:stop].copy(),
            self.root_pos[start:stop].copy(),
            self.skeleton,
            self.fps,
            self.name,
            self.start + start,
        )

    def trim(self, first: int, last: int) -> "Motion":
        """Frames ``first..last`` (inclusive, 0-based): :meth:`slice`, with the range
        checked.

        Raises
        ------
        UserError
            A range that is empty or outside the clip's ``len(self)`` frames.
        """
        first, last = int(first), int(last)
        if not 0 <= first <= last < len(self):
            raise UserError(
                f"cannot trim {self.name or 'the clip'} to frames {first}-{last}: it has frames 0-{len(self) - 1}"
            )
        return self.slice(first, last + 1)
