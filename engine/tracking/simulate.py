"""Simulated trackers from a ground-truth clip: noise, faulty sensors and tracking gaps.

Two failure models from the literature are reproduced:

* **Faulty sensors** (DragPoser, Ponton et al. 2024, sec. 5.2): every frame, with
  probability ``P``, one randomly chosen *connected* sensor disconnects; it reconnects
  100 frames later. Any sensor of the set can fail.
* **Tracking gaps** (RPM, Barquero et al. 2025, supplementary sec. C, the "HT"
  benchmark): *for each wrist (hand) sensor independently*, a gap starts at a given
  frame with probability 2.5 %; it lasts ``L ~ U(0.5, 2)`` seconds, and consecutive gaps
  of one sensor are at least 2 s apart (end of one to start of the next). RPM simulates
  hand-tracking losses, so only ``lwrist``/``rwrist`` lose tracking; a sensor set
  without hands gets no gaps. The probability is per frame at the clip's frame rate
  (60 fps for canonical clips, as RPM's A-P1 benchmark). No gap starts in the first
  second: RPM discards the first second of every sequence as warm-up, so every clip
  starts tracked.

While a sensor is disconnected its reading holds the last value it reported while
connected (what a real device would leave in its buffer); methods must ignore it.
Position-only (3-DoF) sensors report an identity rotation, so the ground truth never
leaks through them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion
from engine.sensors import Sensor, SensorFrame
from engine.tracking.presets import parse_sensors

#: Frames a faulty sensor stays disconnected (DragPoser sec. 5.2).
FAULTY_DOWN_FRAMES = 100
#: Per-frame probability that a hand-tracking gap starts (RPM supp. sec. C).
GAP_START_PROB = 0.025
#: Gap length range, seconds (RPM supp. sec. C).
GAP_SECONDS = (0.5, 2.0)
#: Minimum time between the end of a gap and the start of the next, seconds.
GAP_SPACING_S = 2.0
#: No gap starts before this time (RPM's warm-up padding), seconds.
GAP_WARMUP_S = 1.0
#: Sensors that lose tracking in the gaps model (RPM simulates hand-tracking losses).
GAP_JOINTS = ("lwrist", "rwrist")


@dataclass
class Tracking:
    """Simulated tracker stream of one clip.

    Attributes
    ----------
    joints : tuple of str, length S
        Canonical joint of each sensor.
    dof : tuple of int, length S
        6 (position + rotation) or 3 (position only) per sensor.
    positions : ndarray (F, S, 3)
        Reported world positions, metres (noisy if noise was asked for).
    rotations : ndarray (F, S, 4)
        Reported world rotations (w, x, y, z); identity for 3-DoF sensors.
    connected : ndarray (F, S) of bool
        False while a sensor is lost (faulty or in a gap).
    fps : float
        Frame rate of the clip, frames per second.
    """

    joints: tuple[str, ...]
    dof: tuple[int, ...]
    positions: np.ndarray
    rotations: np.ndarray
    connected: np.ndarray
    fps: float = sk.FPS

    def __len__(self) -> int:
        return self.positions.shape[0]

    def frame(self, i: int) -> SensorFrame:
        """All sensor readings of frame ``i`` (0-based)."""
        readings = {
            j: Sensor(
                joint=j,
                position=self.positions[i, s].copy(),
                rotation=self.rotations[i, s].copy(),
                dof=self.dof[s],
                connected=bool(self.connected[i, s]),
            )
            for s, j in enumerate(self.joints)
        }
        return SensorFrame(i, readings)

    def transitions(self) -> list[tuple[int, int, bool]]:
        """Tracking-state changes as ``(frame, sensor index, reconnected)``.

        ``frame`` is the first frame in the new state; ``reconnected`` is True for a
        synthesis-to-tracking change (S-T) and False for a loss (T-S).
        """
        c = self.connected.astype(np.int8)
        f, s = np.nonzero(np.diff(c, axis=0))
        return [(int(fi) + 1, int(si), bool(c[fi + 1, si])) for fi, si in zip(f, s)]


def _specs(sensors: str | Sequence[str | Sensor]) -> tuple[Sensor, ...]:
    if isinstance(sensors, str):
        return parse_sensors(sensors)
    out: list[Sensor] = []
    for s in sensors:
        out.extend(parse_sensors(s) if isinstance(s, str) else (s,))
    return parse_sensors(",".join(f"{s.joint}:{s.dof}" for s in out))


def faulty_mask(
    num_frames: int, num_sensors: int, prob: float, rng: np.random.Generator, down_frames: int = FAULTY_DOWN_FRAMES
) -> np.ndarray:
    """Connected mask ``(F, S)`` of the faulty-sensor model (DragPoser sec. 5.2).

    Each frame, with probability ``prob``, one uniformly chosen connected sensor
    disconnects for ``down_frames`` frames (including that frame). A sensor counts as
    connected again once it has been back for one frame, so losses never merge.
    """
    connected = np.ones((num_frames, num_sensors), dtype=bool)
    # first frame back online; a sensor can fail again only after one connected frame
    down_until = np.full(num_sensors, -1, dtype=np.int64)
    if prob <= 0 or num_sensors == 0:
        return connected
    fails = rng.random(num_frames) < prob
    for f in np.flatnonzero(fails):
        up = np.flatnonzero(down_until < f)
        if up.size == 0:
            continue
        s = up[rng.integers(up.size)]
        down_until[s] = f + down_frames
        connected[f : f + down_frames, s] = False
    return connected


def gap_mask(num_frames: int, fps: float, rng: np.random.Generator) -> np.ndarray:
    """Connected mask ``(F,)`` of one hand sensor under RPM's tracking-gap model."""
    connected = np.ones(num_frames, dtype=bool)
    lo, hi = (round(s * fps) for s in GAP_SECONDS)
    spacing = round(GAP_SPACING_S * fps)
    f = round(GAP_WARMUP_S * fps)
    starts = rng.random(num_frames) < GAP_START_PROB
    lengths = rng.integers(lo, hi + 1, size=num_frames)
    while f < num_frames:
        if starts[f]:
            connected[f : f + lengths[f]] = False
            f += lengths[f] + spacing
        else:
            f += 1
    return connected


def _hold_last(values: np.ndarray, connected: np.ndarray) -> np.ndarray:
    """Replace samples of lost frames by the last connected sample (per sensor)."""
    f = np.arange(values.shape[0])[:, None]
    last = np.where(connected, f, -1)
    last = np.maximum.accumulate(last, axis=0)
    last = np.where(last < 0, f, last)  # lost from the first frame: keep the true value
    return np.take_along_axis(values, last[..., None], axis=0)


def simulate(
    motion: Motion,
    sensors: str | Sequence[str | Sensor],
    noise_pos_m: float = 0.0,
    noise_rot_deg: float = 0.0,
    faulty: float = 0.0,
    gaps: bool = False,
    seed: int = 0,
) -> Tracking:
    """Trackers for ``motion`` from its forward kinematics, with optional failures.

    Parameters
    ----------
    motion : Motion
        Ground-truth clip (F frames).
    sensors : str or sequence of str / Sensor
        A preset name, a ``--sensors`` list (``"root,lwrist:3"``) or specs.
    noise_pos_m : float
        Standard deviation of the Gaussian noise added to each position axis, metres.
    noise_rot_deg : float
        Standard deviation, degrees, of each component of a random rotation vector
        applied to the reported rotations (6-DoF sensors only).
    faulty : float
        Per-frame probability that one connected sensor fails for 100 frames
        (DragPoser's faulty-sensor test uses 0.01 and 0.005).
    gaps : bool
        Simulate RPM's hand-tracking gaps (see module docs).
    seed : int
        Seed; the same seed gives the same stream. Noise, faults and gaps draw from
        independent streams, so turning noise on does not move the failures.

    Returns
    -------
    Tracking
    """
    specs = _specs(sensors)
    joints = tuple(s.joint for s in specs)
    dof = tuple(s.dof for s in specs)
    idx = [sk.JOINT_INDEX[j] for j in joints]
    g_pos, g_rot = motion.fk()
    pos = g_pos[:, idx].copy()
    rot = g_rot[:, idx].copy()
    n, s_count = pos.shape[:2]
    rng_noise, rng_fault, rng_gap = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3))

    if noise_pos_m > 0:
        pos += rng_noise.normal(0.0, noise_pos_m, size=pos.shape)
    if noise_rot_deg > 0:
        rv = rng_noise.normal(0.0, np.radians(noise_rot_deg), size=pos.shape)
        ang = np.linalg.norm(rv, axis=-1)
        axis = rv / np.maximum(ang[..., None], 1e-12)
        rot = Q.normalize(Q.mul(Q.from_axis_angle(axis, ang), rot))
    rot[:, [k for k, d in enumerate(dof) if d == 3]] = Q.identity()

    connected = faulty_mask(n, s_count, faulty, rng_fault)
    if gaps:
        for k, j in enumerate(joints):
            if j in GAP_JOINTS:
                connected[:, k] &= gap_mask(n, motion.fps, rng_gap)
    pos = _hold_last(pos, connected)
    rot = _hold_last(rot, connected)
    return Tracking(joints, dof, pos, Q.canonicalize(rot), connected, float(motion.fps))
