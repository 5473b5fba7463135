"""Pose mode: the character without a clip, posed continuously by dragged joint targets.

A :class:`PoseMode` holds the character, its current pose and the user's targets and
constraints. :meth:`PoseMode.solve` is one short solve from the current pose (call it on
every drag event, :data:`ITERATIONS` plain gradient steps with the root held where it
stands, then the feet grounded and targeted wrists / ankles put exactly on their
targets); with targets only it runs on the solver's fast path. :meth:`PoseMode.settle`
is a full offline solve (grounded, so the body may crouch), for when the drag ends.
Bone lengths are those of the skeleton by construction (forward kinematics of fixed
offsets), and the lowest foot stands on the floor after every solve.
"""

from __future__ import annotations

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.character import Character, Pose
from engine.authoring.targets import JointTarget, solve_inputs
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.features import encoder_input, pose_from_motion
from engine.motion.clip import Motion

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
    """

    def __init__(self, vae, height: float | None = None, latent: np.ndarray | None = None,
                 root_xy=(0.0, 0.0), heading: float = 0.0) -> None:  # fmt: skip
        self.character = Character(vae, height)
        self.base_latent = self.character.mean_latent() if latent is None else np.asarray(latent, np.float32)
        self.heading = float(heading)
        self.targets: dict[str, JointTarget] = {}
        self.constraints: list[Constraint] = []
        self.pose: Pose = self.character.decode(self.base_latent, self.character.grounded(root_xy, self.heading))

    @classmethod
    def from_clip_frame(cls, vae, motion: Motion, frame: int, height: float | None = None) -> "PoseMode":
        """Start from frame ``frame`` of ``motion``: its encoded latent, where it stands
        and its facing."""
        if not 0 <= frame < len(motion):
            raise UserError(f"frame {frame} is outside the clip (0-{len(motion) - 1})")
        latent = encode_frames(vae, motion, [frame])[0]
        return cls(vae, height, latent, motion.root_pos[frame, :2], heading_deg(motion.local_rot[frame, 0]))

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

    # -- solving -------------------------------------------------------------------
    def solve(self, iterations: int = ITERATIONS) -> Pose:
        """One continuous solve from the current pose (a drag event)."""
        terms, reach, rotations = solve_inputs(list(self.targets.values()))
        c = self.character
        ctx = c.placed(self.pose.root_pos, self.heading, prior=self.base_latent)
        self.pose = c.solve(self.pose.latent, terms + list(self.constraints), ctx, reach, rotations,
                            iterations=iterations, rule="sgd", step_size=STEP_SIZE)  # fmt: skip
        return self.pose

    def settle(self) -> Pose:
        """An offline, grounded solve from the current pose (when a drag ends)."""
        terms, reach, rotations = solve_inputs(list(self.targets.values()))
        c = self.character
        ctx = c.grounded(self.pose.root_pos[:2], self.heading, prior=self.base_latent)
        self.pose = c.solve(self.pose.latent, terms + list(self.constraints), ctx, reach, rotations)
        return self.pose

    def motion(self) -> Motion:
        """The current pose as a one-frame motion on the character's skeleton."""
        return Motion(self.pose.local_rot[None], self.pose.root_pos[None], self.character.skeleton, sk.FPS, "pose")
