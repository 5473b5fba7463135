"""How a pose mode solves its pose (:class:`PoseSolving`, a base of
:class:`engine.authoring.pose_mode.PoseMode`).

:meth:`PoseSolving.solve` is one short solve from the current pose (a drag event):
:data:`ITERATIONS` plain gradient steps with the root held where
:func:`engine.authoring.pose_root.root_where` puts it, then the feet grounded and
targeted wrists / ankles put exactly on their targets, and, unless the root has a target,
the planted feet's toes on their places; while a targeted wrist or ankle is
still beyond its limb's reach, up to ``PoseOptions.reach_rounds`` further rounds, a round
that overshoots dropped. :meth:`PoseSolving.settle` is the offline, grounded solve for
when a drag ends. The solve's terms are the user's targets, the planted feet no target
moves and the scene's constraints; the holds (``PoseOptions.hold_weight``,
``free_arm_weight``), the trunk rule
(``keep_trunk``) and a pelvis-only target's step
(:mod:`engine.authoring.pelvis_drag`) act on every solve.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Character, Pose, yaw_quaternion
from engine.authoring.keys import PLANTED
from engine.authoring.pelvis_drag import pelvis_pose, toes_on
from engine.authoring.pins import pinned_places, pinned_targets
from engine.authoring.pose_hold import arm_reach, free_arm_terms, free_arms, held_joints, hold_terms
from engine.authoring.pose_options import SQUAT_FROM, PoseOptions
from engine.authoring.pose_root import FOOT_OF, Stance, moved_feet, root_where, shortfall, stoop_targets
from engine.authoring.pose_trunk import LEGS, TRUNK, keep_trunk
from engine.authoring.targets import JointTarget, pelvis_only_target, solve_inputs
from engine.constraints.base import Constraint
from engine.kinematics import quat_np as QN
from engine.progress import CancelCheck, check
from engine.solver import FrameContext
from engine.solver.limb_ik import LIMBS, finish

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


class PoseSolving:
    """The solves of a pose mode (see the module doc); :class:`PoseMode` holds the state
    they read and write, declared here."""

    character: Character
    options: PoseOptions
    pose: Pose
    base_latent: np.ndarray
    heading: float
    frame: int
    targets: dict[str, JointTarget]
    constraints: list[Constraint]
    planted: dict[str, np.ndarray]
    anchor: Pose | None
    _standing_root: float
    _lowest_reach: dict[int, float]
    _hanging_reach: dict[int, float]
    _solved: Pose | None

    @property
    def aimed(self) -> dict[str, JointTarget]:
        """The targets the solves aim at, by joint: the user's, a pin acting on
        :attr:`frame` winning on its joint as the bake's does
        (:func:`engine.authoring.pins.pinned_targets`)."""
        aimed, _ = pinned_targets(list(self.targets.values()), self.constraints, self.frame)
        return {t.joint: t for t in aimed}

    def pelvis_target(self) -> JointTarget | None:
        """The root's target when it is active and moves the pelvis only, else None."""
        return pelvis_only_target(self.aimed)

    def pelvis_step(self, pose: Pose) -> Pose:
        """``pose`` with the pelvis on its pelvis-only target, the feet on their planted
        places and targeted wrists and ankles on their targets
        (:func:`engine.authoring.pelvis_drag.pelvis_pose`); ``pose`` itself without one."""
        t = self.pelvis_target()
        if t is None:
            return pose
        limbs = {x.index: x.position for x in self.aimed.values() if x.active and x.index in LIMBS}
        feet, pinned = self.feet_places()
        # a pinned ankle is reached as a target is: its toe goes where the foot's turn takes it
        limbs.update({sk.JOINT_INDEX[j]: feet[j] for j in pinned if sk.JOINT_INDEX[j] in LIMBS})
        legs = self.character.decode(pose.latent, self.character.grounded()).local_rot
        return pelvis_pose(pose, t.position, feet, self.character.skeleton.offsets, limbs, legs)

    def feet_places(self) -> tuple[dict[str, np.ndarray], set[str]]:
        """Where the planted foot joints are held on :attr:`frame`, metres: their planted
        places, a pin acting there winning as over a target
        (:func:`engine.authoring.pins.pinned_places`); and the joints a pin holds."""
        return pinned_places(self.planted, self.constraints, self.frame)

    def _planted(self, pose: Pose) -> Pose:
        """``pose`` after a round of a settle's latent and limb steps, with its feet put
        where they are planted: under a pelvis-only target :meth:`pelvis_step`, else
        :meth:`_toes_planted`."""
        if self.pelvis_target() is not None:
            return self.pelvis_step(pose)
        return self._toes_planted(pose)

    def _toes_planted(self, pose: Pose) -> Pose:
        """``pose`` (a drag event's or a settle's, its planted ankles on their places by
        the legs' two bones) with, under ``options.plant_feet``, each planted foot's ankle
        turned so its toe joint is on its place; ``pose`` itself under a pelvis-only
        target (:meth:`pelvis_step` has put the feet). The toe is a target of the latent
        solve as the ankle is, but a soft one: left to the latent, a drag of a wrist moves
        a planted toe up to 2.5 cm (a reach forward and down) and 3.7 cm in the
        benchmark's pick-up, the foot rolled on its planted ankle, and the settle's
        grounded solve, which moves the root freely, 4.2 cm in the hand-to-knee reach.
        The turn moves no joint but the toes and leaves the latent as it is.

        A drag event (:meth:`solve`) turns the pose it ends on, after its rounds, while
        the root has no target: turned on every round, a low reach's hips dragged back up
        stand 2 cm lower; and while the pelvis crouches under a target on the root (the
        hips dragged down or held), turned toes keep the squat's feet from splaying 3 cm,
        which moves its knees 2.5 cm closer together: a hand then dragged onto a knee in
        the front view passes it by more than the 6 cm that lands it there, and the hips
        dragged back up after a reach to the shin stand 2-5 cm short of standing (0.6-3.6
        cm with the toes left; both with real mouse events). The crouch's toes are left to
        the latent (within 1.7 cm in the benchmark's squat)."""
        if self.pelvis_target() is not None or not self.options.plant_feet:
            return pose
        moved = moved_feet(self.aimed)
        places, pinned = self.feet_places()
        moved |= {FOOT_OF[j] for j in pinned if j.endswith("ankle")}  # a pinned ankle turns its foot itself
        toes = {j: p for j, p in places.items() if j.endswith("toe") and FOOT_OF[j] not in moved}
        if not toes:
            return pose
        local, positions = toes_on(pose.local_rot, pose.root_pos, self.character.skeleton.offsets, toes)
        return Pose(pose.latent, local, pose.root_pos, positions, pose.iterations, pose.decoded)

    def _inputs(self) -> tuple[list[Constraint], dict, dict]:
        """The solve's terms: the user's targets, the planted feet that no target moves, the
        scene's constraints; and the exact limb and rotation steps after it."""
        user = list(self.targets.values())
        planted, shift = self.planted, None
        pelvis = self.pelvis_target()
        if pelvis is not None and self.pose.decoded is not None:
            # the latent solves the body standing where it stood, the user's targets and the
            # pins' places moved by the pelvis's offset; the pelvis step follows
            decoded = self.pose.decoded
            shift = decoded[0] - pelvis.position
            planted = {j: decoded[sk.JOINT_INDEX[j]].copy() for j in planted}
            user = [replace(t, position=t.position + shift) for t in user if t.joint != "root"]
        feet = []
        if self.options.plant_feet:
            moved = moved_feet(self.aimed)
            feet = [
                JointTarget(j, p, weight=self.options.plant_weight)
                for j, p in planted.items()
                if FOOT_OF[j] not in moved and j not in self.aimed
            ]
        # a pin wins over a planted foot as over a target: the exact limb step would otherwise
        # put a pinned ankle back where it was planted, away from the pin
        targets, rules = pinned_targets(user + feet, self.constraints, self.frame, shift)
        terms, reach, rotations = solve_inputs(targets)
        for t in terms:
            if t.dof == 6:
                t.rotation_weight *= self.options.turn_weight
        return terms + rules, reach, rotations

    def _replant(self) -> None:
        """A foot the user moves is planted where it is left."""
        moved = moved_feet(self.aimed)
        for j in PLANTED:
            if FOOT_OF[j] in moved:
                self.planted[j] = self.pose.positions[sk.JOINT_INDEX[j]].copy()

    def _where(self, adjust: bool = True) -> np.ndarray:
        """Where the root is held during the solve (3,) metres (:func:`engine.authoring.pose_root.root_where`)."""
        if self.pelvis_target() is not None and self.pose.decoded is not None:
            return self.pose.decoded[0].copy()  # the standing body's root (see _inputs)
        stance = Stance(self.pose, self.aimed, self.planted, self.options)
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
        gap = self.shortfall()
        for round_ in range(1 + (max(0, o.reach_rounds) if iterations > 0 else 0)):
            if round_ and gap <= o.reach_tolerance:
                break
            where = self._where(o.free_height or iterations > 0)
            stands = self._stands(where)
            if o.free_height:
                ctx = c.grounded(where[:2], self.heading, self.frame, prior=self.base_latent)
            else:
                ctx = c.placed(where, self.heading, self.frame, prior=self.base_latent)
            before = self.pose
            solved = self._plain_steps(terms, ctx, where, reach, rotations, iterations)
            if stands:
                solved = self._standing_height(solved, where, reach, rotations)
            self.pose = self.pelvis_step(self._kept_trunk(solved, reach, rotations))
            short = self.shortfall()
            if round_ and short > gap + OVERSHOOT:
                # the plain steps overshot (a folded body near the floor): keep the round before
                self.pose = before
                break
            if short < best[0]:
                best = (short, self.pose)
            gap = short  # the next round starts from this pose, with the same targets
        if best[1] is not None:
            # rounds near the floor can circle their target: the event ends on its closest one
            self.pose = best[1]
        root = self.aimed.get("root")
        if root is None or not root.active:
            self.pose = self._toes_planted(self.pose)
        self._replant()
        self._solved = self.pose
        return self.pose

    def _stands(self, where: np.ndarray) -> bool:
        """Whether a drag event's solve with the root at ``where (3,)`` metres holds the
        pelvis at its height on both planted feet: they are planted, the targets are an
        arm's or the head's reach (:func:`engine.authoring.pose_hold.arm_reach`: a low
        reach bends the knees as the latent finds), and the pelvis stands (within
        :data:`~engine.authoring.pose_options.SQUAT_FROM` of :attr:`_standing_root`) and
        is not being lowered by a crouch. The legs' exact two-bone step puts the ankles on
        their places from that height (:meth:`_standing_height`). The solve's ground step
        reads the decoded feet, which the latent leaves a few millimetres above their
        planted places when it bends the knees for a reach: grounded on them alone, each
        event would lower the body by that much, 3-4 cm over a 30-cm reach."""
        return bool(
            self.options.plant_feet
            and not self.options.free_height
            and all(f"{s}ankle" in self.planted for s in "lr")
            and arm_reach(self.aimed, self._hanging_reach)
            and where[2] >= self.pose.root_pos[2]
            and where[2] >= self._standing_root - SQUAT_FROM
        )

    def _standing_height(self, pose: Pose, where: np.ndarray, reach: dict, rotations: dict) -> Pose:
        """``pose``, solved with the root at ``where (3,)`` metres on both planted feet
        (:meth:`_stands`), at the height the legs hold it: no lower than ``where`` (the
        ground step may lift it), then lowered by as much as a planted ankle stands above
        its place (one the legs cannot reach from there). The toes do not count: the legs'
        step turns each foot with its shin, which lifts a toe a few millimetres."""
        up = float(where[2] - pose.root_pos[2])
        if up > 0.0:
            pose = self._shifted(pose, up, reach, rotations)
        gap = max(pose.positions[sk.JOINT_INDEX[j], 2] - self.planted[j][2] for j in ("lankle", "rankle"))
        if gap > 0.0:
            pose = self._shifted(pose, -gap, reach, rotations)
        return pose

    def _shifted(self, pose: Pose, dz: float, reach: dict, rotations: dict) -> Pose:
        """``pose`` moved up by ``dz`` metres, its targeted limbs put back on their targets."""
        moved = pose.moved([0.0, 0.0, dz])
        limbs = {j: np.asarray(p, float) for j, p in reach.items() if j in LIMBS}
        offsets = self.character.skeleton.offsets
        local, positions = finish(moved.local_rot, moved.root_pos, offsets, limbs, dict(rotations))
        return Pose(moved.latent, local, moved.root_pos, positions, moved.iterations, moved.decoded)

    def _plain_steps(
        self,
        terms: list[Constraint],
        ctx: FrameContext,
        where: np.ndarray,
        reach: dict,
        rotations: dict,
        iterations: int,
    ) -> Pose:
        """One round of a drag's solve: ``iterations`` plain gradient steps of
        :data:`STEP_SIZE` from the current latent against ``terms``, the hold (for the root
        at ``where``) and the prior, in the context ``ctx``, then the exact limb and
        rotation steps."""
        return self.character.solve(
            self.pose.latent,
            terms + self._hold_terms(where) + self._stoop_terms(where) + self._free_arm_terms(where),
            ctx,
            reach,
            rotations,
            iterations=iterations,
            prior_weight=self.options.prior_weight,
            rule="sgd",
            step_size=STEP_SIZE,
        )

    def _kept_trunk(self, pose: Pose, reach: dict, rotations: dict) -> Pose:
        """``pose`` with ``options.keep_trunk``'s rule (:mod:`engine.authoring.pose_trunk`)
        applied against :attr:`anchor`, while no trunk or leg joint has a target; the
        pelvis is kept only while it stands on both planted feet."""
        o = self.options
        if (
            not o.keep_trunk
            or self.anchor is None
            or any(t.active and t.index in TRUNK + LEGS for t in self.aimed.values())
        ):
            return pose
        forward = QN.rotate(yaw_quaternion(self.heading), sk.FORWARD)
        limbs = {j: np.asarray(p, float) for j, p in reach.items() if j in LIMBS}
        pelvis = o.plant_feet and pose.root_pos[2] >= self._standing_root - SQUAT_FROM
        return keep_trunk(pose, self.anchor, forward, self.character.skeleton.offsets, limbs, dict(rotations), pelvis)

    def held(self) -> list[int]:
        """Joints the hold pulls towards the anchor (see ``PoseOptions.hold_weight`` and
        :func:`engine.authoring.pose_hold.held_joints`)."""
        return held_joints(self.aimed, self.planted, self.options.plant_feet)

    def _hold_terms(self, where: np.ndarray) -> list[Constraint]:
        """The hold's terms for a solve with the root at ``where (3,)`` metres
        (:func:`engine.authoring.pose_hold.hold_terms`)."""
        w = self.options.hold_weight
        if w <= 0 or self.anchor is None:
            return []
        return hold_terms(self.anchor, self.held(), where, w)

    def _free_arm_terms(self, where: np.ndarray) -> list[Constraint]:
        """The free-arm hold's terms (``PoseOptions.free_arm_weight``) for a solve with the
        root at ``where (3,)`` metres (:func:`engine.authoring.pose_hold.free_arm_terms`)."""
        w = self.options.free_arm_weight
        if w <= 0 or self.anchor is None or self.pelvis_target() is not None:
            return []
        arms = free_arms(self.aimed, self._hanging_reach, self.options.plant_feet)
        return free_arm_terms(self.anchor, self.pose, arms, where, w)

    def _stoop_terms(self, where: np.ndarray) -> list[Constraint]:
        """The trunk's pull towards wrist targets a stoop reaches, for a solve with the root
        at ``where (3,)`` metres (:func:`engine.authoring.pose_root.stoop_targets`). Under
        a pelvis-only target the latent solves the body where it stood, with the targets
        moved by the pelvis's offset (:meth:`_inputs`): the pull is that body's."""
        pose, targets = self.pose, self.aimed
        pelvis = self.pelvis_target()
        if pelvis is not None:
            if pose.decoded is None:
                return []
            shift = pose.decoded[0] - pelvis.position
            targets = {j: replace(t, position=t.position + shift) for j, t in targets.items()}
            pose = replace(pose, positions=pose.decoded, root_pos=pose.decoded[0].copy())
        stance = Stance(pose, targets, self.planted, self.options)
        return [t.constraint() for t in stoop_targets(stance, where, self._lowest_reach)]

    def shortfall(self) -> float:
        """How far the solve is from its targets, metres (:func:`engine.authoring.pose_root.shortfall`)."""
        return shortfall(Stance(self.pose, self.aimed, self.planted, self.options))

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
        extra = self._hold_terms(where) + self._stoop_terms(where) + self._free_arm_terms(where)
        solved = c.solve(self.pose.latent, terms + extra, ctx, reach, rotations, prior_weight=o.prior_weight)
        self.pose = self._planted(self._kept_trunk(solved, reach, rotations))
        for _ in range(max(0, o.settle_rounds)):
            if self.shortfall() <= o.reach_tolerance:
                break
            check(cancelled)
            where = self._where()
            ctx = c.grounded(where[:2], self.heading, self.frame, prior=self.base_latent)
            solved = self._plain_steps(terms, ctx, where, reach, rotations, ITERATIONS)
            self.pose = self._planted(self._kept_trunk(solved, reach, rotations))
        self._replant()
        self._solved = self.pose
        return self.pose
