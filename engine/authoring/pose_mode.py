"""Pose mode: the character without a clip, posed continuously by dragged joint targets.

A :class:`PoseMode` holds the character, its current pose and the user's targets and
constraints; its solves are :class:`engine.authoring.pose_solve.PoseSolving`'s.
:meth:`PoseMode.solve` is one short solve from the current pose (call it on every drag
event, :data:`~engine.authoring.pose_solve.ITERATIONS` plain gradient steps with the
root held where it stands, then the feet grounded and targeted wrists / ankles put
exactly on their targets; while a targeted wrist or ankle is still beyond its limb's
reach, up to ``PoseOptions.reach_rounds`` further rounds of those steps, so a low reach
bends the body within the drag; a round that overshoots is dropped); with targets only
it runs on the solver's fast path. :meth:`PoseMode.settle` is a full offline solve (grounded, so the
body may crouch), for when the drag ends. Bone lengths are those of the skeleton by
construction (forward kinematics of fixed offsets), and the lowest foot stands on the
floor after every solve.

What no target asks for stays as the user left it (:class:`PoseOptions`): a turn is
taken exactly by its joint after the solve and moves no other joint, a low wrist target
bends the trunk and crouches the pelvis only for what the stooping trunk does not reach
(:mod:`engine.authoring.pose_root`), an arm no target holds keeps hanging as it hung
from its shoulder while the other is dragged (``free_arm_weight``), ``hold_weight`` pulls the
joints no target holds towards :attr:`PoseMode.anchor`, the pose the drag began from,
and ``keep_trunk`` keeps any trunk bone from leaning further back than it did then.

:meth:`PoseMode.pose_key` poses a key as the bake does (:mod:`engine.authoring.bake`):
one machinery for the pose window and the baked keys.
"""

from __future__ import annotations

import copy

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Character, Pose, encode_frames, heading_deg
from engine.authoring.keys import PLANTED, Key
from engine.authoring.pelvis_drag import within_legs
from engine.authoring.pose_drag import EVENTS, drag
from engine.authoring.pose_options import LOWEST_ROOT, SQUAT_FROM, PoseOptions
from engine.authoring.pose_root import (
    FOOT_OF,
    arm_low_points,
    moved_feet,
    reach_crouches,
)
from engine.authoring.pose_solve import PoseSolving
from engine.authoring.targets import JointTarget
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.motion.clip import Motion
from engine.progress import CancelCheck, check


class PoseMode(PoseSolving):
    """A posing session (see the module doc).

    Parameters
    ----------
    vae : engine.models.PoseVAE
    height : float or None
        The character's standing height, metres.
    latent : ndarray (L,) or None
        Starting latent (None: the VAE's mean pose).
    root_xy : sequence of 2 floats
        Where the character stands, metres.
    heading : float
        Facing, degrees about +Z.
    options : PoseOptions or None
        How the pose is kept natural (None: the defaults).
    """

    def __init__(
        self,
        vae,
        height: float | None = None,
        latent: np.ndarray | None = None,
        root_xy=(0.0, 0.0),
        heading: float = 0.0,
        options: PoseOptions | None = None,
    ) -> None:
        self.options = options or PoseOptions()
        self.character = Character(vae, height)
        self.base_latent = self.character.mean_latent() if latent is None else np.asarray(latent, np.float32)
        self.heading = float(heading)
        self.targets: dict[str, JointTarget] = {}
        self.constraints: list[Constraint] = []
        #: The animation frame being posed: a constraint limited to frames acts on the
        #: pose as it will on that frame of the bake (its activity there).
        self.frame = 0
        self.pose: Pose = self.character.decode(self.base_latent, self.character.grounded(root_xy, self.heading))
        self._standing_root = float(self.pose.root_pos[2])
        self._lowest_reach = arm_low_points(self.pose.positions, self.options.stoop_deg)
        self._hanging_reach = arm_low_points(self.pose.positions)
        #: Where each untargeted foot joint stays (world, metres), see :class:`PoseOptions`.
        self.planted: dict[str, np.ndarray] = {}
        #: The pose the current drag began from (None: the next solve's starting pose),
        #: and the joint dragged; see :meth:`held`.
        self.anchor: Pose | None = None
        self._anchor_joint: str | None = None
        self._solved: Pose | None = None
        self.plant_where_standing()

    @classmethod
    def from_clip_frame(
        cls, vae, motion: Motion, frame: int, height: float | None = None, options: PoseOptions | None = None
    ) -> "PoseMode":
        """Start from frame ``frame`` of ``motion``: its encoded latent, where it stands
        and its facing."""
        if not 0 <= frame < len(motion):
            raise UserError(f"frame {frame} is outside the clip (0-{len(motion) - 1})")
        latent = encode_frames(vae, motion, [frame])[0]
        return cls(vae, height, latent, motion.root_pos[frame, :2], heading_deg(motion.local_rot[frame, 0]), options)

    @property
    def standing_root(self) -> float:
        """Height (metres) of the pelvis standing in the starting pose: the highest the
        crouch and a dragged pelvis put it."""
        return self._standing_root

    # -- targets -------------------------------------------------------------------
    def set_target(
        self,
        joint: str,
        position=None,
        rotation=None,
        weight: float | None = None,
        enabled: bool | None = None,
        pelvis_only: bool | None = None,
    ) -> JointTarget:
        """Create or change the target on ``joint``; arguments left None keep their value
        (a new target starts at the joint's current position, weight 1, not pelvis-only)."""
        old = self.targets.get(joint)
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        # a drag begins when another joint is moved or the pose was set other than by a solve
        if joint != self._anchor_joint or self.anchor is None or self.pose is not self._solved:
            self.anchor, self._anchor_joint = self.pose, joint
        here = self.pose.positions[sk.JOINT_INDEX[joint]]
        t = JointTarget(
            joint,
            position if position is not None else (old.position if old else here),
            rotation if rotation is not None else (old.rotation if old else None),
            weight if weight is not None else (old.weight if old else 1.0),
            enabled if enabled is not None else (old.enabled if old else True),
            pelvis_only if pelvis_only is not None else (old.pelvis_only if old else False),
        )
        self.targets[joint] = t
        return t

    def clear_rotation(self, joint: str) -> None:
        """Make the target on ``joint`` a position target again."""
        t = self.targets.get(joint)
        if t is not None:
            t.rotation = None

    def remove_target(self, joint: str) -> None:
        self.targets.pop(joint, None)

    def clear_targets(self) -> None:
        self.targets.clear()

    def drag_hips(self, position: np.ndarray) -> Pose:
        """The hips dragged to ``position (3,)`` metres. The level part of the move is root
        motion: the whole body and its feet move. The height lowers the pelvis over the
        planted feet, so the knees bend: a target on ``root``, kept between
        :data:`LOWEST_ROOT` of :attr:`standing_root` and :attr:`standing_root`. A pelvis
        dragged back up to standing height loses the target, unless a wrist target below
        what the stooping trunk reaches would crouch the body again (a hand on the shin):
        then it is held at standing height and the trunk bends instead; one less than
        :data:`SQUAT_FROM` below it gets none, so the jitter of a level drag does not
        crouch. The targets are solved from there.

        While crouching, the target's level part is where the body stands (the hips'
        handle) and the pelvis balances around it (``PoseOptions.crouch_balance``): a
        pelvis that the balance moved back keeps its offset from the handle, so a
        straight-down drag does not pull it forward again."""
        p = np.asarray(position, float)
        held = self.targets.get("root")
        handle = self.hips_handle()
        level = np.array([p[0] - handle[0], p[1] - handle[1], 0.0])
        standing = self._standing_root
        z = float(np.clip(p[2], LOWEST_ROOT * standing, standing))
        if np.any(level):
            solved, anchor = self.pose is self._solved, self.anchor
            self.pose = self.pose.moved(level)
            self.plant_where_standing()
            if solved:  # root motion keeps the body's pose (the anchor is root-relative): the drag goes on
                self._solved, self.anchor = self.pose, anchor
        if held is not None and z >= standing and not reach_crouches(self.targets, self._lowest_reach, self.options):
            self.remove_target("root")
        elif held is not None or standing - z > SQUAT_FROM:
            self.set_target("root", np.array([handle[0] + level[0], handle[1] + level[1], z]), pelvis_only=False)
        if self.targets:
            self.solve()
        return self.pose

    def drag_pelvis(self, position: np.ndarray) -> Pose:
        """Only the pelvis dragged to ``position (3,)`` metres (Shift + drag on the hips,
        :mod:`engine.authoring.pelvis_drag`): the feet stay planted exactly where they are
        (flat), the legs bend by their two bones, the upper body keeps its pose relative
        to the pelvis and targeted wrists stay on their targets where the arms reach. The
        root gets a ``pelvis_only`` target there, kept above :data:`LOWEST_ROOT` of
        :attr:`standing_root` and within the planted legs' reach. No latent solve runs
        unless a targeted wrist or ankle is then short of its target: the event then
        solves the body (:meth:`solve`), so the trunk leans to a pinned hand."""
        if self.pelvis_target() is None:  # the drag begins: the feet stay where they are now
            moved = moved_feet(self.targets)
            for j in PLANTED:
                if FOOT_OF[j] not in moved:
                    self.planted[j] = self.pose.positions[sk.JOINT_INDEX[j]].copy()
        p = np.asarray(position, float).copy()
        p[2] = max(p[2], LOWEST_ROOT * self._standing_root)
        self.set_target("root", within_legs(self.pose, p, self.planted), pelvis_only=True)
        self.pose = self._solved = self.pelvis_step(self.pose)
        if self.shortfall() > self.options.reach_tolerance:
            # a pinned hand the carried arm no longer reaches: the trunk leans to it
            self.solve()
        return self.pose

    def standing_place(self) -> np.ndarray:
        """Where the body stands (2,) metres, what a key keeps as its ``root``: the
        pelvis's level place, or under a pelvis-only target that of the body the latent
        describes (the pelvis before it was dragged, :mod:`engine.authoring.pelvis_drag`)."""
        pose = self.pose
        body = pose.decoded if self.pelvis_target() is not None and pose.decoded is not None else pose.positions
        return body[0, :2].copy()

    def hips_handle(self) -> np.ndarray:
        """Where a drag of the hips starts (3,) metres, the point :meth:`drag_hips` moves:
        the target on ``root`` while crouching (the body's level place at the pelvis's
        height; the balanced pelvis sits behind it), else the pelvis."""
        held = self.targets.get("root")
        return np.asarray(held.position if held is not None else self.pose.root_pos, float).copy()

    def plant_where_standing(self) -> None:
        """Plant the feet where the current pose has them (after the pose was set from a
        key, or the whole body was moved or turned)."""
        self.planted = {j: self.pose.positions[sk.JOINT_INDEX[j]].copy() for j in PLANTED}
        self.anchor = None

    def detached(self) -> "PoseMode":
        """A copy to settle or solve on another thread: its own targets, planted feet and
        constraint list (constraints copied), the character and its networks shared (they
        are only read)."""
        other = copy.copy(self)
        other.targets = copy.deepcopy(self.targets)
        other.planted = {j: p.copy() for j, p in self.planted.items()}
        other.constraints = copy.deepcopy(self.constraints)
        return other

    def adopt(self, other: "PoseMode") -> None:
        """Take the pose, planted feet and drag anchor of ``other``, a :meth:`detached`
        copy of this mode that was settled or solved (its targets are this mode's)."""
        self.pose, self.anchor, self._anchor_joint = other.pose, other.anchor, other._anchor_joint
        self.planted = {j: p.copy() for j, p in other.planted.items()}
        self._solved = other._solved

    def pose_key(self, key: Key, events: int = EVENTS, cancelled: CancelCheck | None = None) -> Pose:
        """Pose as ``key`` (what a baked key is, :mod:`engine.authoring.bake`, and what the
        pose window shows on a key).

        A key with a latent (one the window keyed): that pose where the key stands and
        faces, the feet planted there (or at the key's ``feet``), its targets taken exactly
        by the limbs and turned joints, a pelvis-only target's pelvis moved alone
        (``solve(0)``). A key with targets only (a scene written by hand): from the
        current pose, each active target dragged from where its joint is to its place in
        ``events`` drag events, then turned to its rotation in as many, in the key's order,
        each event one :meth:`solve`, as a user drags it in the pose window
        (:func:`engine.authoring.pose_drag.drag`); targets already in place (within 1 mm)
        are set, not dragged, and inactive ones are set as they are. ``cancelled()`` is
        asked before each event.
        """
        if key.latent is not None:
            self.targets = copy.deepcopy(key.targets)
            self.heading = key.heading
            self.pose = self.character.decode(key.latent, self.character.grounded(key.root, key.heading))
            self.plant_where_standing()
            self.planted.update({j: np.asarray(p, float).copy() for j, p in key.feet.items()})
            return self.solve(0)
        offsets = self.character.skeleton.offsets
        for t in key.targets.values():
            here = self.pose.positions[t.index]
            if t.pelvis_only and t.active:
                start = self.hips_handle()
                for k in range(1, events + 1):
                    check(cancelled)
                    self.drag_pelvis(start + (t.position - start) * k / events)
                continue
            if not t.active or np.linalg.norm(here - t.position) < 1e-3:
                self.set_target(t.joint, t.position, None, t.weight, t.enabled)
            else:
                drag(self, t.joint, offsets, position=t.position, events=events, weight=t.weight, cancelled=cancelled)
            if t.rotation is not None:
                if t.active:
                    drag(self, t.joint, offsets, rotation=t.rotation, events=events, cancelled=cancelled)
                else:
                    self.set_target(t.joint, rotation=t.rotation)
        return self.pose

    def motion(self) -> Motion:
        """The current pose as a one-frame motion on the character's skeleton."""
        return Motion(self.pose.local_rot[None], self.pose.root_pos[None], self.character.skeleton, sk.FPS, "pose")
