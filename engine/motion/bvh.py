"""BVH files in and out: a strict validating reader and an atomic canonical writer.

Reading
-------
upc-pymotion's ``BVH.load`` trusts its input: a malformed file gives an ``IndexError``
or a silently wrong array instead of a message a user can act on. :func:`load_bvh`
therefore parses the file itself, token by token with line numbers, and every problem
becomes an :class:`engine.errors.BVHError` that reads ``file:line: message``. The
result, :class:`RawBVH`, keeps the file's own rig (names, offsets, Euler orders, units);
retargeting to the canonical skeleton is :mod:`engine.motion.retarget`'s job. Euler angles
become quaternions with upc-pymotion's rotation maths.

Writing
-------
:func:`save_motion_bvh` writes a canonical :class:`engine.motion.clip.Motion` through
upc-pymotion's ``BVH.save`` into a temporary file beside the target, then renames it
over the target (:mod:`engine.atomic`), so a crash never leaves a half-written file.
See ``docs/bvh.md``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pymotion.rotations import quat_np as _qnp

from engine import skeleton as sk
from engine.atomic import atomic_path
from engine.errors import BVHError, UserError
from engine.kinematics import quaternion as Q
from engine.motion.bvh_parser import parse_bvh_lines
from engine.motion.bvh_syntax import MAX_OFFSET
from engine.motion.clip import Motion
from engine.validation import check_input_file

__all__ = ["MAX_OFFSET", "SAVE_ROT_ORDER", "RawBVH", "load_bvh", "save_motion_bvh"]

#: Euler order written for every joint by :func:`save_motion_bvh` (intrinsic Z, X, Y).
SAVE_ROT_ORDER = "zxy"

_AXES = "xyz"
_UNIT = np.eye(3)

#: Largest accepted absolute OFFSET component, in the file's units (cm, m, inches...).


@dataclass(frozen=True)
class RawBVH:
    """The contents of a BVH file on its own rig, validated.

    Attributes
    ----------
    names : tuple of str, length J
        Joint names in file order (depth first).
    parents : tuple of int, length J
        Parent index of each joint; the root's is -1.
    offsets : ndarray (J, 3)
        OFFSET of each joint from its parent, in the file's units.
    end_sites : dict of int to ndarray (3,)
        End-site OFFSET keyed by the index of the joint that owns it.
    channels : tuple of tuple of str, length J
        Channel names of each joint as written (``"Xposition"``, ``"Zrotation"``...).
    rot_order : ndarray (J, 3) of str
        Rotation channel order per joint, ``'x'``/``'y'``/``'z'`` (intrinsic Euler).
    positions : ndarray (F, J, 3)
        Local position of each joint: its position channels (x, y, z) if it has
        them, else its OFFSET. File units.
    rotations_deg : ndarray (F, J, 3)
        Euler angles in degrees, in each joint's ``rot_order``.
    frame_time : float
        Seconds per frame from the header (> 0).
    path : str
        The file read.
    file_frames : int
        Frames in the file; F is smaller when only the first frames were kept.
    """

    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray
    end_sites: dict[int, np.ndarray]
    channels: tuple[tuple[str, ...], ...]
    rot_order: np.ndarray
    positions: np.ndarray
    rotations_deg: np.ndarray
    frame_time: float
    path: str
    file_frames: int = 0

    @property
    def frames(self) -> int:
        """Number of frames F held (all of the file's unless ``load_bvh(max_frames=)``)."""
        return int(self.rotations_deg.shape[0])

    @property
    def total_frames(self) -> int:
        """Frames in the file (>= :attr:`frames`)."""
        return max(self.file_frames, self.frames)

    @property
    def fps(self) -> float:
        """Frames per second from the header (``1 / frame_time``), not rounded."""
        return 1.0 / self.frame_time

    @property
    def channel_counts(self) -> tuple[int, ...]:
        """Number of channels (3 or 6) of each joint."""
        return tuple(len(c) for c in self.channels)

    def local_quaternions(self) -> np.ndarray:
        """Local joint rotations as unit quaternions, shape (F, J, 4), (w, x, y, z).

        Built with upc-pymotion's ``from_angle_axis`` and ``mul`` one Euler axis at a
        time: ``quat_np.from_euler`` maps a Python lambda over every element of the
        order array, which takes seconds on a 100-joint clip.
        """
        rad = np.radians(self.rotations_deg)
        q = None
        for k in range(3):
            axis = _UNIT[[_AXES.index(a) for a in self.rot_order[:, k]]]  # (J, 3)
            axis = np.broadcast_to(axis, rad.shape)
            qk = _qnp.from_angle_axis(rad[..., k : k + 1], axis)
            q = qk if q is None else _qnp.mul(q, qk)
        assert q is not None  # three axes were multiplied in
        return Q.normalize(q)


def file_error(path: str, exc: Exception, error: type[BVHError] = BVHError, kind: str = "file") -> BVHError:
    """The ``file:line: message`` error of a motion file that could not be opened or
    checked (an :class:`OSError`, or the size and type checks' :class:`UserError`)."""
    if isinstance(exc, OSError):
        return error(path, f"cannot read {kind}: {exc.strerror or exc}")
    return error(path, str(exc).removeprefix(f"{path}: "))


def load_bvh(path: str | Path, max_frames: int | None = None) -> RawBVH:
    """Read and validate a BVH file.

    Parameters
    ----------
    path : str or Path
        The file: a regular file of at most 1 GB (no FIFO, device or symlink loop).
    max_frames : int, optional
        Keep only the first ``max_frames`` frames (every row is still checked); the file
        is streamed, so a long clip costs memory only for what is kept.

    Returns
    -------
    RawBVH
        Hierarchy and F frames of motion, in the file's units and Euler orders.

    Raises
    ------
    BVHError
        For any problem, naming the file and (when there is one) the line: missing
        sections, unbalanced braces, bad OFFSET or CHANNELS, duplicated names, huge
        offsets, zero or miscounted frames, short/long/non-numeric/non-finite rows,
        non-positive Frame Time, truncation.
    """
    path = str(path)
    try:  # a regular file below the size limit, before opening (no FIFO, /dev/zero, loop)
        size = check_input_file(path, "BVH file").stat().st_size
        with open(path, encoding="utf-8", errors="replace") as fh:
            p = parse_bvh_lines(path, fh, max_frames, size)
    except BVHError:
        raise
    except (UserError, OSError) as exc:
        raise file_error(path, exc) from None
    frames = p.data.shape[0]
    j = len(p.names)
    offsets = np.array(p.offsets, dtype=np.float64)
    positions = np.repeat(offsets[None], frames, axis=0)
    rotations = np.empty((frames, j, 3))
    rot_order = np.empty((j, 3), dtype="<U1")
    col = 0
    for k, chans in enumerate(p.channels):
        rot_cols = [(c[0].lower(), col + i) for i, c in enumerate(chans) if c.endswith("rotation")]
        pos_cols = {c[0].lower(): col + i for i, c in enumerate(chans) if c.endswith("position")}
        rot_order[k] = [a for a, _ in rot_cols]
        rotations[:, k] = p.data[:, [i for _, i in rot_cols]]
        if pos_cols:
            positions[:, k] = p.data[:, [pos_cols[a] for a in _AXES]]
        col += len(chans)
    return RawBVH(
        names=tuple(p.names),
        parents=tuple(p.parents),
        offsets=offsets,
        end_sites=p.end_sites,
        channels=tuple(p.channels),
        rot_order=rot_order,
        positions=positions,
        rotations_deg=rotations,
        frame_time=p.frame_time,
        path=path,
        file_frames=p.frames,
    )


def save_motion_bvh(path: str | Path, motion: Motion) -> None:
    """Write a canonical motion as a standard BVH file (Blender, MotionBuilder...).

    Hierarchy and names are those of :mod:`engine.skeleton`; OFFSETs are
    ``motion.skeleton.offsets`` and end sites :data:`engine.skeleton.END_SITES`
    scaled by ``motion.skeleton.scale``. Units are metres, Z up, as in the engine.

    Channel layout:

    * root: ``CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation``
      (root world position, metres, then Euler degrees);
    * every other joint: ``CHANNELS 3 Zrotation Xrotation Yrotation``.

    The Euler angles are intrinsic Z then X then Y (the local rotation is
    ``Rz @ Rx @ Ry``), the usual BVH reading of the channel order. ``Frame Time`` is
    ``1 / motion.fps``.

    The file is written to a temporary file in the target's directory and moved over
    ``path`` with :func:`os.replace` (:func:`engine.atomic.atomic_path`): readers see the old file or the complete new one,
    never part of one, and an exception leaves no temporary file behind.

    Parameters
    ----------
    path : str or Path
        Output file; missing parent folders are created. It gets the permissions a
        plain ``open(path, "w")`` would give.
    motion : Motion
        F frames of local rotations (F, 22, 4) and root positions (F, 3), metres.

    Raises
    ------
    ValueError
        If the motion holds non-finite values (the file would not load again).
    """
    path = Path(path)
    if not (np.isfinite(motion.local_rot).all() and np.isfinite(motion.root_pos).all()):
        raise ValueError(f"motion {motion.name!r} holds NaN or infinite values; not writing {path}")
    if len(motion) == 0:
        raise ValueError(f"motion {motion.name!r} has no frames; not writing {path}")
    f, j = len(motion), sk.NUM_JOINTS
    order = np.array([list(SAVE_ROT_ORDER)] * j)
    euler = np.degrees(Q.to_euler(Q.normalize(motion.local_rot), np.broadcast_to(order, (f, j, 3))))
    euler = (euler + 180.0) % 360.0 - 180.0  # pymotion returns [0, 360); keep angles readable
    offsets = np.asarray(motion.skeleton.offsets, dtype=np.float64).copy()
    offsets[0] = 0.0  # the root's position lives in its channels
    positions = np.repeat(offsets[None], f, axis=0)
    positions[:, 0] = motion.root_pos
    ends = sorted((sk.JOINT_INDEX[n], off) for n, off in sk.END_SITES.items())
    # pymotion's BVH module imports torch (its skeleton ops take tensors too): only when saving
    from pymotion.io.bvh import BVH as _PymotionBVH

    writer = _PymotionBVH()
    writer.data = {
        "filename": path.stem,
        "names": np.array(sk.JOINT_NAMES),
        "offsets": offsets,
        "end_sites": np.array([off * motion.skeleton.scale for _, off in ends]),
        "end_sites_parents": np.array([i for i, _ in ends]),
        "parents": np.array([0, *sk.PARENTS[1:]]),  # pymotion marks the root as its own parent
        "rot_order": order,
        "channels": np.array([6] + [3] * (j - 1)),
        "positions": positions,
        "rotations": euler,
        "frame_time": 1.0 / float(motion.fps),
    }
    with atomic_path(path) as tmp:
        writer.save(str(tmp))
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())  # the rename must not land before the data
