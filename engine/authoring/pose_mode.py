"""Pose mode: the character without a clip, posed continuously by dragged joint targets.

A :class:`PoseMode` holds the character, its current pose and the user's targets and
constraints. :meth:`PoseMode.solve` is one short solve from the current pose (call it on
every drag event, :data:`ITERATIONS` plain gradient steps with the root held where it
stands, then the feet grounded and targeted wrists / ankles put exactly on their
targets; while a targeted wrist or ankle is still beyond its limb's reach, up to
``PoseOptions.reach_rounds`` further rounds of those steps, so a low reach bends the
body within the drag); with targets only it runs on the solver's fast path. :meth:`PoseMode.settle`
is a full offline solve (grounded, so the body may crouch), for when the drag ends.
Bone lengths are those of the skeleton by construction (forward kinematics of fixed
offsets), and the lowest foot stands on the floor after every solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.character import PRIOR_WEIGHT, Character, Pose
from engine.authoring.pose_metrics import centre_of_mass
from engine.authoring.targets import JointTarget, solve_inputs
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.features import encoder_input, pose_from_motion
from engine.motion.clip import Motion
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


def encode_frames(vae, motion: Motion, frames: list[int]) -> np.ndarray:
    """The VAE encoder's mean latents ``(len(frames), L)`` of some frames of ``motion``."""
    local = torch.as_tensor(motion.local_rot, dtype=torch.float64)
    root = torch.as_tensor(motion.root_pos, dtype=torch.float64)
    rot, disp = pose_from_motion(local, root)
    idx = list(frames)
    offsets = torch.as_tensor(motion.skeleton.offsets, dtype=torch.float64).expand(len(idx), -1, -1)
    with torch.no_grad():
        mu, _ = vae.encode(encoder_input(rot[idx], disp[idx], offsets).float())
    return mu.numpy().astype(np.float32)


def heading_deg(rotation: np.ndarray) -> float:
    """Yaw of a world rotation ``(4,)`` about +Z, degrees."""
    h = QN.heading(np.asarray(rotation, float))
    return float(np.degrees(2.0 * np.arctan2(h[3], h[0])))


#: Foot joints that stay planted where they stand until the user drags that foot.
PLANTED = ("lankle", "ltoe", "rankle", "rtoe")
_FOOT_OF = {"lankle": "l", "ltoe": "l", "rankle": "r", "rtoe": "r"}


#: Lowest pelvis height the crouch moves it to, as a share of its standing height (a deep
#: squat; the two-bone legs cannot fold much further).
LOWEST_ROOT = 0.45
#: A dragged pelvis crouches once it is this far below its standing height, metres: less
#: is the jitter of a level drag of the hips.
SQUAT_FROM = 0.02


@dataclass
class PoseOptions:
    """How pose mode keeps a pose natural (``bench --pose-tasks --set name=value``).

    Attributes
    ----------
    plant_feet : bool
        Untargeted feet stay where they stand (ankle and toe each a target at their
        planted place) until that foot is dragged; a dragged foot is planted where it is
        left.
    plant_weight : float
        Weight of a planted foot's targets, as a user target's.
    balance : bool
        While both feet are planted, each solve starts with the pelvis moved horizontally
        by ``balance_gain`` of the distance from the centre of mass to the middle of the
        feet, so a body that leans or reaches keeps its weight over its feet (the planted
        feet stay, the legs lean). A pelvis the user drags goes where it is dragged.
    balance_gain : float
        Share of the centre of mass's distance from the feet that one solve corrects.
    balance_tolerance : float
        Distance (metres) from the middle of the feet within which the centre of mass is
        left where it is (well inside a standing support polygon), so a reach forward is
        not pulled back.
    crouch_share : float
        Share of a dragged joint's downward distance to its target that the pelvis takes
        at the start of each solve (the planted legs bend under it), so a low reach
        bends the knees as well as the trunk; the pelvis stays between
        :data:`LOWEST_ROOT` of its standing height and its standing height.
    free_height : bool
        Drags solve with the lowest foot on the floor (the root's height is part of the
        pose, so reaching low bends the knees instead of folding the trunk) instead of
        holding the root where it stands. It runs on the solver's reference path, about
        30 times slower than the fast path that drags use otherwise: too slow for
        interactive drags on two cores.
    prior_weight : float
        Pull towards the starting latent (the character's neutral pose for a new pose),
        which keeps the parts no target constrains as they were.
    reach_rounds : int
        Most further rounds of a drag event's solve (each :data:`ITERATIONS` steps from
        where the last ended, the crouch and balance steps redone first) while a dragged
        joint is more than ``reach_tolerance`` from its target after the exact limb step:
        a reach beyond the arm bends the body further within the same event, and a drag
        that is reached costs one round.
    reach_tolerance : float
        Distance (metres) of a dragged joint from its target below which no further
        round runs.
    """

    plant_feet: bool = True
    plant_weight: float = 1.0
    balance: bool = True
    balance_gain: float = 0.5
    balance_tolerance: float = 0.10
    crouch_share: float = 0.5
    free_height: bool = False
    prior_weight: float = PRIOR_WEIGHT
    reach_rounds: int = 4
    reach_tolerance: float = 0.005


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

    def __init__(self, vae, height: float | None = None, latent: np.ndarray | None = None,
                 root_xy=(0.0, 0.0), heading: float = 0.0, options: PoseOptions | None = None) -> None:  # fmt: skip
        self.options = options or PoseOptions()
        self.character = Character(vae, height)
        self.base_latent = self.character.mean_latent() if latent is None else np.asarray(latent, np.float32)
        self.heading = float(heading)
        self.targets: dict[str, JointTarget] = {}
        self.constraints: list[Constraint] = []
        self.pose: Pose = self.character.decode(self.base_latent, self.character.grounded(root_xy, self.heading))
        self._standing_root = float(self.pose.root_pos[2])
        #: Where each untargeted foot joint stays (world, metres), see :class:`PoseOptions`.
        self.planted: dict[str, np.ndarray] = {}
        self.plant_where_standing()

    @classmethod
    def from_clip_frame(cls, vae, motion: Motion, frame: int, height: float | None = None,
                        options: PoseOptions | None = None) -> "PoseMode":  # fmt: skip
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
    def set_target(self, joint: str, position=None, rotation=None, weight: float | None = None,
                   enabled: bool | None = None) -> JointTarget:  # fmt: skip
        """Create or change the target on ``joint``; arguments left None keep their value
        (a new target starts at the joint's current position, weight 1)."""
        old = self.targets.get(joint)
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        here = self.pose.positions[sk.JOINT_INDEX[joint]]
        t = JointTarget(
            joint,
            position if position is not None else (old.position if old else here),
            rotation if rotation is not None else (old.rotation if old else None),
            weight if weight is not None else (old.weight if old else 1.0),
            enabled if enabled is not None else (old.enabled if old else True),
        )  # fmt: skip
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
        dragged back up to standing height loses the target; one less than
        :data:`SQUAT_FROM` below it gets none, so the jitter of a level drag does not
        crouch. The targets are solved from there."""
        p = np.asarray(position, float)
        level = np.array([p[0] - self.pose.root_pos[0], p[1] - self.pose.root_pos[1], 0.0])
        standing = self._standing_root
        z = float(np.clip(p[2], LOWEST_ROOT * standing, standing))
        held = self.targets.get("root")
        if np.any(level):
            self.pose = self.pose.moved(level)
            self.plant_where_standing()
        if held is not None and z >= standing:
            self.remove_target("root")
        elif held is not None or standing - z > SQUAT_FROM:
            self.set_target("root", np.array([*self.pose.root_pos[:2], z]))
        if self.targets:
            self.solve()
        return self.pose

    # -- solving -------------------------------------------------------------------
    def _moved_feet(self) -> set[str]:
        """The feet (``"l"``, ``"r"``) that an active user target moves."""
        return {_FOOT_OF[t.joint] for t in self.targets.values() if t.joint in _FOOT_OF and t.active}

    def _inputs(self) -> tuple[list[Constraint], dict, dict]:
        """The solve's terms: the user's targets, the planted feet that no target moves, the
        scene's constraints; and the exact limb and rotation steps after it."""
        targets = list(self.targets.values())
        if self.options.plant_feet:
            moved = self._moved_feet()
            targets += [JointTarget(j, p, weight=self.options.plant_weight) for j, p in self.planted.items()
                        if _FOOT_OF[j] not in moved and j not in self.targets]  # fmt: skip
        terms, reach, rotations = solve_inputs(targets)
        return terms + list(self.constraints), reach, rotations

    def plant_where_standing(self) -> None:
        """Plant the feet where the current pose has them (after the pose was set from a
        key, or the whole body was moved or turned)."""
        self.planted = {j: self.pose.positions[sk.JOINT_INDEX[j]].copy() for j in PLANTED}

    def _replant(self) -> None:
        """A foot the user moves is planted where it is left."""
        moved = self._moved_feet()
        for j in PLANTED:
            if _FOOT_OF[j] in moved:
                self.planted[j] = self.pose.positions[sk.JOINT_INDEX[j]].copy()

    def _where(self, adjust: bool = True) -> np.ndarray:
        """Where the root is held during the solve (3,) metres: a target on the root puts
        it there; else, with ``adjust``, the crouch and balance steps move it (see
        :class:`PoseOptions`), which a solve without latent steps does not do, so that it
        only puts the limbs on their targets."""
        root = self.targets.get("root")
        if root is not None and root.active:
            return np.asarray(root.position, float).copy()
        where = self.pose.root_pos.copy()
        o = self.options
        if not adjust:
            return where
        user = [t for t in self.targets.values() if t.active and t.joint != "root" and t.joint not in _FOOT_OF]
        if o.crouch_share > 0 and user:
            drop = min(0.0, min(t.position[2] - self.pose.positions[t.index, 2] for t in user))
            standing = self._standing_root
            where[2] = float(np.clip(where[2] + o.crouch_share * drop, LOWEST_ROOT * standing, standing))
        if o.balance and o.plant_feet and not self._moved_feet():
            feet = np.mean([p[:2] for p in self.planted.values()], axis=0)
            off = feet - centre_of_mass(self.pose.positions)[:2]
            dist = float(np.linalg.norm(off))
            if dist > o.balance_tolerance:
                where[:2] += o.balance_gain * off * (1.0 - o.balance_tolerance / dist)
        return where

    def solve(self, iterations: int = ITERATIONS) -> Pose:
        """One continuous solve from the current pose (a drag event): a round of
        ``iterations`` steps, and up to ``options.reach_rounds`` more while a dragged
        joint is short of its target."""
        terms, reach, rotations = self._inputs()
        c, o = self.character, self.options
        for round_ in range(1 + (max(0, o.reach_rounds) if iterations > 0 else 0)):
            if round_ and self.shortfall() <= o.reach_tolerance:
                break
            if o.free_height:
                ctx = c.grounded(self._where()[:2], self.heading, prior=self.base_latent)
            else:
                ctx = c.placed(self._where(iterations > 0), self.heading, prior=self.base_latent)
            self.pose = c.solve(self.pose.latent, terms, ctx, reach, rotations, iterations=iterations,
                                prior_weight=o.prior_weight, rule="sgd", step_size=STEP_SIZE)  # fmt: skip
        self._replant()
        return self.pose

    def shortfall(self) -> float:
        """Largest distance (metres) of a targeted wrist or ankle from its target in the
        current pose (0 without such targets): after the exact limb step, how far the
        target lies beyond the limb's reach."""
        gaps = [np.linalg.norm(self.pose.positions[t.index] - t.position) for t in self.targets.values()
                if t.active and t.index in LIMBS]  # fmt: skip
        return float(max(gaps, default=0.0))

    def settle(self) -> Pose:
        """An offline, grounded solve from the current pose (when a drag ends), then up to
        ``options.reach_rounds`` grounded rounds of the drag's plain steps while a dragged
        wrist or ankle is short of its target: the offline solve's adaptive steps can stop
        at once from a pose that is already close, where the plain steps still close
        the gap."""
        terms, reach, rotations = self._inputs()
        c, o = self.character, self.options
        ctx = c.grounded(self._where()[:2], self.heading, prior=self.base_latent)
        self.pose = c.solve(self.pose.latent, terms, ctx, reach, rotations, prior_weight=o.prior_weight)
        for _ in range(max(0, o.reach_rounds)):
            if self.shortfall() <= o.reach_tolerance:
                break
            ctx = c.grounded(self._where()[:2], self.heading, prior=self.base_latent)
            self.pose = c.solve(self.pose.latent, terms, ctx, reach, rotations, iterations=ITERATIONS,
                                prior_weight=o.prior_weight, rule="sgd", step_size=STEP_SIZE)  # fmt: skip
        self._replant()
        return self.pose

    def motion(self) -> Motion:
        """The current pose as a one-frame motion on the character's skeleton."""
        return Motion(self.pose.local_rot[None], self.pose.root_pos[None], self.character.skeleton, sk.FPS, "pose")
