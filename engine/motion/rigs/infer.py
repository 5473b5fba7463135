"""Unit, up axis and root-channel convention of a BVH rig, inferred from the file itself.

Used for rigs mapped automatically (:mod:`engine.motion.rigs.automap`) and for mapping files
that leave these fields out; the TOML profiles state them explicitly.

* **Unit**: the leg (hip to knee to ankle, rest OFFSETs) of an adult is 0.65-1.1 m;
  the unit is the common one (metres, centimetres, millimetres, inches, or CMU's ASF
  unit of 1/0.45 inch) that puts the leg nearest 0.85 m on a log scale.
* **Up axis**: the axis (with sign) closest to the median head-minus-ankles direction
  over the clip's frames; the character's *left* is the axis closest to the median
  right-hip-to-left-hip direction, and forward is ``left x up`` (facing in the rest
  pose does not matter: only the root's heading changes with it).
* **Root channels**: some exporters (iClone) write root positions relative to the
  root OFFSET; the reading whose lowest feet (2nd percentile) sit nearer the floor wins.
"""

from __future__ import annotations

import numpy as np

from engine.kinematics.fk import fk

#: Candidate units: metres per file unit and their names.
UNITS = {1.0: "m", 0.01: "cm", 0.001: "mm", 0.0254: "inch", 0.0254 / 0.45: "CMU ASF unit (1/0.45 inch)"}
_TYPICAL_LEG_M = 0.85
_AXES = "xyz"


def infer_units(leg_length: float) -> tuple[float, str]:
    """Metres per file unit for a rig whose leg measures ``leg_length`` file units."""
    if not leg_length > 0:
        return 1.0, "leg length is zero; assuming metres"
    best = min(UNITS, key=lambda u: abs(np.log(leg_length * u / _TYPICAL_LEG_M)))
    return best, f"leg {leg_length:.4g} file units = {leg_length * best:.2f} m if the unit is {UNITS[best]}"


def _axis(v: np.ndarray, exclude: int | None = None) -> str:
    a = np.abs(v).astype(float)
    if exclude is not None:
        a[exclude] = -1.0
    k = int(np.argmax(a))
    return ("+" if v[k] >= 0 else "-") + _AXES[k]


def sample_positions(raw, relative_root: bool, max_frames: int = 240) -> np.ndarray:
    """World positions (F', J, 3) of the source joints in file units on a frame subsample."""
    step = max(1, raw.frames // max_frames)
    quats = raw.local_quaternions()[::step]
    pos = raw.positions[::step].copy()
    if relative_root:
        pos[:, 0] += raw.offsets[0]
    return fk(quats, pos[:, 0], raw.offsets, list(raw.parents))[0]


def infer_axes(raw, joints: dict[str, str]) -> tuple[str, str, bool, str]:
    """``(up, forward, root_relative, reason)`` from the clip's motion."""
    idx = {n: i for i, n in enumerate(raw.names)}
    pos = sample_positions(raw, False)
    feet = 0.5 * (pos[:, idx[joints["lankle"]]] + pos[:, idx[joints["rankle"]]])
    up = _axis(np.median(pos[:, idx[joints["upperneck"]]] - feet, axis=0))
    k = _AXES.index(up[1])
    left = _axis(np.median(pos[:, idx[joints["lhip"]]] - pos[:, idx[joints["rhip"]]], axis=0), exclude=k)
    u, lv = np.zeros(3), np.zeros(3)
    u[k] = 1.0 if up[0] == "+" else -1.0
    lv[_AXES.index(left[1])] = 1.0 if left[0] == "+" else -1.0
    forward = _axis(np.cross(lv, u))
    relative = False
    has_pos = any(c.endswith("position") for c in raw.channels[0])
    if has_pos and np.linalg.norm(raw.offsets[0]) > 0:
        sign = u[k]

        def floor_gap(rel: bool) -> float:
            p = sample_positions(raw, rel)
            low = np.minimum(p[:, idx[joints["lankle"]], k], p[:, idx[joints["rankle"]], k]) * sign
            return abs(float(np.percentile(low, 2)))

        relative = floor_gap(True) < floor_gap(False)
    why = f"up {up} (head above the ankles), left {left} (right hip to left hip), forward {forward}"
    if relative:
        why += "; root position channels are relative to the root OFFSET (feet nearer the floor)"
    return up, forward, relative, why
