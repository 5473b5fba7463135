"""Pose mode's trunk rule (``PoseOptions.keep_trunk``): a drag of the arms does not lean
the trunk further back than it stood.

To lift both arms overhead the latent solve leans the trunk back (the head joint 16 cm
behind where it stood relative to the pelvis, from the mean pose's 11-degree forward
lean to 3 degrees). With the rule, after each latent solve while no trunk or leg joint
has a target, each trunk bone (:data:`BONES`, pelvis first) that leans further back than
it did in the pose the drag began from is turned forward, at its joint, until it leans
back no further (:func:`unleaned`, which keeps its side lean); a bone that leans no
further back keeps its direction, so a reach to a knee or the floor still bends the
trunk. The joints above a turned bone follow it, and the wrists, ankles and turned
joints are then put on their targets again from where the trunk left them
(:func:`engine.solver.limb_ik.finish`).

The pelvis is turned only while it stands (not crouched) on planted feet: turning it
swings the legs, which the planted ankles' two-bone step then bends back onto the feet;
a crouch tips the pelvis back as the knees fold, as a squat does.

Off by default: real poses with both hands overhead lean back a little (docs/authoring.md,
*The trunk in the hands overhead*).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk_joints
from engine.solver.limb_ik import finish

J = sk.JOINT_INDEX
#: Joints whose target means the user poses the trunk: the rule leaves it alone.
TRUNK = tuple(J[n] for n in ("root", "lowerback", "upperback", "chest", "lowerneck", "upperneck"))
#: Joints whose target moves the pelvis with the legs (a step): the rule leaves the trunk alone.
LEGS = tuple(J[s + n] for s in "lr" for n in ("hip", "knee", "ankle", "toe"))
#: The trunk's bones, pelvis first: (the joint that turns the bone, the joint at its far end).
BONES = (
    (J["root"], J["lowerback"]),
    (J["lowerback"], J["upperback"]),
    (J["upperback"], J["chest"]),
    (J["chest"], J["lowerneck"]),
    (J["lowerneck"], J["upperneck"]),
)


def unleaned(have: np.ndarray, start: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """The unit bone direction ``have (3,)`` leaning back no further than ``start (3,)``:
    when ``have`` has less of the horizontal unit ``forward (3,)`` than ``start``, the
    direction with ``start``'s forward component whose other part (side and up) points
    as ``have``'s does; else ``have``."""
    ahead, was = float(have @ forward), float(start @ forward)
    if ahead >= was:
        return np.asarray(have, float)
    rest = have - ahead * forward
    n = float(np.linalg.norm(rest))
    if n < 1e-9:  # pointing straight back: no side or up part to keep
        return np.asarray(start, float)
    return was * forward + np.sqrt(max(0.0, 1.0 - was * was)) * rest / n


def keep_trunk(
    pose: Pose,
    start: Pose,
    forward: np.ndarray,
    offsets: np.ndarray,
    reach: dict[int, np.ndarray],
    rotations: dict[int, np.ndarray],
    pelvis: bool = True,
) -> Pose:
    """``pose`` with no trunk bone leaning further back than in ``start`` (module doc).

    Parameters
    ----------
    pose : Pose
        The solved pose (after the exact limb and rotation steps).
    start : Pose
        The pose the drag began from.
    forward : ndarray (3,)
        The character's horizontal forward direction, unit.
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    reach, rotations : dict
        The solve's exact steps, redone from the kept trunk: end joint (a wrist or ankle)
        -> world position ``(3,)`` metres; joint -> world rotation ``(4,)``.
    pelvis : bool
        Whether the pelvis bone is kept too (the legs then bend back onto ``reach``'s ankles).

    Returns
    -------
    Pose
        Same latent, root position and decoded positions; ``pose`` itself when no bone
        leaned back further.
    """
    local = np.array(pose.local_rot, float)
    root = np.asarray(pose.root_pos, float)
    forward = np.asarray(forward, float)
    turned = False
    for j, end in BONES[0 if pelvis else 1 :]:
        # the bone's ends and its joint's parent (the root's: none, the identity) in one pass
        pos, rot = fk_joints(local, root, offsets, [j, end, max(sk.PARENTS[j], 0)])
        have = (pos[1] - pos[0]) / np.linalg.norm(pos[1] - pos[0])
        was = start.positions[end] - start.positions[j]
        want = unleaned(have, was / np.linalg.norm(was), forward)
        if float(have @ want) > 1.0 - 1e-12:
            continue
        world = QN.mul(QN.from_to(have, want), rot[0])
        parent = rot[2] if j else np.array([1.0, 0.0, 0.0, 0.0])
        local[j] = QN.canonicalize(QN.normalize(QN.mul(QN.conjugate(parent), world)))
        turned = True
    if not turned:
        return pose
    local, positions = finish(local, root, offsets, reach, rotations)
    return Pose(pose.latent, local, root.copy(), positions, pose.iterations, pose.decoded)
