"""Where DragPoser's body is and which way it faces, frame by frame (the root rules of
:class:`engine.methods.dragposer.DragPoserMethod`; the solver side is
:mod:`engine.solver.pose`, the rules are described in ``docs/optimizer.md``).

Every function reads the method's sensor constraints (joint name ->
:class:`~engine.constraints.SensorConstraint`, enabled while connected) and returns the
solver's root objects (:class:`~engine.solver.RootFrame`, :class:`~engine.solver.RootOverride`,
:class:`~engine.solver.RootAnchor`); none keeps state. :class:`Conditioning` is the
root's motion as the temporal predictor reads it.
"""

from __future__ import annotations

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints import SensorConstraint
from engine.kinematics import quaternion as Q
from engine.kinematics.root import root_displacement
from engine.solver import OptimizerSettings, RootAnchor, RootFrame, RootOverride
from engine.solver.pose import (
    BODY_HEADING_LIMIT_DEG,
    clamp_heading,
    follow_fraction,
    follow_heading,
    head_hands_facing,
)

Sensors = dict[str, SensorConstraint]
_HEIGHT_IDX = [sk.JOINT_INDEX[j] for j in sk.HEIGHT_JOINTS]


def root_override(sensors: Sensors) -> RootOverride | None:
    """The connected hip tracker's reading (rotation None for a 3-DoF one), else None."""
    c = sensors.get("root")
    if c is None or not c.enabled:
        return None
    pos = torch.as_tensor(c.position, dtype=torch.float32)
    rot = torch.as_tensor(Q.normalize(c.rotation), dtype=torch.float32) if c.dof == 6 else None
    return RootOverride(pos, rot)


def reference_root(
    previous: RootFrame,
    sensors: Sensors,
    s: OptimizerSettings,
    override: RootOverride | None,
    facing: np.ndarray | None,
    fps: float = sk.FPS,
    learned: bool = False,
) -> RootFrame:
    """The root the decoded root pose is relative to: the previous solved root
    ``previous``, whose heading (setting ``heading = anchor``) is kept, when there is no
    hip tracker, within :data:`engine.solver.pose.HEADING_LIMIT_DEG` of the anchor
    tracker's heading and then within ``hands_heading_limit`` of the facing of that
    tracker and the hands (:func:`engine.solver.pose.head_hands_facing`); and within
    :data:`~engine.solver.pose.BODY_HEADING_LIMIT_DEG` of the body heading ``facing
    (4,)`` of the feet and hands (:func:`engine.solver.pose.body_facing`) when the hip
    tracker gives no rotation, and turned towards it with the time constant
    ``body_heading_follow`` when ``learned`` (the heading network's facing), else
    ``lines_heading_follow`` (seconds, at ``fps`` frames per second)."""
    hip = sensors.get("root")
    if (
        override is not None
        and override.rotation is None
        and s.heading == "anchor"
        and facing is not None
        and hip is not None
        and hip.enabled
    ):
        rot = clamp_heading(previous.rotation.double().numpy(), facing, BODY_HEADING_LIMIT_DEG)
        tau = s.body_heading_follow if learned else s.lines_heading_follow
        rot = follow_heading(rot, facing, follow_fraction(tau, fps))
        return RootFrame(torch.as_tensor(rot, dtype=torch.float32), previous.position)
    if override is not None or s.heading != "anchor" or s.root_anchor == "none":
        return previous
    c = sensors.get(s.root_anchor)
    if c is None or not c.enabled or c.dof != 6:
        return previous
    head = Q.normalize(c.rotation)
    rot = clamp_heading(previous.rotation.double().numpy(), head)
    if s.hands_heading_limit < 180.0:
        hands: dict[str, np.ndarray] = {
            j: sensors[j].position for j in ("lwrist", "rwrist") if j in sensors and sensors[j].enabled
        }
        body = head_hands_facing(head, hands)
        if body is not None:
            rot = clamp_heading(rot, body, s.hands_heading_limit)
    return RootFrame(torch.as_tensor(rot, dtype=torch.float32), previous.position)


def held_root(previous: RootFrame, points: dict[str, np.ndarray], last_points: dict[str, np.ndarray]) -> RootOverride:
    """Where the root goes when neither a hip tracker nor the anchor (head) tracker is
    connected (e.g. only the hands, with ``--faulty``): nothing measures where the body
    is, and integrating the decoded displacement ran away (3 m within 70 frames on a
    validation clip). The root keeps its height and moves horizontally with the mean of
    the trackers connected in this frame (``points``, joint -> world position ``(3,)``,
    metres) and the previous one (``last_points``); its rotation is solved as usual."""
    pos = previous.position.double().numpy().copy()
    shared = [j for j in points if j in last_points]
    if shared:
        pos[:2] += np.mean([points[j][:2] - last_points[j][:2] for j in shared], axis=0)
    return RootOverride(torch.as_tensor(pos, dtype=torch.float32), None)


def root_anchor(sensors: Sensors, s: OptimizerSettings) -> RootAnchor | None:
    """The head tracker places the body when there is no hip tracker (setting
    ``root_anchor``; ``none`` integrates the decoded displacement instead)."""
    if s.root_anchor == "none":
        return None
    c = sensors.get(s.root_anchor)
    if c is None or not c.enabled:
        return None
    return RootAnchor(sk.JOINT_INDEX[c.joint], torch.as_tensor(c.position, dtype=torch.float32))


def initial_root(skeleton: sk.Skeleton, sensors: Sensors, facing: np.ndarray | None) -> RootFrame:
    """Where the first frame's root is relative to: the hip sensor, else below the head
    sensor by the rest root-to-head offset, else at rest height under the trackers'
    mean, facing their heading (or -Y); ``facing (4,)`` is the body heading of the feet
    and hands, used for a hip tracker without rotation."""
    rest = skeleton.rest_positions()
    rot = np.array([1.0, 0.0, 0.0, 0.0])
    live = {j: c for j, c in sensors.items() if c.enabled}
    if "root" in live:
        pos = live["root"].position.copy()
        if live["root"].dof == 6:
            rot = Q.heading(live["root"].rotation)
        elif facing is not None:  # positions only: face the way the feet and hands say
            rot = facing.copy()
    elif "upperneck" in live:
        head = live["upperneck"]
        if head.dof == 6:
            rot = Q.heading(head.rotation)
        pos = head.position - Q.rotate(rot, rest[sk.JOINT_INDEX["upperneck"]])
    elif live:
        pos = np.mean([c.position for c in live.values()], axis=0)
        pos[2] = -rest[:, 2].min()
    else:
        pos = np.array([0.0, 0.0, -rest[:, 2].min()])
    return RootFrame(torch.as_tensor(rot, dtype=torch.float32), torch.as_tensor(pos, dtype=torch.float32))


class Conditioning:
    """The temporal predictor's conditioning of a frame ``(C,)``, computed on first call:
    the root displacement summed over the last ``n`` frames (each in its previous heading
    frame, :func:`~engine.kinematics.root.root_displacement`), then the heights of
    :data:`~engine.skeleton.HEIGHT_JOINTS` (engine.models.predictor).

    Parameters
    ----------
    roots : tuple of (Tensor (4,), Tensor (3,), Tensor (3,))
        Per frame, oldest first: the previous root's rotation and position and this
        frame's root position (float32, never changed afterwards).
    positions : Tensor (22, 3)
        The frame's solved joint positions, float32, metres.
    """

    def __init__(
        self, roots: tuple[tuple[torch.Tensor, torch.Tensor, torch.Tensor], ...], positions: torch.Tensor
    ) -> None:
        self.roots, self.positions = roots, positions
        self._value: torch.Tensor | None = None

    def __call__(self) -> torch.Tensor:
        if self._value is None:
            disps = torch.stack([root_displacement(*r) for r in self.roots])
            self._value = torch.cat((disps.sum(0), self.positions[_HEIGHT_IDX, 2]))
        return self._value
