"""Plain IK posing: the pose-mode benchmark's comparison, an IK rig posed by the same targets.

:class:`IKPoser` has :class:`engine.authoring.pose_mode.PoseMode`'s posing calls
(``set_target``, ``solve``, ``settle``, ``pose``) but no learned prior. It is what a
character rig with IK handles does, from the current pose on every solve:

1. **Root.** A position target on the root moves the pelvis there (a rotation target
   turns it); nothing else moves the pelvis.
2. **Spine.** A wrist target beyond its arm's reach bends the spine (lower back, upper
   back, chest, evenly) so the shoulder comes towards it, in :data:`SPINE_PASSES`
   passes, as far as that bend can bring it; a position target on the head bends the
   spine the same way to bring the head there.
3. **Limbs.** Wrists and ankles with targets are put on them by the analytic two-bone
   step (:func:`engine.solver.limb_ik.reach_local`: the elbow or knee bends in the limb's
   current plane, the limb turns about the shoulder or hip; beyond reach the limb points
   straight at the target). Feet without targets stay where they stood when the poser
   was made, as an IK rig's foot handles do, so moving the pelvis bends the legs.
4. **Rotations.** Joints with rotation targets take them exactly
   (:func:`engine.solver.limb_ik.finish`).

Targets on other joints (knees, elbows, the trunk joints) are not moved towards.
Bone lengths are the skeleton's (forward kinematics of fixed offsets).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.authoring.targets import JointTarget
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.kinematics.quat_np import qbetween, qpow
from engine.solver.limb_ik import finish

J = sk.JOINT_INDEX
SPINE = (J["lowerback"], J["upperback"], J["chest"])
#: Wrist -> shoulder of each arm.
ARMS = {J["lwrist"]: J["lshoulder"], J["rwrist"]: J["rshoulder"]}
FEET = (J["lankle"], J["rankle"])
SPINE_PASSES = 6
#: The spine brings an arm's target within this share of the arm's length (a fully
#: straight arm has no bend plane left).
REACH_SHARE = 0.98


class IKPoser:
    """See the module doc. ``pose``: the starting :class:`Pose` (e.g. a :class:`PoseMode`'s);
    ``offsets (22, 3)``: the skeleton's bone offsets, metres."""

    def __init__(self, pose: Pose, offsets: np.ndarray) -> None:
        self.offsets = np.asarray(offsets, float)
        self.pose = Pose(
            pose.latent,
            np.array(pose.local_rot, float),
            np.array(pose.root_pos, float),
            np.array(pose.positions, float),
        )
        self.feet = {j: self.pose.positions[j].copy() for j in FEET}
        self.targets: dict[str, JointTarget] = {}

    def set_target(self, joint: str, position=None, rotation=None) -> JointTarget:
        """Create or change the target on ``joint`` (as :meth:`PoseMode.set_target`)."""
        if joint not in J:
            raise UserError(f"unknown joint {joint!r}")
        old = self.targets.get(joint)
        here = self.pose.positions[J[joint]]
        t = JointTarget(
            joint,
            position if position is not None else (old.position if old else here),
            rotation if rotation is not None else (old.rotation if old else None),
        )
        self.targets[joint] = t
        return t

    def solve(self) -> Pose:
        """Pose the rig onto the targets from the current pose (see the module doc)."""
        local = np.array(self.pose.local_rot, float)
        root = np.array(self.pose.root_pos, float)
        live = {J[t.joint]: t for t in self.targets.values() if t.active}
        if 0 in live:
            root = np.array(live[0].position, float)
            if live[0].rotation is not None:
                local[0] = live[0].rotation
        for j, t in live.items():
            if j in ARMS:
                self._bend_spine(local, root, ARMS[j], t.position, self._arm_length(j))
            elif j == J["upperneck"]:
                self._bend_spine(local, root, j, t.position, 0.0)
        reach = {j: self.feet[j] for j in FEET}
        reach.update({j: np.array(t.position, float) for j, t in live.items() if j in ARMS or j in FEET})
        rotations = {j: t.rotation for j, t in live.items() if t.rotation is not None and j != 0}
        local, positions = finish(local, root, self.offsets, reach, rotations)
        self.pose = Pose(self.pose.latent, local, root, positions)
        return self.pose

    def settle(self) -> Pose:
        """The rig has nothing more to do at a drag's end: :meth:`solve` again."""
        return self.solve()

    def _arm_length(self, wrist: int) -> float:
        elbow = sk.PARENTS[wrist]
        return REACH_SHARE * float(np.linalg.norm(self.offsets[elbow]) + np.linalg.norm(self.offsets[wrist]))

    def _bend_spine(self, local: np.ndarray, root: np.ndarray, joint: int, goal: np.ndarray, slack: float) -> None:
        """Bend :data:`SPINE` (in place) so ``joint`` comes within ``slack`` metres of ``goal``."""
        goal = np.asarray(goal, float)
        for _ in range(SPINE_PASSES):
            pos, rot = fk(local, root, self.offsets)
            here = pos[joint]
            gap = float(np.linalg.norm(goal - here)) - slack
            if gap <= 1e-4:
                return
            wanted = here + gap * (goal - here) / np.linalg.norm(goal - here)
            base = pos[SPINE[0]]
            swing = qbetween(here - base, wanted - base)
            if 1.0 - abs(swing[0]) < 1e-12:
                return
            step = qpow(swing, 1.0 / len(SPINE))
            for j in SPINE:  # each turns one step more than the one below it, about the world axes
                pr = rot[sk.PARENTS[j]]
                local[j] = QN.mul(QN.mul(QN.conjugate(pr), QN.mul(np.array(step), pr)), local[j])
            local[:] = local / np.linalg.norm(local, axis=-1, keepdims=True)
