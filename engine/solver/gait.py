"""Legs that step when the body travels: a gait planner for sets without foot trackers.

With head and hands (or hips, head and hands) the legs are not measured, and the solver
guesses them from the upper body: when the performer walks, the guessed feet glide along
under the body instead of stepping. The :class:`GaitPlanner` reads the travel of an
anchor tracker (the hips' when connected, else the head's) and gives the ``gait`` term
(:mod:`engine.constraints.gait`) a target per ankle every frame:

* **Speed and heading.** The anchor's horizontal velocity over the last
  :attr:`GaitParams.window_s` seconds. Below :attr:`GaitParams.on_speed` the planner is
  off (the targets' weights are 0: standing, dancing and turning on the spot are left to
  the solver as before); it fades in up to :attr:`GaitParams.full_speed`.
* **Phase.** One foot is in stance, the other swings. Walkers swing each arm with the
  opposite leg, so while the left hand moves forward relative to the right one (along the
  travel, over :attr:`GaitParams.arm_lag_s`), the left foot stands
  (:meth:`GaitPlanner.arm_stance`); the roles swap when the arms say so and the step has
  lasted :attr:`GaitParams.min_step_s`, after the step time ``T``
  (:meth:`GaitParams.step_time`: about 0.5 s at a walk) when the arms do not
  swing (hands still or not tracked), and whenever the body has left the stance foot more
  than :attr:`GaitParams.max_reach` behind. When the planner starts, the arms (else the
  lower foot of the previous solved pose) pick the stance foot. On the walking clips the
  arms name the truth's slower foot in 73-96 % of the travelling frames; a head-height
  rule (swap at the head's low points, which fall within 0-3 frames of a landing on a
  walk) did worse in the solve (research/README.md, *Legs from the head*).
* **Stance foot planted.** Its target is where the swing foot was headed when it landed
  (under its hip, :attr:`GaitParams.lead_s` of travel ahead), fixed for the whole stance,
  so it does not skate while the body moves on.
* **Swaps without jumps.** The arms or the classifier often swap the feet before the swing
  target has reached its landing spot, so the landed foot's target glides there from the
  swing target's last position over :attr:`GaitParams.settle_s`, and the two ankles'
  weights trade places over :attr:`GaitParams.ramp_s` (a step in the targets or the weights
  is a jerk in the solved legs: with both stepped the walks' mean joint jerk is 30 % above
  the term's absence, with both eased 8 %; docs/optimizer.md, *Swaps without jumps*).
* **Swing foot on its way.** Its target moves, along a quintic ease of the phase (zero
  velocity and acceleration at both ends), from where it lifted off to its landing spot: under its own hip (previous solved pose) carried
  ahead by the velocity over the rest of the step and :attr:`GaitParams.lead_s` more
  (Raibert's foot-placement rule: the foot lands ahead of the hips by part of a stance's
  travel), so the stride grows with speed. "Under its hip" is 30 % of the way from the
  pelvis to the hip joint: feet land nearly under the pelvis.

* **Standing legs** (setting ``stand_weight``, the hip profiles). While the anchor travels
  slower than :attr:`GaitParams.stand_speed` each ankle is also pulled under its hip
  joint, fading out by :attr:`GaitParams.stand_off_speed`: a standing or slowly stepping
  performer's legs hang nearly straight, where the pose bank's guess for motion it does not
  hold bends or lifts them. Where the bank does hold such motion (its neighbours are near
  the readings: :attr:`GaitParams.stand_near`, :attr:`GaitParams.stand_far`) its legs are
  better and the pull stays off. Without a hip tracker the pull moves the guessed pelvis
  instead, so the head profile leaves it off (docs/optimizer.md, *Standing legs*).

Only the horizontal position is targeted (heights are the ``ground`` term's and the
decoder's). Everything here is numpy and reads only this frame's and earlier readings and
solved poses, so it works live.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.constraints.gait import ANKLES, GaitTargets
from engine.models.stance import StanceModel, stance_features, window_frames

#: The hips the ankles (:data:`~engine.constraints.gait.ANKLES`) hang from, left, right.
HIPS = (sk.JOINT_INDEX["lhip"], sk.JOINT_INDEX["rhip"])


@dataclass(frozen=True)
class GaitParams:
    """The planner's constants (SI units: metres, seconds, metres per second).

    ``window_s``: the anchor velocity's window; ``on_speed`` / ``full_speed``: where the
    planner starts and reaches full weight; ``max_reach``: how far the hip may leave the
    stance foot before the feet swap; ``stance_weight`` / ``swing_weight``: the two ankles'
    shares of ``gait_weight``; ``arm_lag_s`` / ``arm_speed``: the window and the least
    fore-aft speed of the hands' difference that count as an arm swing; ``min_step_s``:
    the shortest step; ``lead_s``: how far (in travel time) ahead of its hip a foot lands;
    ``lateral_share``: where between the pelvis (0) and the hip joint (1) it lands;
    ``stance_confidence``: the least probability of the stance classifier's answer that
    counts (below it the classifier says nothing); ``run_speed`` / ``stop_speed``: where the
    planner starts to fade out and is off again, at a run (a run has a flight phase, and
    planting a foot for a whole stance at 3 m/s tore the pose: CMU runs went from 5-7 to
    19-27 cm of Pos with the term on); ``settle_s``: how long a landed foot's target takes
    to glide from the swing target's last position to the landing spot; ``ramp_s``: how long the
    two ankles' weights take to trade places after a swap (0: at once); ``stand_speed`` /
    ``stand_off_speed``: where the standing-legs pull starts to fade out and is off;
    ``stand_near`` / ``stand_far``: the pose bank's distance to the readings
    (:meth:`~engine.solver.tracker_prior.PoseBank.lookup`) up to which the pull is off and
    from which it is full: where the bank knows motion like this, its legs are better.
    """

    window_s: float = 0.25
    on_speed: float = 0.35
    full_speed: float = 0.7
    max_reach: float = 0.55
    stance_weight: float = 1.0
    swing_weight: float = 0.3
    arm_lag_s: float = 0.1
    arm_speed: float = 0.1
    min_step_s: float = 0.2
    lead_s: float = 0.3
    lateral_share: float = 0.3
    stance_confidence: float = 0.75
    run_speed: float = 1.8
    stop_speed: float = 2.2
    settle_s: float = 0.1
    ramp_s: float = 0.07
    stand_speed: float = 0.6
    stand_off_speed: float = 1.2
    stand_near: float = 2.0
    stand_far: float = 3.0

    def step_time(self, speed: float) -> float:
        """Seconds per step at ``speed`` m/s: 0.55 s at 0.7 m/s, 0.49 s at 1.3, 0.3 s
        when running (cadence rises with speed)."""
        return float(np.clip(0.62 - 0.1 * speed, 0.3, 0.6))

    def activity(self, speed: float) -> float:
        """0 below :attr:`on_speed` and above :attr:`stop_speed`, 1 from :attr:`full_speed`
        to :attr:`run_speed`, smoothsteps between."""

        return _rise(speed, self.on_speed, self.full_speed) * (1.0 - _rise(speed, self.run_speed, self.stop_speed))

    def standing(self, speed: float, distance: float | None = None) -> float:
        """The standing-legs pull's share: 1 up to :attr:`stand_speed`, 0 from
        :attr:`stand_off_speed`, a smoothstep between; times a smoothstep from 0 at
        :attr:`stand_near` to 1 at :attr:`stand_far` of the pose bank's ``distance``
        (None: no bank lookup this frame, no such factor)."""
        share = 1.0 - _rise(speed, self.stand_speed, self.stand_off_speed)
        return share if distance is None else share * _rise(distance, self.stand_near, self.stand_far)


class GaitPlanner:
    """Stance and swing targets for the ankles from an anchor's travel (module doc).

    Parameters
    ----------
    fps : float
        Frames per second of the readings.
    params : GaitParams, optional
    """

    def __init__(self, fps: float, params: GaitParams | None = None, stance: StanceModel | None = None) -> None:
        self.fps = float(fps)
        self.params = params or GaitParams()
        self.stance = stance
        self.reset()

    def reset(self) -> None:
        n = max(2, round(self.params.window_s * self.fps) + 1)
        self._anchor: deque[np.ndarray] = deque(maxlen=n)
        self._hands: deque[np.ndarray] = deque(maxlen=max(2, round(self.params.arm_lag_s * self.fps) + 1))
        self._window: deque[np.ndarray] = deque(maxlen=window_frames(self.fps))
        self._stance: int | None = None
        self._planted = np.zeros(3)
        self._lift = np.zeros(3)
        self._elapsed = 0
        self._swapped = False  # the stance began at a swap (not at the planner's start)
        self._settle_from = np.zeros(2)
        self._last = np.zeros((2, 3))  # the last frame's targets

    def velocity(self) -> np.ndarray:
        """The anchor's horizontal velocity ``(2,)``, m/s, over the window (0 until two readings)."""
        if len(self._anchor) < 2:
            return np.zeros(2)
        return (self._anchor[-1] - self._anchor[0]) * self.fps / (len(self._anchor) - 1)

    def arm_stance(self, v: np.ndarray) -> int | None:
        """The stance foot :func:`arm_swing` says (0 left, 1 right) from the hands' last
        :attr:`GaitParams.arm_lag_s` along the travel ``v (2,)``, or None when the arms do
        not swing (or are not tracked)."""
        if len(self._hands) < 2 or not np.all(np.isfinite(self._hands[0])):
            return None
        change = (self._hands[-1] - self._hands[0])[None]
        left = int(arm_swing(change, v[None], self.fps, len(self._hands) - 1, self.params.arm_speed)[0])
        return None if left < 0 else 1 - left

    def learned_stance(self) -> int | None:
        """The stance foot the classifier (:mod:`engine.models.stance`) names from the head's
        and hands' last half second (0 left, 1 right), or None: no classifier, not a full
        window yet, or an answer below :attr:`GaitParams.stance_confidence`."""
        if self.stance is None or len(self._window) < (self._window.maxlen or 0):
            return None
        w = np.array(self._window)  # (K, 3, 3): head, left hand, right hand
        x = stance_features(w[:, 0], w[:, 1:], self.fps)
        if x is None:
            return None
        p = float(self.stance.left_stance(x))
        c = self.params.stance_confidence
        return 0 if p >= c else 1 if p <= 1.0 - c else None

    def update(
        self,
        anchor: np.ndarray | None,
        previous: np.ndarray | None,
        hands: np.ndarray | None = None,
        head: np.ndarray | None = None,
        *,
        walk: bool = True,
        stand: float = 0.0,
        distance: float | None = None,
    ) -> GaitTargets:
        """Advance one frame and give its targets.

        Parameters
        ----------
        anchor : ndarray (3,) or None
            This frame's anchor tracker position, metres (None: not connected; the
            planner stops and forgets the anchor's history).
        previous : ndarray (22, 3) or None
            The previous frame's solved joint positions (None on the first frame).
        hands : ndarray (2, 3) or None
            The left and right hand trackers' positions (None: not both connected; the
            steps then follow the step time alone).
        head : ndarray (3,) or None
            The head tracker's position (None: not connected); with the hands it feeds
            the stance classifier, whose confident answer goes before the arms' swing.
        walk : bool
            Plan steps (False: the stepping targets stay off).
        stand : float
            The standing-legs pull's weight relative to the stepping targets' (0: off):
            while the anchor travels slowly each ankle is also pulled horizontally under
            its hip joint (:meth:`GaitParams.standing`); where both act, an ankle's target
            is their weighted mean and its weight their sum.
        distance : float or None
            The pose bank's distance to this frame's readings (None: the bank gave no
            prior); near ones leave the legs to the bank (:meth:`GaitParams.standing`).
        """
        if anchor is None or previous is None or not np.all(np.isfinite(anchor)):
            self.reset()
            return GaitTargets.off()
        self._anchor.append(np.asarray(anchor, dtype=np.float64)[:2].copy())
        if hands is None:
            self._hands.clear()
        else:
            self._hands.append(np.asarray(hands[0, :2] - hands[1, :2], dtype=np.float64))
        if hands is None or head is None or not (np.all(np.isfinite(hands)) and np.all(np.isfinite(head))):
            self._window.clear()
        else:
            self._window.append(np.vstack([np.asarray(head, dtype=np.float64)[None], hands]))
        p = self.params
        v = self.velocity()
        speed = float(np.linalg.norm(v))
        a = p.activity(speed) if walk else 0.0
        standing = _StandingPull(previous[list(HIPS), :2], stand * p.standing(speed, distance))
        if a <= 0.0:
            self._stance = None
            return standing.apply(GaitTargets.off())
        ankles = previous[list(ANKLES)]
        # feet land nearly under the pelvis: 2 cm outwards of its centre on average, ~5 cm
        # inside their hips (touch-downs of 9 walking clips)
        root = previous[sk.JOINT_INDEX["root"]]
        hips = root + p.lateral_share * (previous[list(HIPS)] - root)
        learned = self.learned_stance()
        arms = self.arm_stance(v) if learned is None else learned
        if self._stance is None:  # starting: as the arms say, else the lower foot stands
            stance = int(np.argmin(ankles[:, 2])) if arms is None else arms
            self._start(stance, ankles[stance], ankles[1 - stance])
        step_s = p.step_time(speed)
        step = max(1, round(step_s * self.fps))
        self._elapsed += 1
        s = self._stance
        assert s is not None  # set by _start above on the first frame
        behind = np.linalg.norm(hips[s, :2] - self._planted[:2])
        lasted = self._elapsed > p.min_step_s * self.fps
        swap = (arms is not None and arms != s and lasted) or (arms is None and self._elapsed > step)
        if swap or behind > p.max_reach:
            # the swing foot lands where it was headed now (its target, not where the solve
            # left it: the solved foot lags its target, and planting it there left the stance
            # foot 18 cm behind the truth's on a walk)
            landed = np.r_[hips[1 - s, :2] + v * p.lead_s, ankles[1 - s, 2]]
            self._start(1 - s, landed, np.r_[self._last[s, :2], self._planted[2]])
            self._swapped, self._settle_from = True, self._last[1 - s, :2].copy()
            self._elapsed = 1
            s = 1 - s
        w = 1 - s
        phase = min(1.0, self._elapsed / step)
        remaining = max(0.0, (step - self._elapsed) / self.fps)
        landing = hips[w, :2] + v * (remaining + p.lead_s)
        target = np.zeros((2, 3))
        target[s] = self._planted
        # a landed foot's target glides from the swing target's last position, so it does not
        # jump when the swap comes before the swing has reached its landing spot
        settle = self._ease(self._elapsed, p.settle_s)
        if settle < 1.0:
            target[s, :2] = self._settle_from + (self._planted[:2] - self._settle_from) * settle
        target[w, :2] = self._lift[:2] + (landing - self._lift[:2]) * _smootherstep(phase)
        target[w, 2] = ankles[w, 2]
        self._last = target.copy()
        # the weights trade places over ramp_s: a step in the weight snaps the solved foot,
        # which lags its swing target, onto its new stance target in one frame
        r = self._ease(self._elapsed, p.ramp_s)
        scale = np.zeros((2, 3))
        scale[s, :2] = np.sqrt(a * (p.swing_weight + r * (p.stance_weight - p.swing_weight)))
        scale[w, :2] = np.sqrt(a * (p.stance_weight + r * (p.swing_weight - p.stance_weight)))
        return standing.apply(GaitTargets(target, scale, s, phase))

    def _ease(self, frames: int, seconds: float) -> float:
        """A smoothstep from 0 to 1 over ``seconds`` after a swap, at ``frames`` frames into
        the stance; 1 when the stance began at the planner's start or ``seconds`` is 0."""
        n = round(seconds * self.fps)
        return 1.0 if not self._swapped or frames >= n else _rise(frames, 0.0, n)

    def _start(self, stance: int, planted: np.ndarray, lift: np.ndarray) -> None:
        """``stance`` plants at ``planted (3,)``; the other foot lifts off from ``lift (3,)``."""
        self._stance = stance
        self._planted = np.array(planted, dtype=np.float64)
        self._lift = np.array(lift, dtype=np.float64)
        self._elapsed = 0
        self._swapped = False


@dataclass(frozen=True)
class _StandingPull:
    """Each ankle pulled horizontally under its hip joint, ``under (2, 2)``, with the
    relative weight ``weight`` (0: no pull)."""

    under: np.ndarray
    weight: float

    def apply(self, t: GaitTargets) -> GaitTargets:
        """``t`` with the pull added: the sum of two quadratic pulls on an axis is one pull
        towards their weighted mean, weighted by their sum."""
        if self.weight <= 0.0:
            return t
        own = t.scale[:, :2] ** 2
        total = own + self.weight
        target, scale = t.target.copy(), t.scale.copy()
        target[:, :2] = (own * t.target[:, :2] + self.weight * self.under) / total
        scale[:, :2] = np.sqrt(total)
        return GaitTargets(target, scale, t.stance, t.phase)


def _rise(x: float, lo: float, hi: float) -> float:
    """A smoothstep of ``x`` from 0 at ``lo`` to 1 at ``hi``."""
    t = float(np.clip((x - lo) / (hi - lo), 0.0, 1.0))
    return t * t * (3.0 - 2.0 * t)


def arm_swing(change: np.ndarray, travel: np.ndarray, fps: float, frames: int, arm_speed: float) -> np.ndarray:
    """The arm-swing rule, per sample ``(N,)``: 1 when it says the left foot stands, 0 the
    right, -1 when the arms do not swing (a fore-aft speed below ``arm_speed`` m/s).
    ``change (N, 2)`` is how the left hand's horizontal position minus the right one's
    changed over the last ``frames`` frames at ``fps``, ``travel (N, 2)`` the direction of
    travel (any length). Walkers swing each arm with the opposite leg, so while the left
    hand moves forward relative to the right one, the right foot swings and the left one
    stands (on the walking clips the rule names the truth's slower foot in 73-94 % of the
    travelling frames). The gait planner asks it of one frame, the stance training
    (:mod:`engine.training.stance`) of every frame of a clip."""
    fwd = travel / np.maximum(np.linalg.norm(travel, axis=-1, keepdims=True), 1e-9)
    rate = np.einsum("ij,ij->i", change, fwd) * fps / frames
    return np.where(np.abs(rate) < arm_speed, -1, (rate > 0).astype(int))


def _smootherstep(t: float) -> float:
    """Perlin's quintic ease, 0 to 1 with zero velocity and acceleration at both ends (the
    cubic smoothstep's acceleration jumps at the ends, a jerk the swing foot passes on)."""
    return t * t * t * (10.0 - 15.0 * t + 6.0 * t * t)
