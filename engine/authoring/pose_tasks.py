"""The pose-mode benchmark: fixed posing tasks on the canonical character, done as a user
drags, measured for reach and plausibility (``dragposer-studio bench --pose-tasks``).

A task (:data:`engine.authoring.pose_task_table.TASKS`) is a list of drags. A drag
moves one joint's target from where the joint (or its existing target) is to a goal in
:data:`EVENTS` equal steps, calling ``set_target`` and ``solve()`` on every step as the
pose window does on every mouse move (``app/pose_window.py``: ``drag_joint`` sets the
target and solves; a release calls nothing, and *Edit > Settle pose* calls
``settle()``; ``release="settle"`` settles after every drag, as a user who uses that
menu does). Targets stay after their drag, as in the
window. Goals are placed relative to the starting pose's joints (the VAE's mean pose,
standing at the origin, facing -Y), resolved once, so every poser gets the same goals.

Per task and poser (:func:`run_task`): each goal's error (centimetres, or degrees for a
turn), the final pose's naturalness (:mod:`engine.authoring.pose_reference`), the
measures of :func:`engine.authoring.pose_metrics.check_pose`, how far each ankle
that no drag moved has slid over the floor from where it stood, and the lower knee's
height above the floor (centimetres).

Posers: ``pose-mode`` (:class:`engine.authoring.pose_mode.PoseMode`, with the keyword
options given to :func:`run_task`) and ``ik`` (:class:`engine.authoring.ik_poser.IKPoser`
from the same starting pose). Beside them, :func:`run_bake` bakes each task's one-key
scene (:data:`TASK_SCENES`, written by :func:`task_scene`: the task's goals as the key's
targets, as a user would write them) with :func:`engine.authoring.bake.bake` and
measures its one frame the same way (the ``bake`` rows).
"""

from __future__ import annotations

import dataclasses
import inspect
import time
import typing
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose, yaw_quaternion
from engine.authoring.document import AuthoringScene, load_authoring
from engine.authoring.ik_poser import IKPoser
from engine.authoring.keys import Animation, Key
from engine.authoring.pose_drag import drag as drag_target
from engine.authoring.pose_metrics import PoseCheck, check_pose
from engine.authoring.pose_mode import PoseMode, PoseOptions
from engine.authoring.pose_reference import ReferenceSet
from engine.authoring.pose_task_table import BAKE, EVENTS, POSERS, RELEASES, TASK_NAMES, TASKS, Task
from engine.authoring.targets import JointTarget
from engine.config import parse_typed
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk

J = sk.JOINT_INDEX
# Goals are placed from the decoded neutral pose, whose last float32 bits differ between
# CPUs (their kernels sum in other orders); rounded, a task's goals and the scenes written
# from them are the same numbers on every machine.
GOAL_DECIMALS = 4
#: A task is reached when every position goal is within this (centimetres) ...
REACH_CM = 2.0
#: ... and every turn within this (degrees).
TURN_DEG = 5.0
#: Ankles whose horizontal slide from the starting pose is reported (when not dragged).
FOOT_JOINTS = ("lankle", "rankle")
#: The knees whose lower height is reported (a squat that kneels puts one near the floor).
KNEES = ("lknee", "rknee")
#: The tasks' one-key scenes, ``<task>.json`` (:func:`task_scene`; ``bake`` rows).
TASK_SCENES = Path(__file__).resolve().parents[2] / "assets" / "scenes" / "pose_tasks"


@dataclass
class Goal:
    """A drag's resolved goal: a world ``position (3,)`` metres, or a world ``rotation (4,)``."""

    joint: str
    position: np.ndarray | None = None
    rotation: np.ndarray | None = None


@dataclass
class TaskResult:
    """What one poser did on one task (see the module doc); errors in cm / degrees."""

    task: str
    poser: str
    drags: int
    allowed: int
    goal_errors: list[dict]
    reached: bool
    naturalness_cm: float
    within_spread: bool
    check: PoseCheck
    seconds: float
    feet_moved_cm: dict[str, float] = field(default_factory=dict)
    positions: list[list[float]] = field(default_factory=list)
    knee_height_cm: float | None = None
    nearest_take: str = ""

    @property
    def max_position_error_cm(self) -> float | None:
        e = [g["error"] for g in self.goal_errors if g["kind"] == "position"]
        return max(e) if e else None

    @property
    def max_turn_error_deg(self) -> float | None:
        e = [g["error"] for g in self.goal_errors if g["kind"] == "turn"]
        return max(e) if e else None

    def to_dict(self) -> dict:
        out = asdict(self)
        out["check"] = self.check.to_dict()
        out["balanced"] = self.check.balanced
        return out


def resolve_goals(task: Task, pose, offsets: np.ndarray, heading_deg: float = 0.0) -> list[Goal]:
    """World goals of ``task``'s drags, placed from ``pose`` (a starting :class:`Pose`),
    positions to 0.1 mm and rotations to 1e-6 (:data:`GOAL_DECIMALS`)."""
    yaw = yaw_quaternion(heading_deg)
    world_rot = fk(pose.local_rot, pose.root_pos, offsets)[1]
    goals = []
    for d in task.drags:
        if d.turn_deg is not None:
            q = np.round(QN.mul(yaw_quaternion(d.turn_deg), world_rot[J[d.joint]]), GOAL_DECIMALS + 2)
            goals.append(Goal(d.joint, rotation=q / np.linalg.norm(q)))
            continue
        p = pose.positions[J[d.anchor or d.joint]] + QN.rotate(yaw, np.asarray(d.offset, float))
        if d.height is not None:
            p[2] = d.height
        goals.append(Goal(d.joint, position=np.round(p, GOAL_DECIMALS)))
    return goals


def drag(poser, goal: Goal, offsets: np.ndarray, events: int = EVENTS, solve: dict | None = None) -> None:
    """Move ``goal.joint``'s target to the goal in ``events`` steps, solving on each
    (``offsets (22, 3)``: the poser's skeleton; :func:`engine.authoring.pose_drag.drag`)."""
    drag_target(poser, goal.joint, offsets, goal.position, goal.rotation, events, solve=solve)


def goal_errors(pose, goals: list[Goal], offsets: np.ndarray) -> list[dict]:
    """Each goal's error: ``{"joint", "kind": "position" | "turn", "error"}`` (cm or degrees).

    A goal on the hips (``root``) is a height: the level place of a crouching body is
    where its planted feet stand, and pose mode moves the pelvis level to balance over
    them (``PoseOptions.crouch_balance``)."""
    world_rot = fk(pose.local_rot, pose.root_pos, offsets)[1]
    out = []
    for g in goals:
        if g.rotation is not None:
            err = float(np.degrees(QN.angle(world_rot[J[g.joint]], g.rotation)))
            out.append({"joint": g.joint, "kind": "turn", "error": err})
        else:
            gap = pose.positions[J[g.joint]] - g.position
            err = 100.0 * float(abs(gap[2]) if g.joint == "root" else np.linalg.norm(gap))
            out.append({"joint": g.joint, "kind": "position", "error": err})
    return out


def split_options(items: list[str]) -> tuple[dict, dict, dict]:
    """``--set NAME=VALUE`` items as keyword arguments of ``PoseMode(...)``, of its
    ``solve()`` (``solve.NAME``) and of its ``settle()`` (``settle.NAME``), each value
    typed by the parameter's annotation; a field of :class:`PoseOptions` by its own name.
    Every keyword those take is accepted, so a new
    pose-mode option needs no change here; a name none of them takes is a
    :class:`UserError` that lists the names they take."""
    calls = {"": PoseMode.__init__, "solve.": PoseMode.solve, "settle.": PoseMode.settle}
    out: dict[str, dict] = {k: {} for k in calls}
    option_hints = typing.get_type_hints(PoseOptions)  # its fields are set by name (``plant_feet=false``)
    chosen: dict = {}
    for item in items:
        if "=" not in item:
            raise UserError(f"--set {item!r}: expected NAME=VALUE")
        name, raw = (x.strip() for x in item.split("=", 1))
        prefix = next((p for p in ("solve.", "settle.") if name.startswith(p)), "")
        key, hints = name[len(prefix) :], _keywords(calls[prefix])
        if not prefix and key in option_hints:
            chosen[key] = parse_typed(name, raw, option_hints[key])
            continue
        if key not in hints:
            every = sorted([f"{p}{k}" for p, f in calls.items() for k in _keywords(f)] + list(option_hints))
            raise UserError(f"--set {name}: pose mode takes no option {key!r}; options: {', '.join(every)}")
        out[prefix][key] = parse_typed(name, raw, hints[key])
    if chosen:
        out[""]["options"] = dataclasses.replace(out[""].get("options") or PoseOptions(), **chosen)
    return out[""], out["solve."], out["settle."]


def _keywords(func) -> dict:
    """Keyword parameter -> annotation (``Any`` where there is none) of ``func``."""
    hints = typing.get_type_hints(func)
    skip = {"self", "vae", "latent"}
    return {
        p.name: hints.get(p.name, Any)
        for p in inspect.signature(func).parameters.values()
        if p.name not in skip and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
    }


def run_task(
    task: Task,
    poser_name: str,
    vae,
    reference: ReferenceSet,
    options: list[str] | None = None,
    release: str = "none",
    events: int = EVENTS,
) -> TaskResult:
    """Do ``task`` with one poser from the starting pose and measure the result.

    Parameters
    ----------
    poser_name : str
        One of :data:`POSERS`.
    vae : engine.models.PoseVAE
    reference : ReferenceSet
        For naturalness; laid out on the character's skeleton.
    options : list of str
        Pose-mode options ``NAME=VALUE``, see :func:`split_options` (the IK poser starts
        from the pose these make).
    release : str
        ``none`` (the pose window) or ``settle`` after every drag.
    events : int
        Drag events per drag.
    """
    if poser_name not in POSERS:
        raise UserError(f"unknown poser {poser_name!r}; posers: {', '.join(POSERS)}")
    if release not in RELEASES:
        raise UserError(f"unknown release {release!r}; choices: {', '.join(RELEASES)}")
    if events < 1:
        raise UserError(f"drag events must be at least 1, got {events}")
    init, solve, settle = split_options(options or [])
    mode, goals, feet = task_start(task, vae, init)
    offsets = mode.character.skeleton.offsets
    poser = mode if poser_name == "pose-mode" else IKPoser(mode.pose, offsets)
    t0 = time.perf_counter()
    for g in goals:
        drag(poser, g, offsets, events, solve if poser is mode else None)
        if release == "settle":
            poser.settle(**(settle if poser is mode else {}))
    seconds = time.perf_counter() - t0
    return measure_pose(task, poser_name, poser.pose, goals, offsets, reference, feet, seconds)


def measure_pose(
    task: Task,
    poser_name: str,
    pose: Pose,
    goals: list[Goal],
    offsets: np.ndarray,
    reference: ReferenceSet,
    feet: dict[str, np.ndarray],
    seconds: float,
) -> TaskResult:
    """The measures of ``pose``, the end of ``task`` (``feet``: each undragged ankle's
    starting place, ``(2,)`` metres)."""
    errors = goal_errors(pose, goals, offsets)
    reached = all(e["error"] <= (REACH_CM if e["kind"] == "position" else TURN_DEG) for e in errors)
    nearest, take = reference.closest(pose.positions)
    natural = 100.0 * nearest
    moved = {j: 100.0 * float(np.linalg.norm(pose.positions[J[j], :2] - xy)) for j, xy in feet.items()}
    return TaskResult(
        task.name,
        poser_name,
        len(task.drags),
        task.allowed,
        errors,
        reached,
        natural,
        natural <= reference.spread_summary()["p95_cm"],
        check_pose(pose.local_rot, pose.root_pos, offsets),
        seconds,
        moved,
        [[round(float(x), 4) for x in p] for p in pose.positions],
        100.0 * float(min(pose.positions[J[k], 2] for k in KNEES)),
        take,
    )


def task_start(task: Task, vae, init: dict) -> tuple[PoseMode, list[Goal], dict[str, np.ndarray]]:
    """The starting pose mode, the task's goals and the undragged ankles' places."""
    mode = PoseMode(vae, **init)
    goals = resolve_goals(task, mode.pose, mode.character.skeleton.offsets, mode.heading)
    feet = {j: mode.pose.positions[J[j], :2].copy() for j in FOOT_JOINTS if j not in {d.joint for d in task.drags}}
    return mode, goals, feet


def task_scene(task: Task, vae) -> AuthoringScene:
    """``task`` as a one-key scene (what :data:`TASK_SCENES` holds): one frame, its goals as
    the key's targets in drag order (a turn: the joint's rotation goal, its position where
    the joint stands), the default character and pose options."""
    mode, goals, _ = task_start(task, vae, {})
    targets = {}
    for g in goals:
        here = mode.pose.positions[J[g.joint]]
        targets[g.joint] = JointTarget(g.joint, here if g.position is None else g.position, g.rotation)
    return AuthoringScene(animation=Animation(frames=1), keys=[Key(0, targets)])


def task_scene_path(task: Task) -> Path:
    """Where ``task``'s one-key scene is (:data:`TASK_SCENES`)."""
    return TASK_SCENES / f"{task.name}.json"


def run_bake(task: Task, vae, reference: ReferenceSet, options: PoseOptions | None = None) -> TaskResult:
    """Bake ``task``'s one-key scene (:func:`task_scene_path`, its own pose options, or
    ``options``) as ``bake`` does and measure the frame against the task's goals (poser
    ``bake``; the seconds are the bake's)."""
    from engine.authoring.bake import bake

    scene = load_authoring(task_scene_path(task))
    if options is not None:
        scene.pose_options = options
    mode, goals, feet = task_start(task, vae, {"height": scene.height})
    t0 = time.perf_counter()
    baked = bake(scene, vae)
    seconds = time.perf_counter() - t0
    m = baked.motion
    pose = Pose(baked.latents[0], m.local_rot[0], m.root_pos[0], m.positions()[0])
    return measure_pose(task, BAKE, pose, goals, mode.character.skeleton.offsets, reference, feet, seconds)


def select_tasks(names: list[str] | None) -> list[Task]:
    """The tasks named (all, in table order, for None); an unknown name is a :class:`UserError`."""
    if not names:
        return list(TASKS)
    unknown = [n for n in names if n not in TASK_NAMES]
    if unknown:
        raise UserError(f"unknown task(s) {', '.join(unknown)}; tasks: {', '.join(TASK_NAMES)}")
    return [t for t in TASKS if t.name in names]
