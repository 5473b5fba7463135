"""Classical IK baseline (the FinalIK role in DragPoser's comparisons).

Per frame, from whatever sensors are connected:

1. **Root.** Position and rotation from the hip sensor. A 3-DoF hip gets only a heading,
   estimated from the head's yaw (6-DoF head) or from the left-right spread of the feet
   and hands. Without a hip sensor the root is placed below the head sensor by the rest
   root-to-head offset, turned by the head's heading.
2. **Spine.** The swing that takes the rest root-to-head chord onto the head sensor is
   spread evenly over lowerback, upperback, chest and lowerneck (a few refinement
   passes, since the joints pivot at different points); the head (``upperneck``) takes
   the head sensor's rotation.
3. **Limbs.** Analytic two-bone IK: shoulder-elbow-wrist and hip-knee-ankle, with the
   bend plane set by a pole vector (elbows down and back in the chest frame; knees
   forward along the pelvis heading, blended with the foot's forward for a 6-DoF foot).
   Wrists and ankles take their 6-DoF sensor rotations; 3-DoF ankles stay level. A hand
   out of reach turns its clavicle (up to 30 degrees) towards the target; an estimated
   root is pulled towards tracked feet the legs could not reach.
4. **Missing sensors.** A limb whose sensor is lost keeps its last solved pose; one never
   tracked keeps its rest pose, except legs, which hang straight down under the hips.

Bone lengths are those of the skeleton, so they are preserved by construction; targets
out of reach are approached along the straight limb.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as Q  # numpy only: no torch dispatch per call
from engine.kinematics.fk import fk_joints
from engine.kinematics.quat_np import qbetween, qfrom_bases, qnorm, qpow, qtwist, vcross, vnorm
from engine.methods.base import FrameResult, Method
from engine.motion.clip import Motion
from engine.sensors import Sensor, SensorFrame
from engine.solver.pose import body_facing

J = sk.JOINT_INDEX
SPINE = (J["lowerback"], J["upperback"], J["chest"], J["lowerneck"])
HEAD = J["upperneck"]
ALL = tuple(range(sk.NUM_JOINTS))
#: (upper, middle, end, sensor joint) of each limb.
ARMS = ((J["lshoulder"], J["lelbow"], J["lwrist"]), (J["rshoulder"], J["relbow"], J["rwrist"]))
LEGS = ((J["lhip"], J["lknee"], J["lankle"]), (J["rhip"], J["rknee"], J["rankle"]))
#: Rest-pose pole directions (world = root frame at rest): elbows down and back (+Y is
#: back), knees forward (-Y).
ARM_POLE = np.array([0.0, 0.5, -1.0]) / math.sqrt(1.25)
LEG_POLE = np.array([0.0, -1.0, 0.0])
SPINE_PASSES = 4
#: Largest clavicle turn used to bring an out-of-reach hand target closer, radians.
CLAVICLE_MAX = math.radians(30.0)
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


#: Farthest a tracker may be from the origin, metres; beyond it a reading is ignored.
MAX_TRACKER_DISTANCE = 1e4


def usable_reading(r: Sensor) -> bool:
    """A finite position within :data:`MAX_TRACKER_DISTANCE` and, for 6 DoF, a finite
    non-zero quaternion (a zero quaternion has no rotation to normalise)."""
    if r.position is None or (r.dof == 6 and r.rotation is None):
        return False
    pos = np.asarray(r.position, float)
    if not (np.isfinite(pos).all() and float(np.abs(pos).max()) <= MAX_TRACKER_DISTANCE):
        return False
    if r.dof == 6:
        q = np.asarray(r.rotation, float)
        return bool(np.isfinite(q).all()) and qnorm(q) > 1e-6
    return True


def two_bone_mid(start: np.ndarray, target: np.ndarray, a: float, b: float, pole: np.ndarray) -> np.ndarray:
    """Middle-joint position of a two-bone chain reaching for ``target``.

    Parameters
    ----------
    start, target : ndarray (3,)
        Chain root (shoulder / hip) and the end target (wrist / ankle), metres.
    a, b : float
        Upper and lower bone lengths, metres.
    pole : ndarray (3,)
        Direction the middle joint (elbow / knee) should point to, world.

    Returns
    -------
    ndarray (3,)
        Middle-joint position; the reach is clamped to ``[|a-b|, a+b]``.
    """
    d_vec = target - start
    d = vnorm(d_vec)
    n = d_vec / d if d > 1e-9 else np.array([0.0, 0.0, -1.0])
    d = min(max(d, abs(a - b) + 1e-6), a + b - 1e-6)
    cos_a = (a * a + d * d - b * b) / (2.0 * a * d)
    sin_a = math.sqrt(max(0.0, 1.0 - cos_a * cos_a))
    m = pole - (pole @ n) * n
    if vnorm(m) < 1e-9:  # pole along the reach: any perpendicular will do
        m = np.array(vcross(n, (1.0, 0.0, 0.0) if abs(n[0]) < 0.9 else (0.0, 1.0, 0.0)))
    m /= vnorm(m)
    return start + a * (cos_a * n + sin_a * m)


class IKMethod(Method):
    """Analytic IK from the sensors; works for every preset (see module docs)."""

    name = "ik"

    def __init__(self, **_ignored: Any) -> None:
        # mode / iterations are the learned methods' knobs; IK has none
        self.reset(sk.Skeleton.canonical())

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.fps = fps
        self.offsets = np.asarray(skeleton.offsets, dtype=np.float64)
        self._offsets_list = self.offsets.tolist()
        self.rest = skeleton.rest_positions()
        self.root_height = float(-self.rest[:, 2].min())  # rest root above the lowest joint
        self._last: np.ndarray | None = None  # last frame's local rotations (22, 4)
        self._seen: set[str] = set()  # sensors tracked at least once
        self._root_pos = np.array([0.0, 0.0, self.root_height])
        self._heading = IDENTITY.copy()

    # -- kinematics -----------------------------------------------------------------
    def _at(self, local: np.ndarray, root_pos: np.ndarray, *joints: int) -> tuple[np.ndarray, np.ndarray]:
        """World positions ``(k, 3)`` and rotations ``(k, 4)`` of ``joints`` (only their
        ancestors are placed: IK asks for a few joints many times per frame)."""
        return fk_joints(local, root_pos, self._offsets_list, joints)

    # -- root ---------------------------------------------------------------------------
    def _estimate_heading(self, s: dict[str, Sensor]) -> np.ndarray:
        head = s.get("upperneck")
        if head is not None and head.dof == 6 and head.rotation is not None:
            return Q.heading(head.rotation)
        facing = body_facing({j: r.position for j, r in s.items() if r.position is not None}, min_length=1e-3)
        return self._heading if facing is None else facing

    def _solve_root(self, s: dict[str, Sensor]) -> tuple[np.ndarray, np.ndarray]:
        hip, head = s.get("root"), s.get("upperneck")
        if hip is not None and hip.dof == 6:
            rot = np.asarray(hip.rotation, float)
            self._heading = Q.heading(rot)
        else:
            rot = self._heading = self._estimate_heading(s)
        if hip is not None:
            pos = np.asarray(hip.position, float)
        elif head is not None:
            pos = head.position - Q.rotate(rot, self.rest[HEAD] - self.rest[0])
        elif s:
            mean = np.mean([r.position for r in s.values() if r.position is not None], axis=0)
            pos = np.array([mean[0], mean[1], self._root_pos[2]])
        else:
            pos = self._root_pos
        self._root_pos = pos
        return pos, rot / qnorm(rot)

    # -- body parts ---------------------------------------------------------------------
    def _solve_spine(self, local: np.ndarray, root: np.ndarray, head: Sensor) -> None:
        n = len(SPINE)
        for _ in range(SPINE_PASSES):
            pos, rot = self._at(local, root, HEAD, SPINE[0], *(sk.PARENTS[j] for j in SPINE))
            swing = qbetween(pos[0] - pos[1], head.position - pos[1])
            if 1.0 - abs(swing[0]) < 1e-12:
                break
            step = qpow(swing, 1.0 / n)
            for j, pr in zip(SPINE, rot[2:]):  # each segment turns one more step than the one below it
                local[j] = Q.mul(Q.mul(Q.conjugate(pr), Q.mul(step, pr)), local[j])
        if head.dof == 6 and head.rotation is not None:
            _, rot = self._at(local, root, sk.PARENTS[HEAD])
            local[HEAD] = Q.mul(Q.conjugate(rot[0]), head.rotation)

    def _reach_with_clavicle(
        self, local: np.ndarray, root: np.ndarray, chain: tuple[int, int, int], target: np.ndarray
    ) -> None:
        """Turn the clavicle (up to :data:`CLAVICLE_MAX`) when the hand is out of reach."""
        up, mid, end = chain
        clav = sk.PARENTS[up]
        pos, rot = self._at(local, root, up, clav, sk.PARENTS[clav])
        p_up, p_clav, pr = pos[0], pos[1], rot[2]
        reach = vnorm(self.offsets[mid]) + vnorm(self.offsets[end])
        if vnorm(target - p_up) <= reach:
            return
        swing = qbetween(p_up - p_clav, target - p_clav)
        angle = 2.0 * math.acos(min(1.0, abs(swing[0])))
        if angle > CLAVICLE_MAX:
            swing = qpow(swing, CLAVICLE_MAX / angle)
        local[clav] = Q.mul(Q.mul(Q.conjugate(pr), Q.mul(swing, pr)), local[clav])

    def _pull_root_to_feet(self, root: np.ndarray, root_rot: np.ndarray, s: dict[str, Sensor]) -> np.ndarray:
        """Move an estimated root towards tracked feet it could not reach otherwise."""
        for _ in range(2):
            for hip, knee, ankle in LEGS:
                r = s.get(sk.JOINT_NAMES[ankle])
                if r is None:
                    continue
                leg = vnorm(self.offsets[knee]) + vnorm(self.offsets[ankle])
                hip_pos = root + Q.rotate(root_rot, self.offsets[hip])
                d = r.position - hip_pos
                excess = vnorm(d) - 0.999 * leg
                if excess > 0:
                    root = root + excess * d / vnorm(d)
        return root

    def _solve_limb(
        self,
        local: np.ndarray,
        root: np.ndarray,
        chain: tuple[int, int, int],
        target: np.ndarray,
        pole: np.ndarray,
        rest_pole: np.ndarray,
        end_rot: np.ndarray | None,
        twist_mid: bool = False,
    ) -> None:
        up, mid, end = chain
        (p_up, _), (_, r_parent) = self._at(local, root, up, sk.PARENTS[up])
        a = vnorm(self.offsets[mid])
        b = vnorm(self.offsets[end])
        elbow = two_bone_mid(p_up, target, a, b, pole)
        bend = pole - (pole @ (target - p_up)) * (target - p_up) / max(float(np.sum((target - p_up) ** 2)), 1e-12)
        g_up = np.array(qfrom_bases(self.offsets[mid], rest_pole, elbow - p_up, bend))
        local[up] = Q.mul(Q.conjugate(r_parent), g_up)
        lower = Q.rotate(g_up, self.offsets[end])
        g_mid = Q.mul(qbetween(lower, target - elbow), g_up)
        if end_rot is not None and twist_mid:
            # the forearm carries the hand's twist (pronation), the wrist only the swing
            g_mid = Q.mul(g_mid, qtwist(Q.mul(Q.conjugate(g_mid), end_rot), self.offsets[end]))
        local[mid] = Q.mul(Q.conjugate(g_up), g_mid)
        local[end] = IDENTITY if end_rot is None else Q.mul(Q.conjugate(g_mid), end_rot)

    def _keep_or_rest(self, local: np.ndarray, joints: tuple[int, ...], sensor: str) -> bool:
        """Keep a lost limb's last pose; return False if it was never tracked."""
        if sensor in self._seen and self._last is not None:
            local[list(joints)] = self._last[list(joints)]
            return True
        return False

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        warnings: list[str] = []
        s: dict[str, Sensor] = {}
        prev_root = self._root_pos.copy()
        for j, r in sensors.connected().items():
            if usable_reading(r):
                s[j] = r
            else:
                warnings.append(f"sensor {j}: non-finite or implausible reading ignored")
        self._seen |= set(s)
        root_pos, root_rot = self._solve_root(s)
        if "root" not in s:
            root_pos = self._root_pos = self._pull_root_to_feet(root_pos, root_rot, s)
        local = np.tile(IDENTITY, (sk.NUM_JOINTS, 1))
        local[0] = root_rot

        if "upperneck" in s:
            self._solve_spine(local, root_pos, s["upperneck"])
        else:
            self._keep_or_rest(local, SPINE + (HEAD,), "upperneck")

        chest = self._at(local, root_pos, J["chest"])[1][0]
        for chain in ARMS:
            joint = sk.JOINT_NAMES[chain[2]]
            hand = s.get(joint)
            if hand is None:
                self._keep_or_rest(local, chain, joint)
                continue
            end_rot = np.asarray(hand.rotation, float) if hand.dof == 6 else None
            reach_to = np.asarray(hand.position, float)
            self._reach_with_clavicle(local, root_pos, chain, reach_to)
            self._solve_limb(
                local, root_pos, chain, reach_to, Q.rotate(chest, ARM_POLE), ARM_POLE, end_rot, twist_mid=True
            )

        forward = Q.rotate(root_rot, LEG_POLE)
        level = Q.heading(root_rot)
        for chain in LEGS:
            joint = sk.JOINT_NAMES[chain[2]]
            foot = s.get(joint)
            if foot is None and self._keep_or_rest(local, chain, joint):
                continue
            if foot is None:  # never tracked: hang straight down under the hip
                reach = vnorm(self.rest[chain[2]] - self.rest[chain[0]])
                hip = self._at(local, root_pos, chain[0])[0][0]
                target, pole, end_rot = hip - [0.0, 0.0, reach], forward, level
            elif foot.dof == 6:
                foot_fwd = Q.rotate(np.asarray(foot.rotation, float), LEG_POLE)
                target, pole, end_rot = foot.position, forward + foot_fwd, np.asarray(foot.rotation, float)
            else:
                target, pole, end_rot = foot.position, forward, level
            self._solve_limb(local, root_pos, chain, np.asarray(target, float), pole, LEG_POLE, end_rot)

        pos, _ = self._at(local, root_pos, *ALL)
        if not (np.isfinite(local).all() and np.isfinite(pos).all()):  # guard, as DragPoser's
            warnings.append("IK produced a non-finite pose; the previous pose is kept")
            local = self._last.copy() if self._last is not None else np.tile(IDENTITY, (sk.NUM_JOINTS, 1))
            root_pos = self._root_pos = prev_root
            pos, _ = self._at(local, root_pos, *ALL)
        self._last = local.copy()
        return FrameResult(
            local_rot=local,
            root_pos=root_pos.copy(),
            positions=pos,
            ms=1000.0 * (time.perf_counter() - t0),
            warnings=warnings,
        )


def create(**kwargs: Any) -> IKMethod:
    """Registry factory: analytic IK (the learned methods' ``mode``, ``iterations``... are ignored)."""
    return IKMethod(**kwargs)
