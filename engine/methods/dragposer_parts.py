"""The collaborators of :class:`engine.methods.dragposer.DragPoserMethod`, one job each.

* :class:`TrackerTerms`: each frame's readings as ``sensor`` constraints (blended in when
  a tracker reconnects), the recent 6-DoF readings the pose bank reads, and where the
  trackers say the body is and faces.
* :class:`UserConstraints`: the user's constraints, edited between frames; what one of
  them captures on first use (a pin's position) is kept on a copy.
* :class:`FramePlan`: what one frame is solved against, read from the frame before any
  solve; the frame-by-frame step and the batched offline solve both take it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.constraints import Constraint, SensorConstraint
from engine.constraints.residual import FrameInputs
from engine.constraints.sensor import SensorTerm
from engine.errors import UserError
from engine.methods.sensor_blend import SensorBlend
from engine.models import heading as hd
from engine.sensors import Sensor, SensorFrame
from engine.solver import OptimizerSettings
from engine.solver.limb_ik import CARRIED, HEAD, LIMBS, finish
from engine.solver.pose import body_facing
from engine.solver.tracker_history import TrackerHistory
from engine.solver.tracker_net import WINDOW


@dataclass
class FramePlan:
    """What a frame is solved against (:meth:`DragPoserMethod.plan`).

    Attributes
    ----------
    settings : OptimizerSettings
        The caller's settings completed by the connected sensor set's profile.
    warnings : list of str
        Readings ignored (not finite) and the like.
    trackers : SensorTerm or None
        The connected trackers' term, their readings frozen for this frame (what the
        batched solve solves against); None in a plan made without it (the frame-by-frame
        step, which solves against the sensor constraints themselves).
    names : tuple of str
        Their constraint names (``sensor:<joint>``).
    weights : ndarray (S,)
        Their weights this frame.
    bank_readings : tuple or None
        The pose bank's lookup input for this frame (``prior = trackers`` with a bank and
        hips or head tracked), else None: the predictor gives the prior.
    feet : bool
        A foot tracker is connected (the ground band is off).
    hip : (ndarray (3,), ndarray (4,)) or None
        The connected 6-DoF hip tracker's position and rotation.
    reach, turn : dict of int to ndarray
        The after-solve steps' targets: the head (by the spine) and limbs onto their
        trackers, tracker rotations.
    level : tuple of int
        Ankles that take the pelvis's heading after the solve (setting ``level_feet``).
    shoulder_deg : float
        How far a clavicle may turn to bring a wrist's tracker within the arm's reach
        (setting ``shoulder_reach``; 0 while a user constraint acts on a clavicle).
    """

    settings: OptimizerSettings
    warnings: list[str]
    trackers: SensorTerm | None
    names: tuple[str, ...]
    weights: np.ndarray
    bank_readings: tuple | None
    feet: bool
    hip: tuple[np.ndarray, np.ndarray] | None
    reach: dict[int, np.ndarray] = field(default_factory=dict)
    turn: dict[int, np.ndarray] = field(default_factory=dict)
    level: tuple[int, ...] = ()
    shoulder_deg: float = 0.0

    def finished(
        self, local_rot: np.ndarray, positions: np.ndarray, offsets: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """A solved pose ``(22, 4)`` local rotations and ``(22, 3)`` positions after this
        frame's after-solve steps (:func:`engine.solver.limb_ik.finish`: one forward
        kinematics pass for all of them); as given when it has none."""
        if not (self.reach or self.turn or self.level):
            return local_rot, positions
        share = self.settings.neck_twist_share
        return finish(local_rot, positions[0], offsets, self.reach, self.turn, share, self.level, self.shoulder_deg)

    @property
    def smooth_weight(self) -> float:
        """The smoothing term's weight this frame."""
        return float(self.settings.smooth_weight)

    @property
    def ground_weight(self) -> float:
        """The ground band's weight this frame: off while a foot tracker is connected."""
        return 0.0 if self.feet else float(self.settings.ground_weight)

    @property
    def gait_weight(self) -> float:
        """The gait term's weight this frame: off while a foot tracker is connected."""
        return 0.0 if self.feet else float(self.settings.gait_weight)

    @property
    def stand_weight(self) -> float:
        """The standing-legs pull's weight this frame: off while a foot tracker is connected."""
        return 0.0 if self.feet else float(self.settings.stand_weight)


def smoothing_history(
    frame: int, previous: np.ndarray | None, before: np.ndarray | None
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The two solved poses ``(22, 3)`` the smoothing term of solve number ``frame`` (since
    the start or a reset) extrapolates from (:meth:`SmoothConstraint.set_history`; None:
    no target). Frame 0 is solved offline from the mean latent, so the step from it to
    frame 1 is not a velocity: extrapolating it threw frames 2-4 of a head-and-hands clip
    36 cm off. The target starts at frame 3."""
    return previous, before if frame >= 3 else None


class TrackerTerms:
    """The trackers of a clip as ``sensor`` constraints (module doc).

    Attributes
    ----------
    constraints : dict of str to SensorConstraint
        One per joint that has had a reading; enabled while its tracker is connected.
    weights : dict of str to float
        The user's weight per joint (1 when absent).
    history : TrackerHistory
        Recent 6-DoF readings (the pose bank's lookup).
    facing : ndarray (4,) or None
        This frame's body heading from its trackers: the heading network's
        (:mod:`engine.models.heading`, setting ``heading_network``) while the hip tracker
        gives no rotation and all of the network's trackers are connected, else the
        feet's and hands' left-right lines (:func:`engine.solver.pose.body_facing`).
    learned_facing : bool
        Whether :attr:`facing` came from the heading network this frame.
    points, last_points : dict of str to ndarray (3,)
        Connected trackers' positions, this frame and the previous one.
    """

    def __init__(self, weights: dict[str, float] | None = None, heading: hd.HeadingModel | None = None) -> None:
        self.weights = weights if weights is not None else {}  # shared: kept across clips
        self.heading = heading
        self._heading_window: list[np.ndarray] = []  # the network's joints' positions, oldest first
        self.learned_facing = False
        self.constraints: dict[str, SensorConstraint] = {}
        self.blends: dict[str, SensorBlend] = {}
        self.history = TrackerHistory(WINDOW)
        self.facing: np.ndarray | None = None
        self.points: dict[str, np.ndarray] = {}
        self.last_points: dict[str, np.ndarray] = {}

    def update(self, frame: SensorFrame, s: OptimizerSettings, fps: float, previous: np.ndarray | None) -> list[str]:
        """Take a frame's readings (``previous (22, 3)``: the last solved pose, where a
        reconnecting tracker is blended in from); returns the warnings."""
        warnings: list[str] = []
        for c in self.constraints.values():
            c.enabled = False  # readings absent this frame are not used
        for joint, r in frame.readings.items():
            c = self.constraints.get(joint)
            if c is None or c.dof != r.dof:
                c = SensorConstraint(
                    name=f"sensor:{joint}", joint=joint, dof=r.dof, weight=self.weights.get(joint, 1.0)
                )
                self.constraints[joint] = c
            ok = finite(r)
            if r.connected and not ok:
                warnings.append(f"sensor {joint}: non-finite reading ignored")
            c.position_tolerance, c.rotation_tolerance = s.position_tolerance, s.rotation_tolerance
            live = bool(r.connected and ok)
            # trackers that place the body (hips, root anchor) are never blended
            seconds = 0.0 if joint in ("root", s.root_anchor) else s.sensor_blend
            prev = None if previous is None else previous[sk.JOINT_INDEX[joint]]
            t = self.blends.setdefault(joint, SensorBlend()).update(r.position, live, prev, seconds, fps)
            c.rotation_weight = s.sensor_rotation_weight * t.rotation_weight
            c.weight = self.weights.get(joint, 1.0) * t.weight
            if t.active:
                c.set_target(t.position, r.rotation if live and r.dof == 6 else None, True)
            c.connected = c.enabled = t.active
        self.history.push(
            {
                j: (np.asarray(r.position, np.float64), np.asarray(r.rotation, np.float64))
                for j, r in frame.readings.items()
                if r.connected and r.dof == 6 and finite(r)
            }
        )
        points = {j: np.array(c.position, dtype=np.float64) for j, c in self.constraints.items() if c.enabled}
        self.facing = self._facing(points, s, fps)
        self.last_points, self.points = self.points, points
        return warnings

    def _facing(self, points: dict[str, np.ndarray], s: OptimizerSettings, fps: float) -> np.ndarray | None:
        """:attr:`facing` of this frame's connected trackers' ``points``; the network's
        window restarts (its first frame repeated) whenever one of its trackers is lost."""
        hip = self.constraints.get("root")
        if (
            self.heading is None
            or not s.heading_network
            or hip is None
            or hip.dof != 3
            or any(j not in points for j in hd.JOINTS)
        ):
            self._heading_window.clear()
            self.learned_facing = False
            return body_facing(points)
        now = np.stack([points[j] for j in hd.JOINTS])
        k = hd.window_frames(fps)
        if not self._heading_window:
            self._heading_window = [now] * (k - 1)
        self._heading_window = [*self._heading_window[-(k - 1) :], now]
        yaw = float(self.heading.yaw(np.stack(self._heading_window)))
        self.learned_facing = True
        return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])

    def set_weight(self, joint: str, weight: float) -> None:
        """The user's weight of the tracker on ``joint``."""
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        self.weights[joint] = float(weight)
        if joint in self.constraints:
            self.constraints[joint].weight = float(weight)

    def scale_rotation_weights(self, factor: float) -> None:
        """Multiply every tracker's rotation weight (a sensor-set profile's own weight)."""
        for c in self.constraints.values():
            c.rotation_weight *= factor

    def live(self) -> list[SensorConstraint]:
        """The enabled trackers, in the order they were first read."""
        return [c for c in self.constraints.values() if c.enabled]

    def feet(self) -> bool:
        """Whether a foot tracker is connected."""
        return any(self.constraints[j].enabled for j in ("lankle", "rankle") if j in self.constraints)

    def reach_targets(self, held: set[int]) -> dict[int, np.ndarray]:
        """Tracked wrists and ankles -> their trackers' positions (setting ``reach``),
        except a limb whose shoulder/elbow (hip/knee) or end joint is in ``held`` (joints
        a user constraint acts on: put back on its tracker, a distance between the
        tracked wrists had no effect on the pose while its loss read as met)."""
        return {
            sk.JOINT_INDEX[j]: c.position
            for j, c in self.constraints.items()
            if c.enabled
            and c.connected
            and sk.JOINT_INDEX[j] in LIMBS
            and not held & {sk.JOINT_INDEX[j], *LIMBS[sk.JOINT_INDEX[j]]}
        }

    def head_target(self, held: set[int]) -> dict[int, np.ndarray]:
        """The head -> its tracker's position (setting ``head_reach``) while a hip tracker
        places the root and no user constraint acts on a joint the spine's turn carries
        (:data:`~engine.solver.limb_ik.CARRIED`: the spine, head, clavicles and arms; the
        turn would take a pinned elbow off the pin the solve met); else empty. Without
        hips the root follows the head tracker already."""
        hip, head = self.constraints.get("root"), self.constraints.get("upperneck")
        if hip is None or head is None or not (hip.enabled and head.enabled and head.connected) or held & CARRIED:
            return {}
        return {HEAD: head.position}

    def level_ankles(self, held: set[int]) -> tuple[int, ...]:
        """Ankles whose connected tracker gives a position only (setting ``level_feet``),
        except one whose ankle or toe is in ``held`` (a user constraint acts on the foot)."""
        return tuple(
            sk.JOINT_INDEX[j]
            for j, c in self.constraints.items()
            if j in ("lankle", "rankle")
            and c.enabled
            and c.connected
            and c.dof == 3
            and not held & {sk.JOINT_INDEX[j], sk.JOINT_INDEX[j[0] + "toe"]}
        )

    def rotation_targets(self) -> dict[int, np.ndarray]:
        """The head, hands and feet -> their connected 6-DoF trackers' world rotations
        (setting ``sensor_rotations``); the hips' is the tracker's already."""
        return {
            sk.JOINT_INDEX[j]: c.rotation
            for j, c in self.constraints.items()
            if c.enabled and c.connected and c.dof == 6 and j != "root"
        }

    def term(self, build: bool = True) -> tuple[SensorTerm | None, tuple[str, ...], np.ndarray]:
        """The live trackers' term with their readings frozen now (None unless ``build``),
        names and weights."""
        live = self.live()
        term = None
        if build:
            terms = SensorConstraint.terms(live, FrameInputs())
            term = terms[0] if terms else SensorTerm([])
        return term, tuple(c.name for c in live), np.array([c.weight for c in live], dtype=np.float64)


class UserConstraints:
    """The user's constraints, names unique; every edit applies from the next frame."""

    def __init__(self) -> None:
        self.items: list[Constraint] = []
        #: id(published constraint) -> (it, the copy that holds what it captured on first use)
        self._captured: dict[int, tuple[Constraint, Constraint]] = {}

    def add(self, constraint: Constraint) -> None:
        if any(c.name == constraint.name for c in self.items):
            raise UserError(f"a constraint named {constraint.name!r} exists already")
        self.items.append(constraint)

    def remove(self, name: str) -> None:
        self.get(name)
        self.items = [c for c in self.items if c.name != name]

    def get(self, name: str) -> Constraint:
        for c in self.items:
            if c.name == name:
                return c
        raise UserError(f"no constraint named {name!r}")

    def replace_all(self, constraints: Iterable[Constraint]) -> None:
        """Replace all user constraints (names must be unique)."""
        items = list(constraints)
        names = [c.name for c in items]
        if len(set(names)) != len(names):
            raise UserError("constraint names must be unique")
        # a constraint sent again keeps what it captured (a pin's first position)
        kept = {k: v for k, v in self._captured.items() if any(c is v[0] for c in items)}
        self._captured = kept
        self.items = [kept[id(c)][1] if id(c) in kept else c for c in items]

    def settle(self, previous_positions: Any) -> None:
        """Let each constraint capture what it takes from the previous solved pose
        ``(22, 3)`` metres (:meth:`~engine.constraints.base.Constraint.settled`): the copies
        replace them here; the caller's objects are never changed."""
        out = []
        for c in self.items:
            s = c.settled(previous_positions)
            if s is not c:
                original = next((v[0] for v in self._captured.values() if v[1] is c), c)
                self._captured[id(original)] = (original, s)
            out.append(s)
        self.items = out

    def edit(self, name: str, **changes: Any) -> None:
        """An edited copy in place of the named constraint (the caller may hold the old one)."""
        old = self.get(name)
        self.items = [dataclasses.replace(old, **changes) if c is old else c for c in self.items]

    def held_joints(self) -> set[int]:
        """Joints an enabled, weighted constraint acts on."""
        return {
            sk.JOINT_INDEX[n]
            for c in self.items
            if c.enabled and c.weight > 0
            for n in c.acts_on()
            if n in sk.JOINT_INDEX
        }

    def active(self) -> bool:
        """Whether any constraint is enabled with a weight."""
        return any(c.enabled and c.weight > 0 for c in self.items)


def finite(r: Sensor) -> bool:
    """Whether a reading is usable: finite position and, for 6-DoF, a finite non-zero quaternion."""
    pos = np.asarray(r.position, dtype=np.float64).tolist()
    if not all(math.isfinite(v) for v in pos):
        return False
    if r.dof == 6:
        q = np.asarray(r.rotation, dtype=np.float64).tolist()
        return all(math.isfinite(v) for v in q) and math.sqrt(sum(v * v for v in q)) > 1e-6
    return True
