"""What retargeting needs to know about a source before it starts: the definition to use
(the model card's :class:`~engine.motion.retarget_strategy.RetargetStrategy`), the true
frame rate, and whether the file opens with a rest frame.

Re-exported by :mod:`engine.motion.retarget`, where callers find them.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from engine.errors import UserError
from engine.input_files import read_json, read_toml
from engine.kinematics import quaternion as Q
from engine.motion.bvh import RawBVH
from engine.motion.retarget_strategy import CURRENT, STRATEGIES, RetargetStrategy
from engine.validation import check_manifest, shown

#: Where the shipped models record the definition they learnt from (``retarget_version``).
MODELS_DATA = Path(__file__).resolve().parents[2] / "assets" / "models" / "data.toml"


def models_strategy(path: Path = MODELS_DATA) -> RetargetStrategy:
    """The retargeting strategy every command feeding the shipped models uses by default
    (``retarget_version`` in :data:`MODELS_DATA`, beside the version they were trained on);
    :data:`CURRENT` when the file is absent."""
    if not path.is_file():
        return CURRENT
    version = read_toml(path, "model data card").get("retarget_version", CURRENT.version)
    if version not in STRATEGIES:
        raise UserError(
            f"{path}: retarget_version must be one of {', '.join(map(str, STRATEGIES))} "
            f"(the definitions this program produces), got {shown(version)}"
        )
    return STRATEGIES[version]


def rest_frame_count(raw: RawBVH) -> int:
    """Leading frames (0 to 2) of the file that hold its rig's rest pose rather than motion.

    Conversions such as the cgspeed CMU files start with the rig's rest pose: root
    rotation exactly zero in frame 0, then a jump to the motion larger than its own steps
    (more than 2 degrees per joint on average and 3 times the median step of the first 200
    frames). A second jump right after counts too (a rest frame followed by a half-way one)."""
    if raw.frames < 8 or np.any(raw.rotations_deg[0, 0] != 0.0):
        return 0
    q = raw.local_quaternions()[:201]
    steps = np.degrees(Q.angle(q[1:], q[:-1])).mean(-1)
    jump = 3.0 * float(np.median(steps))
    n = 0
    while n < 2 and steps[n] > max(2.0, jump):
        n += 1
    return n


def snap_fps(fps: float) -> float:
    """Headers store a rounded frame time (0.008333 s); snap to the whole rate it means."""
    return float(round(fps)) if abs(fps - round(fps)) < 1e-3 * fps else fps


def manifest_entry(path: Path) -> dict | None:
    """The entry of ``path`` in a ``manifest.json`` of one of its parent folders (the shared
    data's lists ``fps``, ``cmu_trial``...), or None.

    A malformed manifest (not an object, ``files`` not a list, an fps outside 1-1000)
    is a :class:`UserError` naming it and the entry (:func:`engine.validation.check_manifest`)."""
    try:
        path = Path(path).resolve()
    except (OSError, RuntimeError):  # a symlink loop: load_bvh names it
        return None
    for parent in list(path.parents)[:4]:
        man = parent / "manifest.json"
        if not man.is_file():
            continue
        stat = man.stat()
        entries = _manifest_entries(str(man), stat.st_mtime_ns, stat.st_size)
        rel = path.relative_to(parent).as_posix()
        for entry in entries:
            listed = str(entry.get("path", ""))
            # paths are relative to the manifest's folder or to the data folder above it
            if listed == rel or listed.endswith("/" + rel):
                return dict(entry)
    return None


@functools.lru_cache(maxsize=8)
def _manifest_entries(man: str, mtime_ns: int, size: int) -> tuple[dict, ...]:
    """The checked entries of one manifest, read once per version of the file (``data
    prepare`` looks up every file of a folder of hundreds in the same manifest)."""
    return tuple(check_manifest(read_json(man, "manifest"), man))


def manifest_fps(path: Path) -> float | None:
    """True frame rate of ``path`` from its :func:`manifest_entry`, or None."""
    entry = manifest_entry(path)
    return float(entry["fps"]) if entry and entry.get("fps") else None
