"""The authored character: the canonical skeleton at a chosen height, standing on the floor,
posed by latent-space solves against joint targets (DragPoser's pose optimizer, sec. 4.4,
with the user's targets in place of trackers).

Without trackers nothing measures where the body is. Two placements:

* **grounded** (:meth:`Character.grounded`, offline key solves): the root's horizontal
  position is given and :class:`Ground` lifts or lowers the body so that its lowest foot
  stands on the floor. The shift is part of the differentiable pose, so the solver sees
  that bending the knees lowers the whole body (a low target can be reached by
  crouching). This runs on the solver's reference path.
* **placed** (:meth:`Character.placed`, the continuous pose mode and in-betweens): the
  root is held at a given position during the solve (the solver's fast path takes it
  when every term is a target or the prior) and the solved pose is then shifted
  vertically onto the floor (:meth:`Character.ground_shift`).

After the latent solve, targeted wrists and ankles are put exactly on their targets by
their limbs' two bones, and joints with a rotation target take it
(:func:`engine.solver.limb_ik.finish`), as the ``dragposer`` method does for trackers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.pose_options import PRIOR_WEIGHT
from engine.constraints.base import Constraint
from engine.constraints.temporal_prior import TemporalPriorConstraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.features import encoder_input, pose_from_motion
from engine.kinematics.fk import fk, fk_positions
from engine.kinematics.root import place_root
from engine.motion.clip import Motion
from engine.solver import FrameContext, OptimizerSettings, PoseOptimizer, RootFrame, RootOverride
from engine.solver.limb_ik import LIMBS, finish

#: Joints whose lowest one stands on the floor.
FOOT_JOINTS = tuple(sk.JOINT_INDEX[j] for j in ("lankle", "rankle", "ltoe", "rtoe"))
#: Height range accepted for a character, metres.
HEIGHT_RANGE = (0.5, 2.5)
#: Plain gradient steps have a fixed size, set for targets of weight about 1; on a term
#: weighted far above them (a pin's default 30) the first steps overshoot (a pin 6 mm off:
#: the total 0.03 -> 4.8 in one step) and the latent wanders off, moving joints no term
#: holds by 20-40 cm. A plain-step solve whose total rises above this multiple of its
#: start is solved again with half the step, at most :data:`HALVINGS` times.
TOTAL_RISE = 1.5
HALVINGS = 6


def yaw_quaternion(yaw_deg: float) -> np.ndarray:
    """Rotation ``(4,)`` (w, x, y, z) by ``yaw_deg`` degrees about +Z."""
    h = np.radians(float(yaw_deg)) / 2.0
    return np.array([np.cos(h), 0.0, 0.0, np.sin(h)])


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


@dataclass
class Ground:
    """Root anchor of an authored pose: root at ``xy``, lowest foot on the floor.

    Attributes
    ----------
    xy : Tensor (2,)
        Root's horizontal world position, metres.
    foot_heights : Tensor (4,)
        Heights above the floor of :data:`FOOT_JOINTS` when the foot is flat (rest pose).
    """

    xy: torch.Tensor
    foot_heights: torch.Tensor

    def apply(self, positions: torch.Tensor) -> torch.Tensor:
        """``positions (22, 3)`` shifted so the root is at ``xy`` and the lowest foot on z = 0."""
        lift = (positions[list(FOOT_JOINTS), 2] - self.foot_heights).min()
        shift = torch.cat((self.xy - positions[0, :2], -lift[None]))
        return positions + shift


@dataclass
class HeldRoot(RootOverride):
    """The root held at ``position`` during the solve; ``ground``: then shift the pose
    vertically so its lowest foot stands on the floor (False keeps a clip's root)."""

    ground: bool = True


@dataclass
class Pose:
    """One solved pose (numpy, float64).

    Attributes
    ----------
    latent : ndarray (L,)
    local_rot : ndarray (22, 4)
        Local rotations; row 0 is the root's world rotation.
    root_pos : ndarray (3,)
        Root world position, metres.
    positions : ndarray (22, 3)
        World joint positions, metres.
    iterations : int
        Latent update steps the solve took.
    decoded : ndarray (22, 3)
        World joint positions of the latent itself, before the exact limb and rotation
        steps, metres (equal to ``positions`` when no such step ran).
    """

    latent: np.ndarray
    local_rot: np.ndarray
    root_pos: np.ndarray
    positions: np.ndarray
    iterations: int = 0
    decoded: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.decoded is None:
            self.decoded = self.positions.copy()

    def moved(self, delta) -> "Pose":
        """The same pose with the whole body translated by ``delta (3,)`` metres (root
        motion: the latent describes the body relative to its root, so it is unchanged)."""
        d = np.asarray(delta, float).reshape(3)
        return Pose(
            self.latent.copy(),
            self.local_rot.copy(),
            self.root_pos + d,
            self.positions + d,
            self.iterations,
            self.decoded + d,
        )

    def turned(self, yaw_deg: float) -> "Pose":
        """The same pose with the whole body turned by ``yaw_deg`` degrees about the
        vertical through its root (the latent is relative to the heading, so it is unchanged)."""
        q = yaw_quaternion(yaw_deg)
        r = QN.to_matrix(q)
        local = self.local_rot.copy()
        local[0] = QN.mul(q, local[0])
        return Pose(
            self.latent.copy(),
            local,
            self.root_pos.copy(),
            (self.positions - self.root_pos) @ r.T + self.root_pos,
            self.iterations,
            (self.decoded - self.root_pos) @ r.T + self.root_pos,
        )


class Character:
    """The canonical skeleton at ``height`` metres, posed through the frozen pose VAE.

    Parameters
    ----------
    vae : engine.models.PoseVAE
        The decoder (frozen by the optimizer).
    height : float or None
        Standing height, metres (None: the canonical skeleton's own).
    skeleton : Skeleton or None
        A subject's own skeleton instead (a loaded clip's); ``height`` is then ignored.
    """

    def __init__(self, vae, height: float | None = None, skeleton: sk.Skeleton | None = None) -> None:
        base = sk.Skeleton.canonical()
        if skeleton is not None:
            base = skeleton
        elif height is not None:
            if not (HEIGHT_RANGE[0] <= float(height) <= HEIGHT_RANGE[1]):
                raise UserError(f"height must be within {HEIGHT_RANGE[0]}-{HEIGHT_RANGE[1]} m, got {height}")
            base = sk.Skeleton.canonical(float(height) / base.height())
        self.skeleton = base
        self.height = base.height()
        self.vae = vae
        self.latent_dim = int(vae.config.latent)
        rest = base.rest_positions()
        toe_tip = rest[sk.JOINT_INDEX["ltoe"], 2] + sk.END_SITES["ltoe"][2] * base.scale
        lowest = min(rest[:, 2].min(), toe_tip)
        self.foot_heights = torch.tensor([rest[j, 2] - lowest for j in FOOT_JOINTS], dtype=torch.float32)
        self.settings = OptimizerSettings(
            mode="offline", optimizer="adam", tuning="off", max_iterations=150, lr=0.05, patience=15
        )
        # Ground is not a joint anchor, which the fast path knows nothing of
        self._grounded = PoseOptimizer(vae, base.offsets, self.settings, fast=False)
        self._placed = PoseOptimizer(vae, base.offsets, self.settings, fast=True)

    def mean_latent(self) -> np.ndarray:
        """The VAE prior's mean, ``(L,)``: the character's neutral pose."""
        return np.zeros(self.latent_dim, dtype=np.float32)

    def grounded(
        self,
        xy=(0.0, 0.0),
        heading_deg: float = 0.0,
        frame: int = 0,
        previous: np.ndarray | None = None,
        prior: np.ndarray | None = None,
    ) -> FrameContext:
        """Context of a grounded solve: root at ``xy (2,)`` metres, lowest foot on the floor,
        facing ``heading_deg`` (about +Z from the canonical -Y); ``previous (22, 3)``
        positions for contact and sliding terms; ``prior (L,)`` the latent pulled towards."""
        ref = RootFrame(_f(yaw_quaternion(heading_deg)), _f([xy[0], xy[1], 0.0]))
        anchor = Ground(_f(np.asarray(xy, float)[:2]), self.foot_heights)
        return FrameContext(ref, None, anchor, _f_or_none(previous), _f_or_none(prior), frame)

    def placed(
        self,
        root: np.ndarray,
        heading_deg: float = 0.0,
        frame: int = 0,
        previous: np.ndarray | None = None,
        prior: np.ndarray | None = None,
        reference: np.ndarray | None = None,
        ground: bool = True,
    ) -> FrameContext:
        """Context of a placed solve: the root held at ``root (3,)`` metres during the
        solve, then grounded (unless ``ground`` is False); the decoded root rotation is
        relative to the heading of ``reference (4,)`` (a clip's previous root rotation)
        or else of ``heading_deg``; the rest as :meth:`grounded`."""
        ref = RootFrame(_f(yaw_quaternion(heading_deg) if reference is None else reference), _f(root))
        held = HeldRoot(_f(root), None, ground)
        return FrameContext(ref, held, None, _f_or_none(previous), _f_or_none(prior), frame)

    def ground_shift(self, positions: np.ndarray) -> float:
        """Metres to add to z so the lowest foot of ``positions (22, 3)`` stands on the floor."""
        return float(self.ground_shifts(np.asarray(positions)[None])[0])

    def ground_shifts(self, positions: np.ndarray) -> np.ndarray:
        """:meth:`ground_shift` of each pose of ``positions (B, 22, 3)``: ``(B,)`` metres."""
        feet = np.asarray(positions, float)[:, list(FOOT_JOINTS), 2] - self.foot_heights.double().numpy()
        return -feet.min(axis=1)

    def decode(self, latent: np.ndarray, ctx: FrameContext) -> Pose:
        """The grounded pose of ``latent (L,)`` without any solve."""
        with torch.no_grad():
            state = self._grounded.decode(torch.as_tensor(np.asarray(latent), dtype=torch.float32), ctx)
        return self._pose(np.asarray(latent, np.float32), state, 0, ctx)

    def decode_many(
        self, latents: np.ndarray, xy: np.ndarray, headings_deg: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The grounded poses of many latents at once, without any solve: what
        :meth:`decode` gives for each row with ``grounded(xy[i], headings_deg[i])``, in one
        decoder call (a 60-frame preview costs ~10 ms where 60 :meth:`decode` calls cost ~900).

        Parameters
        ----------
        latents : ndarray (B, L)
        xy : ndarray (B, 2)
            Root's horizontal world positions, metres.
        headings_deg : ndarray (B,)
            Facing, degrees about +Z from the canonical -Y.

        Returns
        -------
        local_rot : ndarray (B, 22, 4)
            Unit local rotations, row 0 the root's world rotation.
        root_pos : ndarray (B, 3)
            Metres.
        positions : ndarray (B, 22, 3)
            World joint positions, metres, the lowest foot on the floor.
        """
        z = torch.as_tensor(np.asarray(latents, np.float32).reshape(-1, self.latent_dim))
        b = z.shape[0]
        headings = np.asarray(headings_deg, float).reshape(b)
        with torch.no_grad():
            rot, disp = self._grounded.decoder.decode(z)
            h = _f(np.stack([yaw_quaternion(a) for a in headings]) if b else np.zeros((0, 4)))
            root_rot, _ = place_root(Q.heading(h), rot[:, 0])
        local = torch.cat((root_rot[:, None], rot[:, 1:]), dim=1).double().numpy()
        local = local / np.linalg.norm(local, axis=-1, keepdims=True)
        positions = fk_positions(local, np.zeros((b, 3)), self.skeleton.offsets)
        # as Ground.apply: the root over xy, the lowest foot joint at its flat height
        lift = self.ground_shifts(positions)
        shift = np.concatenate((np.asarray(xy, float).reshape(b, 2) - positions[:, 0, :2], lift[:, None]), axis=1)
        positions = positions + shift[:, None, :]
        return local, positions[:, 0].copy(), positions

    def solve(
        self,
        start: np.ndarray,
        constraints: list[Constraint],
        ctx: FrameContext,
        reach: dict[int, np.ndarray] | None = None,
        rotations: dict[int, np.ndarray] | None = None,
        iterations: int | None = None,
        prior_weight: float = PRIOR_WEIGHT,
        rule: str = "adam",
        step_size: float = 0.3,
    ) -> Pose:
        """Solve a pose from latent ``start (L,)``.

        Parameters
        ----------
        constraints : list of Constraint
            Every term of the solve (targets, the scene's rules); a prior towards
            ``ctx.prediction`` is added with ``prior_weight`` when there is one.
        reach : dict joint -> ndarray (3,)
            Wrist / ankle targets put exactly by their limbs after the solve, metres.
        rotations : dict joint -> ndarray (4,)
            World rotations the joints take exactly after the solve.
        iterations : int or None
            A fixed step count (the continuous pose mode); None: offline, until the
            terms are satisfied or stop improving.
        rule : str
            Latent update rule (``OptimizerSettings.optimizer``): ``adam`` reaches far
            targets from the mean pose quickly; ``sgd`` moves only the latent directions
            the terms constrain, so a pose that starts near its answer does not wander.
        step_size : float
            Of the ``sgd`` rule, ``z -= step_size * gradient``.
        """
        s = self.settings
        s.optimizer, s.step_size = rule, float(step_size)
        s.mode, s.iterations = ("realtime", int(iterations)) if iterations is not None else ("offline", s.iterations)
        terms = list(constraints)
        if ctx.prediction is not None and prior_weight > 0:
            terms.append(TemporalPriorConstraint(name="authoring prior", weight=prior_weight))
        opt = self._grounded if isinstance(ctx.root_anchor, Ground) else self._placed
        z0 = torch.as_tensor(np.asarray(start), dtype=torch.float32)
        sol = opt.solve(z0, terms, ctx)
        for _ in range(HALVINGS if rule == "sgd" else 0):
            if not overshot(sol.losses):
                break
            s.step_size *= 0.5
            sol = opt.solve(z0, terms, ctx)
        pose = self._pose(sol.latent.numpy().astype(np.float32), sol.state, sol.iterations, ctx)
        limbs = {j: np.asarray(p, float) for j, p in (reach or {}).items() if j in LIMBS}
        if limbs or rotations:
            pose.local_rot, pose.positions = finish(
                pose.local_rot, pose.root_pos, self.skeleton.offsets, limbs, dict(rotations or {})
            )
        return pose

    def _pose(self, latent: np.ndarray, state, iterations: int, ctx: FrameContext) -> Pose:
        # unit rotations in float64 and one FK pass: what is written (BVH) is what is measured
        local = state.local_rot.detach().double().numpy()
        local = local / np.linalg.norm(local, axis=-1, keepdims=True)
        root = state.positions[0].detach().double().numpy().copy()
        positions = fk(local, root, self.skeleton.offsets)[0]
        if isinstance(ctx.root_override, HeldRoot) and ctx.root_override.ground:
            dz = self.ground_shift(positions)
            root[2] += dz
            positions[:, 2] += dz
        return Pose(latent, local, root, positions, iterations)


def overshot(losses: list[dict[str, float]]) -> bool:
    """Whether a solve's total loss (``losses``, one record per evaluation) rose above
    :data:`TOTAL_RISE` times its start: its fixed steps were too long for its terms."""
    totals = [r["total"] for r in losses]
    return len(totals) > 1 and max(totals[1:]) > TOTAL_RISE * totals[0]


def _f(a) -> torch.Tensor:
    return torch.as_tensor(np.asarray(a, dtype=np.float64), dtype=torch.float32)


def _f_or_none(a) -> torch.Tensor | None:
    return None if a is None else _f(a)
