"""Pose mode: the character without a clip, posed continuously by dragged joint targets.

A :class:`PoseMode` holds the character, its current pose and the user's targets and
constraints. :meth:`PoseMode.solve` is one short solve from the current pose (call it on
every drag event, :data:`ITERATIONS` plain gradient steps with the root held where it
stands, then the feet grounded and targeted wrists / ankles put exactly on their
targets; while a targeted wrist or ankle is still beyond its limb's reach, up to
``PoseOptions.reach_rounds`` further rounds of those steps, so a low reach bends the
body within the drag; a round that overshoots is dropped); with targets only it runs on
the solver's fast path. :meth:`PoseMode.settle` is a full offline solve (grounded, so the
body may crouch), for when the drag ends. Bone lengths are those of the skeleton by
construction (forward kinematics of fixed offsets), and the lowest foot stands on the
floor after every solve.

What no target asks for stays as the user left it (:class:`PoseOptions`): a turn is
taken exactly by its joint after the solve and moves no other joint, the pelvis crouches
only for a wrist target below the hanging arm's reach, ``hold_weight`` pulls the
joints no target holds towards :attr:`PoseMode.anchor`, the pose the drag began from,
and ``keep_trunk`` keeps any trunk bone from leaning further back than it did then.

:meth:`PoseMode.pose_key` poses a key as the bake does (:mod:`engine.authoring.bake`):
one machinery for the pose window and the baked keys.
"""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Character, Pose, encode_frames, heading_deg, yaw_quaternion
from engine.authoring.keys import PLANTED, Key
from engine.authoring.pelvis_drag import pelvis_pose, within_legs
from engine.authoring.pose_drag import EVENTS, drag
from engine.authoring.pose_hold import held_joints, hold_terms
from engine.authoring.pose_options import LOWEST_ROOT, SQUAT_FROM, PoseOptions
from engine.authoring.pose_root import (
    FOOT_OF,
    Stance,
    arm_low_points,
    moved_feet,
    reach_crouches,
    root_where,
    shortfall,
)
from engine.authoring.pose_trunk import LEGS, TRUNK, keep_trunk
from engine.authoring.targets import JointTarget, solve_inputs
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.motion.clip import Motion
from engine.progress import CancelCheck, check
from engine.solver.limb_ik import LIMBS

#: Latent steps of one continuous solve (one drag event).
ITERATIONS = 16
#: Plain gradient step of the continuous solve. Dragging a wrist 30 cm in 30 events
#: (mean pose, 1.75 m) in five directions with the shipped VAE, the decoded wrist's
#: largest lag was 1.9 cm at 1.5 x 16 steps, 2.4 cm at 2 x 8, 3.6 cm at 1 x 8; from a
#: step of 2.5 the solve starts to overshoot (2.8 cm at 2.5 x 12, 9.4 cm at 3 x 8), so
#: the step keeps a margin below that. Plain steps move only the constrained latent
#: directions (Adam moved the free arm more).
STEP_SIZE = 1.5
#: A reach round that leaves the dragged wrist or ankle this much further (metres) from
#: its target than the round before overshot (the plain steps diverge in a body folded
#: near the floor: 5 cm short became 25 cm in one round); it is dropped.
OVERSHOOT = 0.05


class PoseMode:
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
        self._lowest_reach = arm_low_points(self.pose.positions)
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
        the hanging arm's reach would crouch the body again (a hand on the opposite knee):
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
        :attr:`standing_root` and within the planted legs' reach; no latent solve runs."""
        if self.pelvis_target() is None:  # the drag begins: the feet stay where they are now
            moved = moved_feet(self.targets)
            for j in PLANTED:
                if FOOT_OF[j] not in moved:
                    self.planted[j] = self.pose.positions[sk.JOINT_INDEX[j]].copy()
        p = np.asarray(position, float).copy()
        p[2] = max(p[2], LOWEST_ROOT * self._standing_root)
        self.set_target("root", within_legs(self.pose, p, self.planted), pelvis_only=True)
        self.pose = self._solved = self.pelvis_step(self.pose)
        return self.pose

    def pelvis_target(self) -> JointTarget | None:
        """The root's target when it is active and moves the pelvis only, else None."""
        t = self.targets.get("root")
        return t if t is not None and t.active and t.pelvis_only else None

    def pelvis_step(self, pose: Pose) -> Pose:
        """``pose`` with the pelvis on its pelvis-only target, the feet on their planted
        places and targeted wrists and ankles on their targets
        (:func:`engine.authoring.pelvis_drag.pelvis_pose`); ``pose`` itself without one."""
        t = self.pelvis_target()
        if t is None:
            return pose
        limbs = {x.index: x.position for x in self.targets.values() if x.active and x.index in LIMBS}
        legs = self.character.decode(pose.latent, self.character.grounded()).local_rot
        return pelvis_pose(pose, t.position, self.planted, self.character.skeleton.offsets, limbs, legs)

    def standing_place(self) -> np.ndarray:
        """Where the body stands (2,) metres, what a key keeps as its ``root``: the
        pelvis's level place, or under a pelvis-only target that of the body the latent
        describes (the pelvis before it was dragged, :mod:`engine.authoring.pelvis_drag`)."""
        pose = self.pose
        return (pose.decoded if self.pelvis_target() is not None and pose.decoded is not None else pose.positions)[
            0, :2
        ].copy()

    def hips_handle(self) -> np.ndarray:
        """Where a drag of the hips starts (3,) metres, the point :meth:`drag_hips` moves:
        the target on ``root`` while crouching (the body's level place at the pelvis's
        height; the balanced pelvis sits behind it), else the pelvis."""
        held = self.targets.get("root")
        return np.asarray(held.position if held is not None else self.pose.root_pos, float).copy()

    # -- solving -------------------------------------------------------------------
    def _inputs(self) -> tuple[list[Constraint], dict, dict]:
        """The solve's terms: the user's targets, the planted feet that no target moves, the
        scene's constraints; and the exact limb and rotation steps after it."""
        targets, planted = list(self.targets.values()), self.planted
        pelvis = self.pelvis_target()
        if pelvis is not None and self.pose.decoded is not None:
            # the latent solves the body standing where it stood; the pelvis step follows
            decoded = self.pose.decoded
            shift = decoded[0] - pelvis.position
            targets = [replace(t, position=t.position + shift) for t in targets if t.joint != "root"]
            planted = {j: decoded[sk.JOINT_INDEX[j]].copy() for j in planted}
        if self.options.plant_feet:
            moved = moved_feet(self.targets)
            targets += [
                JointTarget(j, p, weight=self.options.plant_weight)
                for j, p in planted.items()
                if FOOT_OF[j] not in moved and j not in self.targets
            ]
        terms, reach, rotations = solve_inputs(targets)
        for t in terms:
            if t.dof == 6:
                t.rotation_weight *= self.options.turn_weight
        return terms + list(self.constraints), reach, rotations

    def plant_where_standing(self) -> None:
        """Plant the feet where the current pose has them (after the pose was set from a
        key, or the whole body was moved or turned)."""
        self.planted = {j: self.pose.positions[sk.JOINT_INDEX[j]].copy() for j in PLANTED}
        self.anchor = None

    def _replant(self) -> None:
        """A foot the user moves is planted where it is left."""
        moved = moved_feet(self.targets)
        for j in PLANTED:
            if FOOT_OF[j] in moved:
                self.planted[j] = self.pose.positions[sk.JOINT_INDEX[j]].copy()

    def _where(self, adjust: bool = True) -> np.ndarray:
        """Where the root is held during the solve (3,) metres (:func:`engine.authoring.pose_root.root_where`)."""
        if self.pelvis_target() is not None and self.pose.decoded is not None:
            return self.pose.decoded[0].copy()  # the standing body's root (see _inputs)
        stance = Stance(self.pose, self.targets, self.planted, self.options)
        return root_where(stance, self._standing_root, self._lowest_reach, adjust)

    def solve(self, iterations: int = ITERATIONS) -> Pose:
        """One continuous solve from the current pose (a drag event): a round of
        ``iterations`` steps, and up to ``options.reach_rounds`` more while a dragged
        joint is short of its target."""
        terms, reach, rotations = self._inputs()
        c, o = self.character, self.options
        if self.anchor is None:
            self.anchor = self.pose
        best: tuple[float, Pose | None] = (np.inf, None)
        for round_ in range(1 + (max(0, o.reach_rounds) if iterations > 0 else 0)):
            gap = self.shortfall()
            if round_ and gap <= o.reach_tolerance:
                break
            where = self._where(o.free_height or iterations > 0)
            if o.free_height:
                ctx = c.grounded(where[:2], self.heading, self.frame, prior=self.base_latent)
            else:
                ctx = c.placed(where, self.heading, self.frame, prior=self.base_latent)
            before = self.pose
            solved = c.solve(
                self.pose.latent,
                terms + self._hold_terms(where),
                ctx,
                reach,
                rotations,
                iterations=iterations,
                prior_weight=o.prior_weight,
                rule="sgd",
                step_size=STEP_SIZE,
            )
            self.pose = self.pelvis_step(self._kept_trunk(solved, reach, rotations))
            short = self.shortfall()
            if round_ and short > gap + OVERSHOOT:
                # the plain steps overshot (a folded body near the floor): keep the round before
                self.pose = before
                break
            if short < best[0]:
                best = (short, self.pose)
        if best[1] is not None and self.shortfall() > best[0]:
            # rounds near the floor can circle their target: the event ends on its closest one
            self.pose = best[1]
        self._replant()
        self._solved = self.pose
        return self.pose

    def _kept_trunk(self, pose: Pose, reach: dict, rotations: dict) -> Pose:
        """``pose`` with ``options.keep_trunk``'s rule (:mod:`engine.authoring.pose_trunk`)
        applied against :attr:`anchor`, while no trunk or leg joint has a target; the
        pelvis is kept only while it stands on both planted feet."""
        o = self.options
        if (
            not o.keep_trunk
            or self.anchor is None
            or any(t.active and t.index in TRUNK + LEGS for t in self.targets.values())
        ):
            return pose
        forward = QN.rotate(yaw_quaternion(self.heading), sk.FORWARD)
        limbs = {j: np.asarray(p, float) for j, p in reach.items() if j in LIMBS}
        pelvis = o.plant_feet and pose.root_pos[2] >= self._standing_root - SQUAT_FROM
        return keep_trunk(pose, self.anchor, forward, self.character.skeleton.offsets, limbs, dict(rotations), pelvis)

    def held(self) -> list[int]:
        """Joints the hold pulls towards the anchor (see ``PoseOptions.hold_weight`` and
        :func:`engine.authoring.pose_hold.held_joints`)."""
        return held_joints(self.targets, self.planted, self.options.plant_feet)

    def _hold_terms(self, where: np.ndarray) -> list[Constraint]:
        """The hold's terms for a solve with the root at ``where (3,)`` metres
        (:func:`engine.authoring.pose_hold.hold_terms`)."""
        w = self.options.hold_weight
        if w <= 0 or self.anchor is None:
            return []
        return hold_terms(self.anchor, self.held(), where, w)

    def shortfall(self) -> float:
        """How far the solve is from its targets, metres (:func:`engine.authoring.pose_root.shortfall`)."""
        return shortfall(Stance(self.pose, self.targets, self.planted, self.options))

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

    def settle(self, cancelled: CancelCheck | None = None) -> Pose:
        """An offline, grounded solve from the current pose (when a drag ends), then up to
        ``options.settle_rounds`` grounded rounds of the drag's plain steps while a dragged
        wrist or ankle is short of its target: the offline solve's adaptive steps can stop
        at once from a pose that is already close, where the plain steps still close
        the gap. ``cancelled()`` is asked before each round (a worker's settle stops
        within a round; raises :class:`~engine.progress.Cancelled`)."""
        terms, reach, rotations = self._inputs()
        c, o = self.character, self.options
        if self.anchor is None:
            self.anchor = self.pose
        where = self._where()
        ctx = c.grounded(where[:2], self.heading, self.frame, prior=self.base_latent)
        solved = c.solve(
            self.pose.latent, terms + self._hold_terms(where), ctx, reach, rotations, prior_weight=o.prior_weight
        )
        self.pose = self.pelvis_step(self._kept_trunk(solved, reach, rotations))
        for _ in range(max(0, o.settle_rounds)):
            if self.shortfall() <= o.reach_tolerance:
                break
            check(cancelled)
            where = self._where()
            ctx = c.grounded(where[:2], self.heading, self.frame, prior=self.base_latent)
            solved = c.solve(
                self.pose.latent,
                terms + self._hold_terms(where),
                ctx,
                reach,
                rotations,
                iterations=ITERATIONS,
                prior_weight=o.prior_weight,
                rule="sgd",
                step_size=STEP_SIZE,
            )
            self.pose = self.pelvis_step(self._kept_trunk(solved, reach, rotations))
        self._replant()
        self._solved = self.pose
        return self.pose

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
