"""Bake an authored scene into a motion: keys solved, in-betweens from the latent space.

1. **Keys.** Each key is posed by pose mode, the machinery the pose window poses with
   (:meth:`engine.authoring.pose_mode.PoseMode.pose_key`, with the scene's
   :class:`~engine.authoring.pose_options.PoseOptions` and its constraints active on the
   key's frame): a key given only targets starts in the VAE's mean pose where the key
   stands and faces and has its targets dragged there as a user drags them (planted
   feet, balance, crouch); a key with a latent takes that pose with the feet planted
   and its targets taken exactly. A one-key bake is the pose pose mode gives.
2. **In-betweens.** For every other frame the neighbouring keys' latents, targets and
   root placements are interpolated (:mod:`engine.authoring.keys`), the interpolated
   latent decoded and re-solved from there: against the interpolated targets, a prior
   towards the interpolated latent, the smoothing term on the last two solved frames
   (the temporal terms of the ``dragposer`` method) and the scene's constraints with
   their frame ranges, the root held on the interpolated trajectory and the feet
   grounded. Joints targeted by both keys follow their targets exactly (wrists and
   ankles by their limbs), so a pinned effector stays put and nothing jumps. A pin on a
   joint that no target holds there acts through a target too: the frame is solved
   without that pin, and again with the joint's target going from where that solve put
   it to the pin's place by the pin's activity. The
   latent solve aims each target plus the offset the keys' own latents leave from their
   targets (interpolated too): the exact limb step closes that gap on the keys, and
   without the offset the in-betweens next to a key would pull the latent elsewhere and
   the motion would snap on the key. Next to a key whose pelvis was moved alone (a
   ``pelvis_only`` target on ``root``), the in-between's pelvis then goes on the
   interpolated root and its legs reach the feet interpolated between the keys' (each
   key's ``feet``, else where its pose has them), as the key's own legs do
   (:func:`engine.authoring.pelvis_drag.pelvis_pose`).

Deterministic: the same scene gives the same motion, so the studio's export and the
``bake`` command write the same bytes.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Character, Pose
from engine.authoring.document import AuthoringScene
from engine.authoring.keys import PLANTED, Key, eased, interpolate, segment, slerp_quaternion
from engine.authoring.pelvis_drag import pelvis_pose
from engine.authoring.pins import holding_pins, pinned_targets
from engine.authoring.pose_mode import PoseMode
from engine.authoring.targets import JointTarget, pelvis_only_target, solve_inputs
from engine.constraints.base import Constraint
from engine.constraints.pin import PinConstraint
from engine.constraints.smooth import SmoothConstraint
from engine.errors import UserError
from engine.motion.clip import Motion
from engine.progress import CancelCheck, check

#: Latent steps per in-between frame (each starts next to its answer).
IN_BETWEEN_ITERATIONS = 12
#: Weight of the smoothing term in the in-betweens (5, the sparse profiles' value, left a
#: 0.03 latent snap onto the last key of the issue example; 1 left 0.008).
SMOOTH_WEIGHT = 1.0
#: Weight of the pull towards the interpolated latent in the in-betweens.
IN_BETWEEN_PRIOR = 0.2


@dataclass
class Baked:
    """A baked animation.

    Attributes
    ----------
    motion : Motion
        On the character's skeleton, at the output rate.
    latents : ndarray (F, L)
        Each frame's solved latent.
    key_frames : list of int
        Output frames of the keys.
    """

    motion: Motion
    latents: np.ndarray
    key_frames: list[int]


def pinned_key(key: Key, constraints: list[Constraint]) -> Key:
    """``key`` with its targets as the pins acting on its frame leave them
    (:func:`engine.authoring.pins.pinned_targets`)."""
    targets, _ = pinned_targets(list(key.targets.values()), constraints, key.frame)
    return dataclasses.replace(key, targets={t.joint: t for t in targets})


def solve_key(scene: AuthoringScene, vae, key: Key, cancelled: CancelCheck | None = None) -> Pose:
    """The pose of one key (see the module doc) as the pose window poses it on the key's
    frame: the scene's constraints with their frame ranges and the key's own targets, a
    pin on a targeted joint winning over the target by its activity on that frame in every
    solve (:attr:`engine.authoring.pose_solve.PoseSolving.aimed`)."""
    if key.latent is not None and key.latent.shape != (int(vae.config.latent),):
        raise UserError(
            f"key at frame {key.frame}: latent has {key.latent.size} numbers, "
            f"the pose model takes {int(vae.config.latent)}"
        )
    mode = PoseMode(vae, scene.height, root_xy=key.root, heading=key.heading, options=scene.pose_options)
    mode.constraints, mode.frame = copy.deepcopy(scene.constraints), key.frame
    return mode.pose_key(key, cancelled=cancelled)


def output_frames(scene: AuthoringScene, fps: float | None) -> tuple[int, float, float]:
    """Frame count, rate and scene-frames-per-output-frame of the baked motion."""
    a = scene.animation
    rate = float(fps) if fps else a.fps
    if not 1.0 <= rate <= 240.0:
        raise UserError(f"--fps must be within 1-240, got {fps}")
    ratio = a.fps / rate
    return int(round((a.frames - 1) / ratio)) + 1, rate, ratio


def bake(
    scene: AuthoringScene,
    vae,
    fps: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    cancelled: CancelCheck | None = None,
) -> Baked:
    """Bake ``scene`` with the pose VAE ``vae`` at ``fps`` (default: the scene's rate).

    ``progress(done, total)`` is called after every key and frame; ``cancelled()`` is
    asked before each, and a True answer raises
    :class:`engine.progress.Cancelled` (``scene`` is only read).
    """
    character = Character(vae, scene.height)
    n, rate, ratio = output_frames(scene, fps)
    # the in-betweens interpolate the keys' targets as the pins on the keys' frames leave them
    keys = [pinned_key(k, scene.constraints) for k in scene.keys]
    times = [k.frame / ratio for k in keys]
    key_at = {int(round(t)): i for i, t in enumerate(times) if abs(t - round(t)) < 1e-9}
    poses: list[Pose] = []
    for key in scene.keys:
        check(cancelled)
        poses.append(solve_key(scene, vae, key, cancelled))
        if progress:
            progress(0, n + len(keys))
    scheme = scene.animation.interpolation
    smooth = SmoothConstraint(name="authoring smooth", weight=SMOOTH_WEIGHT)
    frames: list[Pose] = []
    for f in range(n):
        check(cancelled)
        if f in key_at:
            pose = poses[key_at[f]]
        elif not keys:
            pose = character.decode(character.mean_latent(), character.grounded())
        else:
            pose = _in_between(character, scene, keys, poses, times, f, f * ratio, scheme, smooth, frames)
        frames.append(pose)
        if progress:
            progress(f + 1 + len(keys), n + len(keys))
    local = np.stack([p.local_rot for p in frames])
    root = np.stack([p.root_pos for p in frames])
    motion = Motion(local, root, character.skeleton, rate, "authored")
    return Baked(motion, np.stack([p.latent for p in frames]), sorted(key_at))


def _in_between(
    character: Character,
    scene: AuthoringScene,
    keys: list[Key],
    poses: list[Pose],
    times: list[float],
    f: int,
    scene_frame: float,
    scheme: str,
    smooth: SmoothConstraint,
    done: list[Pose],
) -> Pose:
    z = interpolate(times, [p.latent for p in poses], f, scheme).astype(np.float32)
    root = interpolate(times, [p.root_pos for p in poses], f, scheme)
    heading = interpolated_heading(keys, times, f, scheme)
    frame = int(round(scene_frame))
    decoded = [p.positions if p.decoded is None else p.decoded for p in poses]  # as Pose fills it in
    previous = done[-1].positions if done else None
    smooth.set_history(previous, done[-2].positions if len(done) > 1 else None)
    ctx = character.placed(root, heading, f, previous=previous, prior=z)

    def solve(targets: list[JointTarget], rules: list[Constraint]) -> tuple[Pose, dict[int, np.ndarray]]:
        """The in-between with ``targets`` and ``rules``, and its exact limb targets."""
        aims = []
        for t in targets:
            track = [
                (tk, d[t.index] - k.targets[t.joint].position)
                for tk, k, d in zip(times, keys, decoded)
                if t.joint in k.targets
            ]
            if not track:  # a pin's target on a joint no key targets: no gap to carry
                aims.append(t)
                continue
            gap = interpolate([tk for tk, _ in track], [g for _, g in track], f, scheme)
            aims.append(dataclasses.replace(t, position=t.position + gap))
        terms, _, _ = solve_inputs(aims)
        _, reach, rotations = solve_inputs(targets)
        pose = character.solve(
            z,
            [*terms, smooth, *rules],
            ctx,
            reach,
            rotations,
            iterations=IN_BETWEEN_ITERATIONS,
            prior_weight=IN_BETWEEN_PRIOR,
            rule="sgd",
        )
        return pose, reach

    interpolated = interpolated_targets(keys, times, f, scheme)
    targeted = {t.joint for t in interpolated}
    held = {j for j in holding_pins(scene.constraints, frame) if j != "root" and j not in targeted}
    if held:
        # a pin on a joint no target holds takes it from where the in-between has it without
        # the pin (solved without it) to the pin's place, through a target
        # (:func:`engine.authoring.pins.pinned_targets`)
        unpinned = [c for c in scene.constraints if not (isinstance(c, PinConstraint) and c.joint in held)]
        first, _ = solve(*pinned_targets(interpolated, unpinned, frame))
        free = {j: first.positions[sk.JOINT_INDEX[j]].copy() for j in held}
        targets, rules = pinned_targets(interpolated, scene.constraints, frame, free=free)
    else:
        targets, rules = pinned_targets(interpolated, scene.constraints, frame)
    pose, reach = solve(targets, rules)
    i, s = segment(times, f)
    if not any(pelvis_only_target(k.targets) for k in keys[i : i + 1 + (s > 0.0)]):  # after the last key: the last
        return pose
    feet = {
        j: interpolate(times, [k.feet.get(j, p.positions[sk.JOINT_INDEX[j]]) for k, p in zip(keys, poses)], f, scheme)
        for j in PLANTED
    }
    return pelvis_pose(pose, root, feet, character.skeleton.offsets, reach)


def interpolated_heading(keys: list[Key], times: list[float], t: float, scheme: str) -> float:
    """The facing (degrees) at time ``t``: the keys' headings interpolated, unwrapped so
    keys facing 170 and -170 degrees turn 20 degrees between them, not 340."""
    headings = np.degrees(np.unwrap(np.radians([k.heading for k in keys])))
    return float(interpolate(times, [np.array([h]) for h in headings], t, scheme)[0])


def one_key_targets(keys: list[Key], t: float) -> dict[str, int]:
    """The joints that one of the two keys around time ``t`` targets and the other does
    not, and that key's frame: :func:`interpolated_targets` leaves them out, so they do
    not act on the in-between (the key's latent carries them into it). Empty on a key,
    before the first and after the last, where one key gives every target."""
    times = [float(k.frame) for k in keys]
    if not keys:
        return {}
    i, s = segment(times, t)
    if s == 0.0:
        return {}
    a, b = keys[i], keys[i + 1]
    out = {j: a.frame for j in a.targets if j not in b.targets}
    out.update({j: b.frame for j in b.targets if j not in a.targets})
    return out


def interpolated_targets(keys: list[Key], times: list[float], t: float, scheme: str) -> list[JointTarget]:
    """The targets at time ``t``: every joint targeted by both neighbouring keys (by the
    one key on a key, before the first or after the last), its position interpolated
    along the keys that target it, its weight blended, its rotation slerped when both
    keys give one."""
    i, s = eased(times, t, scheme)
    near = [keys[i]] if s == 0.0 else [keys[i], keys[i + 1]]
    joints = [j for j in near[0].targets if all(j in k.targets for k in near)]
    out = []
    for j in joints:
        track = [(tk, k.targets[j]) for tk, k in zip(times, keys) if j in k.targets]
        position = interpolate([tk for tk, _ in track], [x.position for _, x in track], t, scheme)
        a, b = near[0].targets[j], near[-1].targets[j]
        rotation = None
        if a.rotation is not None and b.rotation is not None:
            rotation = slerp_quaternion(a.rotation, b.rotation, s)
        weight = (1 - s) * a.weight + s * b.weight
        out.append(JointTarget(j, position, rotation, weight, a.enabled and b.enabled))
    return out
