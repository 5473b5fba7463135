"""Reconstruction metrics: Pos, Rot, Vel, EE, Jitter, PJ and AUJ (pure numpy).

Definitions, formulas and units are in ``docs/metrics.md``. In short:

* ``pos_cm`` - mean world-space joint position error over the 22 joints, cm. No root
  alignment (DragPoser aligns the root; that variant is ``pos_rootaligned_cm``).
* ``rot_deg`` - mean geodesic angle between local joint rotations, 22 joints, degrees.
* ``vel_cms`` - mean norm of the joint velocity error (finite differences x fps), cm/s.
* ``ee_cm`` - mean world position error of head, hands and feet (ankles), cm.
* ``jitter`` / ``gt_jitter`` - mean norm of the joint jerk (third finite difference x
  fps^3), in RPM's unit of 10^2 m/s^3.
* ``pj`` / ``auj`` - Peak Jerk and Area Under the Jerk after tracking-state changes as
  FlowMDM defines them and RPM (sec. 4) uses them: per frame the largest joint jerk (L1
  over x, y, z), the 1-s windows after the changes averaged into one curve, its maximum
  (PJ) and its summed absolute deviation from the ground truth's mean jerk (AUJ), same
  jerk unit. ``pj_raw`` / ``auj_raw`` are plain sums of the mean joint jerk over the same
  windows (:func:`transition_jerk_raw`), which count the motion's own jerk too.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion

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


def peak_jerk_curve(pos: np.ndarray, fps: float) -> np.ndarray:
    """Largest joint jerk per frame ``(F,)`` in 10^2 m/s^3: FlowMDM's transition jerk.

    Frame ``t`` holds ``max_j sum_xyz |p[t] - 3 p[t-1] + 3 p[t-2] - p[t-3]|`` times
    ``fps^3`` (the L1 norm over x, y, z of the backward third difference, then the
    largest joint), so a change at frame ``t`` shows from frame ``t`` on; the first
    three frames are NaN.
    """
    out = np.full(pos.shape[0], np.nan)
    if pos.shape[0] >= 4:
        d3 = np.diff(pos, n=3, axis=0) * fps**3
        out[3:] = np.abs(d3).sum(axis=-1).max(axis=-1) / JERK_UNIT
    return out


def _windows(jerk: np.ndarray, connected: np.ndarray, n: int) -> dict[bool, list[np.ndarray]]:
    """The ``n``-frame windows of ``jerk`` after each change of a sensor's state, by kind
    (True: the sensor was recovered, S-T; False: lost, T-S). Windows running past the
    clip end or over its NaN start are left out."""
    c = np.asarray(connected, dtype=np.int8)
    f_idx, s_idx = np.nonzero(np.diff(c, axis=0))
    out: dict[bool, list[np.ndarray]] = {True: [], False: []}
    for f, s in zip(f_idx + 1, s_idx):
        w = jerk[f : f + n]
        if len(w) == n and not np.isnan(w).any():
            out[bool(c[f, s])].append(w)
    return out


_KINDS = (("", (True, False)), ("_ts", (False,)), ("_st", (True,)))


def transition_jerk(
    jerk: np.ndarray,
    connected: np.ndarray,
    fps: float,
    gt_jerk: float,
    window_s: float = TRANSITION_WINDOW_S,
) -> dict[str, float | int | list[float]]:
    """Peak Jerk and Area Under the Jerk after tracking-state changes (FlowMDM, as RPM uses them).

    The windows after the changes are aligned at the change and averaged frame by frame
    into one mean curve ``m``; ``PJ = max_t m(t)`` and ``AUJ = sum_t |m(t) - gt_jerk|``.
    A reconstruction as smooth (and as jerky) as the real motion scores AUJ ~ 0.

    Parameters
    ----------
    jerk : ndarray (F,)
        :func:`peak_jerk_curve` of the reconstruction, 10^2 m/s^3.
    connected : ndarray (F, S) of bool
        Per-frame tracking state of each sensor.
    fps : float
        Frames per second.
    gt_jerk : float
        The ground truth's mean :func:`peak_jerk_curve`, 10^2 m/s^3.
    window_s : float
        Window length after each change, seconds (RPM: 1 s).

    Returns
    -------
    dict
        ``pj`` / ``auj`` (all changes), ``pj_ts`` / ``auj_ts`` (tracking to synthesis: a
        sensor lost), ``pj_st`` / ``auj_st`` (synthesis to tracking: a sensor recovered),
        the counts ``transitions``, ``transitions_ts``, ``transitions_st`` and the sums
        of the windows ``jerk_window_sum{,_ts,_st}`` (lists of ``n`` floats, for pooling
        files in :func:`summarize`). NaN when there is no complete window.
    """
    n = int(round(window_s * fps))
    wins = _windows(jerk, connected, n)
    out: dict[str, float | int | list[float]] = {}
    for suffix, kinds in _KINDS:
        ws = [w for k in kinds for w in wins[k]]
        total = np.sum(ws, axis=0) if ws else np.zeros(n)
        out["transitions" + suffix] = len(ws)
        out["jerk_window_sum" + suffix] = total.tolist()
        out.update(_peak_and_area(total, len(ws), gt_jerk, suffix))
    return out


def _peak_and_area(window_sum: np.ndarray, count: int, gt_jerk: float, suffix: str) -> dict[str, float]:
    if count == 0:
        return {"pj" + suffix: float("nan"), "auj" + suffix: float("nan")}
    m = np.asarray(window_sum, dtype=np.float64) / count
    return {"pj" + suffix: float(m.max()), "auj" + suffix: float(np.abs(m - gt_jerk).sum())}


def transition_jerk_raw(
    jerk: np.ndarray, connected: np.ndarray, fps: float, window_s: float = TRANSITION_WINDOW_S
) -> dict[str, float]:
    """Plain-sum PJ / AUJ (``pj_raw`` / ``auj_raw`` {,``_ts``, ``_st``}), beside FlowMDM's.

    Per change, the peak and the plain sum of the :func:`jerk_curve` (mean joint jerk)
    over the window, then the mean over changes; NaN without a complete window.
    """
    wins = _windows(jerk, connected, int(round(window_s * fps)))
    out: dict[str, float] = {}
    for suffix, kinds in _KINDS:
        ws = [w for k in kinds for w in wins[k]]
        out["pj_raw" + suffix] = float(np.mean([w.max() for w in ws])) if ws else float("nan")
        out["auj_raw" + suffix] = float(np.mean([w.sum() for w in ws])) if ws else float("nan")
    return out


def evaluate_motion(
    gt: Motion, rec: Motion, connected: np.ndarray | None = None
) -> dict[str, float | int | list[float]]:
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
        gt_jitter, gt_jerk`` (+ the keys of :func:`transition_jerk` and
        :func:`transition_jerk_raw`, and ``gt_pj, gt_auj, gt_jerk_window_sum``: the
        ground truth's own PJ / AUJ at the same changes, the floor of the figure).
        ``gt_jerk`` is the ground truth's mean :func:`peak_jerk_curve`, AUJ's reference.
    """
    if len(gt) != len(rec):
        raise ValueError(f"ground truth has {len(gt)} frames, reconstruction {len(rec)}")
    if len(gt) < 4:
        raise ValueError(f"{gt.name or 'clip'}: metrics need at least 4 frames, got {len(gt)}")
    g_pos, _ = gt.fk()
    r_pos, _ = rec.fk()
    aligned = r_pos - r_pos[:, :1] + g_pos[:, :1]
    gt_jerk = float(np.nanmean(peak_jerk_curve(g_pos, gt.fps)))
    out: dict[str, float | int | list[float]] = {
        "frames": len(gt),
        "pos_cm": float(position_error_cm(g_pos, r_pos).mean()),
        "pos_rootaligned_cm": float(position_error_cm(g_pos, aligned).mean()),
        "rot_deg": float(rotation_error_deg(gt.local_rot, rec.local_rot).mean()),
        "vel_cms": float(velocity_error_cms(g_pos, r_pos, gt.fps).mean()),
        "ee_cm": float(position_error_cm(g_pos[:, _EE], r_pos[:, _EE]).mean()),
        "jitter": float(np.nanmean(jerk_curve(r_pos, rec.fps))),
        "gt_jitter": float(np.nanmean(jerk_curve(g_pos, gt.fps))),
        "gt_jerk": gt_jerk,
    }
    if connected is not None:
        out.update(transition_jerk(peak_jerk_curve(r_pos, rec.fps), connected, rec.fps, gt_jerk))
        own = transition_jerk(peak_jerk_curve(g_pos, gt.fps), connected, gt.fps, gt_jerk)
        out.update({"gt_" + k: own[k] for k in ("pj", "auj", "jerk_window_sum")})
        out.update(transition_jerk_raw(jerk_curve(r_pos, rec.fps), connected, rec.fps))
    return out


def _weight_key(key: str) -> str:
    """Which count a metric is averaged over: transitions for PJ / AUJ, else frames."""
    if key.startswith(("pj", "auj")):
        return "transitions" + next((x for x in ("_ts", "_st") if key.endswith(x)), "")
    return "frames"


def summarize(per_file: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """Totals over files: counts summed, every other number a weighted mean.

    Most metrics are weighted by each file's ``frames``; ``pj_raw`` / ``auj_raw`` are
    means over transitions, so they are weighted by the matching ``transitions*``
    count. PJ / AUJ are recomputed from the files' pooled ``jerk_window_sum*`` (one
    mean curve over all the run's transitions; ``gt_pj`` / ``gt_auj`` likewise) against
    the run's ``gt_jerk`` (the frame-weighted mean of the files'). NaN values are left out.
    """
    files = list(per_file.values())
    if not files:
        return {"frames": 0}
    keys = [k for k in files[0] if all(k in f for f in files)]
    total: dict[str, Any] = {}
    for k in keys:
        if isinstance(files[0][k], list):
            total[k] = np.sum([f[k] for f in files], axis=0).tolist()
            continue
        if k == "frames" or k.startswith("transitions"):
            total[k] = int(sum(f[k] for f in files))
            continue
        wk = _weight_key(k)
        vals = np.array([float(f[k]) for f in files])
        w = np.array([float(f.get(wk, f["frames"])) for f in files])
        ok = ~np.isnan(vals) & (w > 0)
        total[k] = float(np.average(vals[ok], weights=w[ok])) if ok.any() else float("nan")
    for prefix, suffix in [("", x) for x, _ in _KINDS] + [("gt_", "")]:
        if prefix + "jerk_window_sum" + suffix in total and "gt_jerk" in total:
            window_sum = np.asarray(total[prefix + "jerk_window_sum" + suffix])
            pa = _peak_and_area(window_sum, total["transitions" + suffix], total["gt_jerk"], suffix)
            total.update({prefix + k: v for k, v in pa.items()})
    return total
