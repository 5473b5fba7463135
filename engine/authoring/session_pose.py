"""The pose of an authoring session, edited by its joints and its body
(:class:`PoseEditing`, a base of :class:`engine.authoring.session.AuthoringSession`).

Dragging a joint sets its target and solves (a pin holding the joint on the current
frame moves with it); the hips move and turn the whole body or lower the pelvis; targets
are turned, switched, weighted and cleared; the settle is an offline solve, run on any
thread and applied as one undo step. Each gesture is one edit through the session's
``edit`` (a drag's moves merge into one undo step).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.feet_apart import OTHER_FOOT, kept_apart
from engine.authoring.jobs import SettleJob
from engine.authoring.pins import holding_pins
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session_core import SessionCore
from engine.authoring.state import differences
from engine.authoring.turns import world_rotation
from engine.constraints.pin import PinConstraint
from engine.editing.constraint_list import ConstraintList
from engine.errors import UserError


class PoseEditing(SessionCore):
    """The pose, its targets and the body of an authoring session (see the module doc);
    the session holds the state they read and write and the edit machinery, declared here."""

    mode: PoseMode

    def world_rotation(self, joint: str) -> np.ndarray:
        """The current pose's world rotation ``(4,)`` of ``joint``."""
        return world_rotation(self.mode.pose, self.mode.character.skeleton.offsets, joint)

    def hips_handle(self) -> np.ndarray:
        """Where a drag of the hips starts (:meth:`PoseMode.hips_handle`)."""
        return self.mode.hips_handle()

    def drag_joint(self, joint: str, position: np.ndarray) -> None:
        """Create or move the target on ``joint`` to ``position (3,)`` metres and solve (a
        pin holding the joint on this frame is moved there too, :meth:`holding_pin`);
        the hips (``root``) move the whole body and the pelvis's height instead
        (:meth:`engine.authoring.pose_mode.PoseMode.drag_hips`). An ankle or a toe
        joint stops beside the other foot rather than crossing into it
        (:func:`engine.authoring.feet_apart.kept_apart`)."""
        p = np.asarray(position, float)
        if joint == "root":
            self.edit("move body", lambda: self.mode.drag_hips(p), ("body", "root", "position"))
            return
        if joint in OTHER_FOOT:
            held = self.mode.targets.get(joint)
            came = held.position if held is not None else self.mode.pose.positions[sk.JOINT_INDEX[joint]]
            p = kept_apart(joint, p, self.mode.pose.positions, came)
        pin = self.holding_pin(joint)

        def change() -> None:
            self.mode.set_target(joint, p)
            if pin is not None:
                ConstraintList(self.mode.constraints).edit(pin.name, position=p.copy())

        self.edit(f"move target {joint}", change, ("target", joint, "position"), solve=True)

    def holding_pin(self, joint: str) -> PinConstraint | None:
        """The pin that holds ``joint`` on the current frame, if any
        (:func:`engine.authoring.pins.holding_pins`). On that frame the pin wins over the
        joint's target, as in the bake, so a drag of the joint moves the pin's place with
        its target (:meth:`drag_joint`): the joint goes where it is dragged and stays
        pinned there over the pin's frames."""
        return holding_pins(self.mode.constraints, self.frame).get(joint)

    def drag_pelvis(self, position: np.ndarray) -> None:
        """Move only the pelvis to ``position (3,)`` metres, the feet planted and the upper
        body carried (:meth:`engine.authoring.pose_mode.PoseMode.drag_pelvis`); a drag's
        moves are one undo step."""
        p = np.asarray(position, float)
        self.edit("move pelvis", lambda: self.mode.drag_pelvis(p), ("body", "root", "pelvis"))

    def turn_joint(self, joint: str, rotation: np.ndarray) -> None:
        """Give ``joint`` the world rotation ``rotation (4,)`` as a target and solve."""
        q = np.asarray(rotation, float)
        self.edit(
            f"turn {joint}",
            lambda: self.mode.set_target(joint, rotation=q / np.linalg.norm(q)),
            ("target", joint, "rotation"),
            solve=True,
        )

    def hold_turn(self, joint: str, on: bool) -> None:
        """Give the target on ``joint`` the joint's current world rotation (``on``) or make
        it a position target again."""

        def change() -> None:
            if on:
                self.mode.set_target(joint, rotation=self.world_rotation(joint))
            else:
                self.mode.clear_rotation(joint)

        self.edit(f"{'hold' if on else 'free'} turn {joint}", change, solve=True)

    def edit_target(self, joint: str, enabled: bool | None = None, weight: float | None = None) -> None:
        """Switch the target on ``joint`` on or off or change its weight, and solve."""
        self.edit(
            f"edit target {joint}", lambda: self.mode.set_target(joint, enabled=enabled, weight=weight), solve=True
        )

    def clear_target(self, joint: str) -> None:
        self.edit(f"clear target {joint}", lambda: self.mode.remove_target(joint), solve=True)

    def clear_all(self) -> None:
        """Remove every target and put the character back in its starting pose, on the
        feet where it stands now (one undo step)."""

        def change() -> None:
            m = self.mode
            m.clear_targets()
            feet = np.mean([p[:2] for p in m.planted.values()], axis=0)
            pose = m.character.decode(m.base_latent, m.character.grounded(m.pose.root_pos[:2], m.heading))
            shift = feet - np.mean([pose.positions[sk.JOINT_INDEX[j], :2] for j in m.planted], axis=0)
            m.pose = m.character.decode(m.base_latent, m.character.grounded(pose.root_pos[:2] + shift, m.heading))
            m.plant_where_standing()

        self.edit("clear all targets", change)

    def move_body(self, delta: np.ndarray) -> None:
        """Root motion: translate the whole body horizontally by ``delta (3,)`` metres
        (its height is the floor's business), then solve the targets from there."""
        d = np.array([delta[0], delta[1], 0.0], float)

        def change() -> None:
            self.mode.pose = self.mode.pose.moved(d)
            self.mode.plant_where_standing()
            if self.mode.targets:
                self.mode.solve()

        self.edit("move body", change, ("body", "root", "position"))

    def turn_body(self, heading: float) -> None:
        """Root motion: face ``heading`` degrees about +Z (0 faces -Y), the whole body
        turned about its root, then the targets solved from there."""
        turn = float(heading) - self.mode.heading
        if abs(turn) < 1e-9:
            return

        def change() -> None:
            self.mode.heading = float(heading)
            self.mode.pose = self.mode.pose.turned(turn)
            self.mode.plant_where_standing()
            if self.mode.targets:
                self.mode.solve()

        self.edit("turn body", change, ("body", "root", "heading"))

    def settle(self) -> None:
        """An offline, grounded solve of the current targets (one undo step)."""
        self.edit("settle pose", self.mode.settle)

    def settle_job(self) -> SettleJob:
        """The settle of the pose as it stands, to run on any thread (:meth:`take_settle`)."""
        return SettleJob(self.mode.detached(), self.state())

    def take_settle(self, job: SettleJob, settled: PoseMode) -> None:
        """Apply ``job``'s result as the one undo step "settle pose".

        Raises
        ------
        UserError
            When the pose, targets, keys or constraints changed since the job was made
            (the settle would undo that change): nothing is applied.
        """
        d = differences(job.before, self.state())
        if d.joints or d.pose or d.keys or d.constraints or d.animation:
            raise UserError("the pose changed while it settled: nothing was applied (settle again)")
        self.edit("settle pose", lambda: self.mode.adopt(settled))
