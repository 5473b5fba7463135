"""Naturalness of a pose: how far it is from the nearest real pose of the validation files.

A pose is compared by its **root-relative joint positions after aligning heading**: the
root moved to the origin and the body turned about the vertical so its hip line points
along +X (the character faces -Y). The distance between two poses is the mean over the 21
non-root joints of the joints' distances, metres. Both the reference poses and the
measured ones are laid out on the same skeleton (the character's), so bone lengths do
not count, only how the joints are turned.

The **reference set** (:class:`ReferenceSet`) is every ``stride``-th frame of the
validation clips and their left/right mirror images. Its **spread** is the distribution,
over the reference poses, of each one's distance to the nearest pose of *another* take
(its own take, its mirror image and the take's copies on other rigs excluded): how far a
real pose typically is from the rest of the data. A pose whose nearest-neighbour distance
is below the spread's 95th percentile is *within the spread* of real poses.

The validation files' poses ship with the package (:data:`SHIPPED`, local rotations of
every :data:`STRIDE`-th frame, built by ``scripts/build_pose_reference.py``), so the
benchmark needs no motion data beside the installation; a folder holding the files
themselves can be given instead (:func:`validation_files`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.progress import CancelCheck, check

#: The 9 validation files of every release (assets/models/README.md), relative to a mocap folder.
VALIDATION_FILES = (
    "cmu_daz/indian/14.bvh",
    "cmu_daz/salsa/07.bvh",
    "cmu_iclone/002_01.bvh",
    "cmu_iclone/002_09.bvh",
    "cmu_iclone/005_05.bvh",
    "cmu_iclone/005_13.bvh",
    "cmu_iclone/006_02.bvh",
    "cmu_iclone/006_10.bvh",
    "cmu_iclone/007_05.bvh",
)
#: Every 4th frame (15 per second at 60 fps): neighbouring frames add little.
STRIDE = 4
#: The validation files' local rotations at :data:`STRIDE` (scripts/build_pose_reference.py).
SHIPPED = Path(__file__).resolve().parents[2] / "assets" / "reference" / "validation_poses.npz"
_SHIPPED_FIELDS = ("local_rot", "take", "names", "stride")
#: Query rows per distance block (memory: rows x reference poses x 4 bytes per joint).
_BLOCK = 256


def aligned(positions: np.ndarray) -> np.ndarray:
    """Root-relative, heading-aligned joint positions ``(..., 21, 3)`` (no root) of world
    positions ``(..., 22, 3)``: the hip line turned onto +X about the vertical."""
    p = np.asarray(positions, float)
    rel = p - p[..., :1, :]
    left = rel[..., sk.JOINT_INDEX["lhip"], :] - rel[..., sk.JOINT_INDEX["rhip"], :]
    yaw = np.arctan2(left[..., 1], left[..., 0])  # hip line's angle from +X
    c, s = np.cos(-yaw)[..., None], np.sin(-yaw)[..., None]
    x, y = rel[..., 0], rel[..., 1]
    out = np.stack((c * x - s * y, s * x + c * y, rel[..., 2]), axis=-1)
    return out[..., 1:, :]


def pose_distances(query: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Distances ``(Q, N)`` (metres) between aligned poses ``query (Q, 21, 3)`` and
    ``poses (N, 21, 3)``: the mean over joints of the joints' distances."""
    q = torch.as_tensor(np.asarray(query, np.float32)).transpose(0, 1)  # (21, Q, 3)
    r = torch.as_tensor(np.asarray(poses, np.float32)).transpose(0, 1)  # (21, N, 3)
    d = torch.cdist(q, r, compute_mode="donot_use_mm_for_euclid_dist")  # exact: a pose is 0 from itself
    return d.mean(0).numpy()


@dataclass
class ReferenceSet:
    """Aligned real poses and the take each comes from (see the module doc).

    Attributes
    ----------
    poses : ndarray (N, 21, 3) float32
        Aligned joint positions, metres.
    takes : ndarray (N,) int
        Take index per pose; a mirror image has its original's take.
    names : list of str
        Take names.
    description : str
        Where the poses come from, for reports.
    """

    poses: np.ndarray
    takes: np.ndarray
    names: list[str]
    description: str = ""
    _spread: np.ndarray | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.poses)

    @classmethod
    def from_rotations(
        cls,
        clips: list[tuple[str, np.ndarray]],
        offsets: np.ndarray,
        stride: int = STRIDE,
        mirror: bool = True,
        description: str = "",
    ) -> "ReferenceSet":
        """From ``(take name, local rotations (F, 22, 4))`` pairs, laid out on ``offsets
        (22, 3)``; with ``mirror``, each frame's left/right mirror image too. Several
        pairs may share a take name (copies of one take)."""
        if stride < 1:
            raise UserError(f"reference stride must be at least 1, got {stride}")
        names = sorted({n for n, _ in clips})
        poses, takes = [], []
        for name, local in clips:
            rot = np.asarray(local, float)[::stride]
            sets = [rot] + ([QN.mirror_x(rot[:, list(sk.MIRROR_INDEX)])] if mirror else [])
            for r in sets:
                pos = fk(r, np.zeros((len(r), 3)), np.asarray(offsets, float))[0]
                poses.append(aligned(pos).astype(np.float32))
                takes.append(np.full(len(r), names.index(name)))
        if not poses:
            raise UserError("the reference set has no poses")
        return cls(np.concatenate(poses), np.concatenate(takes), names, description)

    def nearest(self, positions: np.ndarray) -> float:
        """Distance (metres) from world positions ``(22, 3)`` to the nearest reference pose."""
        return self.closest(positions)[0]

    def closest(self, positions: np.ndarray) -> tuple[float, str]:
        """Distance (metres) from world positions ``(22, 3)`` to the nearest reference pose,
        and the name of the take that pose comes from."""
        d = pose_distances(aligned(positions)[None], self.poses)[0]
        i = int(d.argmin())
        return float(d[i]), self.names[int(self.takes[i])]

    def spread(self, cancelled: CancelCheck | None = None, sample: int | None = None) -> np.ndarray:
        """Per reference pose, its distance (metres) to the nearest pose of another take
        ``(N,)`` (computed once; about a second for the shipped poses: ``cancelled`` is
        asked between blocks and raises :class:`~engine.progress.Cancelled`). With
        ``sample`` and more poses than that, only every ``ceil(N / sample)``-th pose's
        distance (to all the others), ``(ceil(N / step),)``: the work grows as ``N``
        times the sample instead of ``N^2`` (not kept)."""
        if len(self.names) < 2:
            raise UserError("the spread of real poses needs at least two takes")
        step = -(-len(self.poses) // sample) if sample else 1
        if step == 1 and self._spread is not None:
            return self._spread
        rows = np.arange(0, len(self.poses), step)
        out = np.empty(len(rows))
        for i in range(0, len(rows), _BLOCK):
            check(cancelled)
            block = rows[i : i + _BLOCK]
            d = pose_distances(self.poses[block], self.poses)
            d[self.takes[block, None] == self.takes[None, :]] = np.inf
            out[i : i + _BLOCK] = d.min(1)
        if step == 1:
            self._spread = out
        return out

    def spread_summary(self, cancelled: CancelCheck | None = None, sample: int | None = None) -> dict:
        """Median and 95th percentile of :meth:`spread` (of ``sample`` poses, if given),
        centimetres."""
        s = 100.0 * self.spread(cancelled, sample)
        return {"median_cm": float(np.median(s)), "p95_cm": float(np.percentile(s, 95))}


def take_label(name: str) -> str:
    """A reference take's name for a report: its file and folder (``salsa/07.bvh``)."""
    return "/".join(Path(name).parts[-2:])


def validation_files(mocap: Path) -> list[Path]:
    """The 9 validation files under the mocap folder ``mocap``; a clear error naming the
    missing ones otherwise."""
    paths = [Path(mocap) / f for f in VALIDATION_FILES]
    missing = [str(p) for p in paths if not p.is_file()]
    if missing:
        raise UserError(
            f"validation file(s) not found: {', '.join(missing)} "
            f"(give the mocap folder that holds {VALIDATION_FILES[0]} and the others)"
        )
    return paths


def load_shipped(offsets: np.ndarray, stride: int = STRIDE, path: Path = SHIPPED) -> ReferenceSet:
    """The shipped validation poses (:data:`SHIPPED`), laid out on ``offsets (22, 3)``:
    the same set :func:`load_files` makes of the 9 files at ``stride``, which must be a
    multiple of the stored :data:`STRIDE`."""
    try:
        with np.load(Path(path), allow_pickle=False) as d:
            missing = [f for f in _SHIPPED_FIELDS if f not in d.files]
            if missing:
                raise UserError(f"{path}: not a reference pose file (no field {missing[0]!r})")
            data = {f: d[f] for f in _SHIPPED_FIELDS}
    except (OSError, ValueError) as exc:
        raise UserError(f"{path}: not a reference pose file ({exc})") from None
    stored = int(data["stride"])
    if stride < 1 or stride % stored:
        raise UserError(
            f"--reference-stride must be a multiple of {stored} with the shipped reference poses "
            f"(got {stride}); give --reference DIR for any other stride"
        )
    rot, take, names = data["local_rot"].astype(np.float64), data["take"], [str(n) for n in data["names"]]
    if rot.ndim != 3 or rot.shape[1:] != (sk.NUM_JOINTS, 4) or take.shape != rot.shape[:1]:
        raise UserError(f"{path}: local_rot must be (N, {sk.NUM_JOINTS}, 4) with one take per row")
    clips = [(name, rot[take == i][:: stride // stored]) for i, name in enumerate(names)]
    return ReferenceSet.from_rotations(
        clips, offsets, 1, True, f"{len(names)} validation files (shipped), every {stride}th frame, mirrored"
    )


def load_files(
    paths: list[Path],
    offsets: np.ndarray,
    stride: int = STRIDE,
    kind: str = "validation files",
    max_poses: int | None = None,
    cancelled: CancelCheck | None = None,
) -> ReferenceSet:
    """A reference set of motion files (any format :func:`load_motion` reads), one take each;
    ``kind`` names them in the description (e.g. "validation files", "files"). With
    ``max_poses``, the stride grows (from ``stride``) until the set, mirror images
    included, holds at most that many poses. ``cancelled`` is asked before each file."""
    from engine.motion.retarget import load_motion

    clips = []
    for p in paths:
        check(cancelled)
        clips.append((str(p), load_motion(p).local_rot))
    if max_poses:
        frames = sum(len(rot) for _, rot in clips)
        while 2 * sum(-(-len(rot) // stride) for _, rot in clips) > max_poses and stride < frames:
            stride += 1
    return ReferenceSet.from_rotations(
        clips, offsets, stride, True, f"{len(paths)} {kind}, every {stride}th frame, mirrored"
    )


def load_prepared(data_dir: Path, offsets: np.ndarray, stride: int = STRIDE) -> ReferenceSet:
    """The ``val`` split of a ``data prepare`` folder: its shards (mirrored copies
    included, as prepared), takes as its manifest names them."""
    from engine.training.data import read_manifest

    entries = [e for e in read_manifest(Path(data_dir))["files"] if e["split"] == "val"]
    if not entries:
        raise UserError(f"{data_dir}: no 'val' shards in manifest.json")
    clips = []
    for e in entries:
        path = Path(data_dir) / e["shard"]
        try:
            clips.append((str(e.get("take") or e["path"]), np.load(path)["local_rot"]))
        except (OSError, KeyError, ValueError) as exc:
            raise UserError(f"{path}: cannot read its local rotations ({exc})") from None
    originals = sum(not e["mirrored"] for e in entries)
    return ReferenceSet.from_rotations(
        clips,
        offsets,
        stride,
        False,
        f"{data_dir} val split ({originals} files and their mirrors), every {stride}th frame",
    )
