"""Reconstruction metrics: Pos, Rot, Vel, EE, Jitter, PJ and AUJ (pure numpy).

Definitions, formulas and units are in ``docs/metrics.md``. In short:

* ``pos_cm`` - mean world-space joint position error over the 22 joints, cm. No root
  alignment (DragPoser aligns the root; that variant is ``pos_rootaligned_cm``).
* ``rot_deg`` - mean geodesic angle between local joint rotations, 22 joints, degrees.
* ``vel_cms`` - mean norm of the joint velocity error (finite differences x fps), cm/s.
* ``ee_cm`` - mean world position error of head, hands and feet (ankles), cm.
* ``jitter`` / ``gt_jitter`` - mean norm of the joint jerk (third finite difference x
  fps^3), in RPM's unit of 10^2 m/s^3.
* ``pj`` / ``auj`` - peak and area (sum over frames) of the per-frame jerk curve in the
  1 s after each tracking-state change (RPM sec. 4), same jerk unit.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion import Motion

#: Jerk unit of RPM's tables: 10^2 m/s^3.
JERK_UNIT = 100.0
#: Window after a tracking-state change over which PJ / AUJ are taken, seconds (RPM sec. 4).
TRANSITION_WINDOW_S = 1.0

_EE = [sk.JOINT_INDEX[j] for j in sk.END_EFFECTORS]


def position_error_cm(gt_pos: np.ndarray, rec_pos: np.ndarray) -> np.ndarray:
    """Per-frame mean joint distance ``(F,)``, cm, from positions ``(F, J, 3)`` in metres."""
    return 100.0 * np.linalg.norm(rec_pos - gt_pos, axis=-1).mean(axis=-1)


def rotation_error_deg(gt_rot: np.ndarray, rec_rot: np.ndarray) -> np.ndarray:
    """Per-frame mean geodesic angle ``(F,)``, degrees, between quaternions ``(F, J, 4)``."""
    return np.degrees(Q.angle(Q.normalize(gt_rot), Q.normalize(rec_rot))).mean(axis=-1)


def velocity_error_cms(gt_pos: np.ndarray, rec_pos: np.ndarray, fps: float) -> np.ndarray:
    """Per-frame mean velocity error ``(F-1,)``, cm/s; velocities are ``diff x fps``."""
    dv = np.diff(rec_pos, axis=0) - np.diff(gt_pos, axis=0)
    return 100.0 * fps * np.linalg.norm(dv, axis=-1).mean(axis=-1)


def jerk_curve(pos: np.ndarray, fps: float) -> np.ndarray:
    """Mean joint jerk magnitude per frame ``(F,)`` in 10^2 m/s^3 (RPM's unit).

    Frame ``t`` holds the backward third difference
    ``p[t] - 3 p[t-1] + 3 p[t-2] - p[t-3]`` times ``fps^3``, so a change at frame ``t``
    shows from frame ``t`` on; the first three frames are NaN.
    """
    out = np.full(pos.shape[0], np.nan)
    if pos.shape[0] >= 4:
        d3 = np.diff(pos, n=3, axis=0) * fps**3
        out[3:] = np.linalg.norm(d3, axis=-1).mean(axis=-1) / JERK_UNIT
    return out


def transition_jerk(
    jerk: np.ndarray, connected: np.ndarray, fps: float, window_s: float = TRANSITION_WINDOW_S
) -> dict[str, float | int]:
    """Peak Jerk and Area Under the Jerk after tracking-state changes (RPM sec. 4).

    Parameters
    ----------
    jerk : ndarray (F,)
        :func:`jerk_curve` of the reconstruction, 10^2 m/s^3.
    connected : ndarray (F, S) of bool
        Per-frame tracking state of each sensor.
    fps : float
        Frames per second.
    window_s : float
        Window length after each change, seconds (RPM: 1 s).

    Returns
    -------
    dict
        ``pj`` / ``auj`` (mean over all changes), ``pj_ts`` / ``auj_ts`` (tracking to
        synthesis: a sensor lost), ``pj_st`` / ``auj_st`` (synthesis to tracking: a
        sensor recovered) and the counts ``transitions``, ``transitions_ts``,
        ``transitions_st``. PJ is the maximum of the curve in
        the window, AUJ its sum over the window's frames. Changes whose window runs past
        the clip end are skipped. Values are NaN when there is no complete window.
    """
    n = int(round(window_s * fps))
    c = np.asarray(connected, dtype=np.int8)
    f_idx, s_idx = np.nonzero(np.diff(c, axis=0))
    peaks: dict[bool, list[float]] = {True: [], False: []}
    areas: dict[bool, list[float]] = {True: [], False: []}
    for f, s in zip(f_idx + 1, s_idx):
        if f + n > len(jerk):
            continue
        w = jerk[f : f + n]
        if np.isnan(w).any():
            continue
        kind = bool(c[f, s])
        peaks[kind].append(float(w.max()))
        areas[kind].append(float(w.sum()))

    def mean(xs: list[float]) -> float:
        return float(np.mean(xs)) if xs else float("nan")

    return {
        "pj": mean(peaks[True] + peaks[False]),
        "auj": mean(areas[True] + areas[False]),
        "pj_ts": mean(peaks[False]),
        "auj_ts": mean(areas[False]),
        "pj_st": mean(peaks[True]),
        "auj_st": mean(areas[True]),
        "transitions": len(peaks[True]) + len(peaks[False]),
        "transitions_ts": len(peaks[False]),
        "transitions_st": len(peaks[True]),
    }


def evaluate_motion(
    gt: Motion, rec: Motion, connected: np.ndarray | None = None
) -> dict[str, float | int]:
    """All metrics of one reconstructed clip against its ground truth.

    Parameters
    ----------
    gt, rec : Motion
        Same number of frames; ``rec`` is FK'd with its own skeleton.
    connected : ndarray (F, S) of bool, optional
        Tracking state per sensor; when given, PJ / AUJ are added.

    Returns
    -------
    dict
        ``frames, pos_cm, pos_rootaligned_cm, rot_deg, vel_cms, ee_cm, jitter,
        gt_jitter`` (+ ``pj, auj, pj_ts, auj_ts, pj_st, auj_st, transitions``).
    """
    if len(gt) != len(rec):
        raise ValueError(f"ground truth has {len(gt)} frames, reconstruction {len(rec)}")
    if len(gt) < 4:
        raise ValueError(f"{gt.name or 'clip'}: metrics need at least 4 frames, got {len(gt)}")
    g_pos, _ = gt.fk()
    r_pos, _ = rec.fk()
    aligned = r_pos - r_pos[:, :1] + g_pos[:, :1]
    out: dict[str, float | int] = {
        "frames": len(gt),
        "pos_cm": float(position_error_cm(g_pos, r_pos).mean()),
        "pos_rootaligned_cm": float(position_error_cm(g_pos, aligned).mean()),
        "rot_deg": float(rotation_error_deg(gt.local_rot, rec.local_rot).mean()),
        "vel_cms": float(velocity_error_cms(g_pos, r_pos, gt.fps).mean()),
        "ee_cm": float(position_error_cm(g_pos[:, _EE], r_pos[:, _EE]).mean()),
        "jitter": float(np.nanmean(jerk_curve(r_pos, rec.fps))),
        "gt_jitter": float(np.nanmean(jerk_curve(g_pos, gt.fps))),
    }
    if connected is not None:
        out.update(transition_jerk(jerk_curve(r_pos, rec.fps), connected, rec.fps))
    return out


def _weight_key(key: str) -> str:
    """Which count a metric is averaged over: transitions for PJ / AUJ, else frames."""
    if key.startswith(("pj", "auj")):
        return "transitions" + key[key.index("_"):] if "_" in key else "transitions"
    return "frames"


def summarize(per_file: Mapping[str, Mapping[str, float]]) -> dict[str, float | int]:
    """Totals over files: counts summed, every other number a weighted mean.

    Most metrics are weighted by each file's ``frames``; PJ / AUJ are means over
    transitions, so they are weighted by the matching ``transitions*`` count. NaN
    values (no complete transition window) are left out.
    """
    files = list(per_file.values())
    if not files:
        return {"frames": 0}
    keys = [k for k in files[0] if all(k in f for f in files)]
    total: dict[str, float | int] = {}
    for k in keys:
        if k == "frames" or k.startswith("transitions"):
            total[k] = int(sum(f[k] for f in files))
            continue
        wk = _weight_key(k)
        vals = np.array([float(f[k]) for f in files])
        w = np.array([float(f.get(wk, f["frames"])) for f in files])
        ok = ~np.isnan(vals) & (w > 0)
        total[k] = float(np.average(vals[ok], weights=w[ok])) if ok.any() else float("nan")
    return total
