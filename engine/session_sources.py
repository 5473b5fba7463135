"""Where the session's clip and sensor presets come from (engine modules, or stand-ins).

Presets and per-sensor DoF come from :mod:`engine.tracking`; clips are loaded with
:func:`engine.retarget.load_motion`, or read directly by pymotion when the file is
already on the canonical rig and the BVH reader is not installed.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.motion import Motion

#: Sensor presets used until :mod:`engine.tracking` provides its own.
FALLBACK_PRESETS: dict[str, tuple[str, ...]] = {
    "6 (hips, head, hands, feet)": ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"),
    "4 (hips, head, hands)": ("root", "upperneck", "lwrist", "rwrist"),
    "3 (head, hands)": ("upperneck", "lwrist", "rwrist"),
    "3 (hips, hands)": ("root", "lwrist", "rwrist"),
}


def sensor_presets() -> dict[str, tuple[str, ...]]:
    """Preset name -> joints, from :mod:`engine.tracking` when it provides them."""
    try:
        tracking = importlib.import_module("engine.tracking")
    except ImportError:
        return dict(FALLBACK_PRESETS)
    for attr in ("PRESETS", "presets"):
        presets = getattr(tracking, attr, None)
        if isinstance(presets, dict) and presets:
            return {str(k): tuple(v) for k, v in presets.items()}
    return dict(FALLBACK_PRESETS)


def _preset_dofs(name: str) -> dict[str, int]:
    """Degrees of freedom per joint of a preset (6 unless the tracking module says 3)."""
    try:
        from engine.tracking import PRESET_SENSORS  # type: ignore[attr-defined]
    except ImportError:
        return {}
    return {spec.joint: int(spec.dof) for spec in PRESET_SENSORS.get(name, ())}


def load_clip(path: str | Path) -> Motion:
    """Load any supported BVH onto the canonical skeleton (60 fps, floor at z = 0).

    Raises
    ------
    UserError
        When the file is missing, malformed or of an unknown rig; the message names it.
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    try:
        from engine.retarget import load_motion
    except ImportError:  # the BVH reader has not landed yet: canonical-rig files only
        load_motion = _load_canonical_bvh
    try:
        return load_motion(path)
    except UserError:
        raise
    except Exception as exc:  # a malformed file must never take the studio down
        raise UserError(f"{path}: cannot read ({type(exc).__name__}: {exc})") from exc


def _load_canonical_bvh(path: Path) -> Motion:
    """Stand-in reader for BVH files already on the canonical rig (pymotion, no retarget)."""
    from pymotion.io.bvh import BVH

    bvh = BVH()
    bvh.load(str(path))
    names = tuple(str(n) for n in bvh.data["names"])
    if names != sk.JOINT_NAMES:
        raise UserError(f"{path}: not on the canonical rig (joints {', '.join(names[:4])}...)")
    rot, pos, _, offsets, _, _ = bvh.get_data()
    step = max(int(round(1.0 / float(bvh.data["frame_time"]) / sk.FPS)), 1)
    rot, root = rot[::step], pos[::step, 0].copy()
    motion = Motion(rot, root, sk.Skeleton(np.asarray(offsets, float)), sk.FPS, path.stem)
    p = motion.positions()
    toes = p[:, [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]], 2].min(axis=1)
    motion.root_pos[:, 2] -= np.percentile(toes, 2) - 0.045  # same re-flooring rule as retarget
    return motion
