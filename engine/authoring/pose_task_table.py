"""The pose-mode benchmark's task table (:mod:`engine.authoring.pose_tasks` runs it).

Plain data, no torch: the command line reads the task names while it is built.
"""

from __future__ import annotations

from dataclasses import dataclass

from engine.authoring.pose_drag import EVENTS  # noqa: F401  (drag events per drag: the bake's too)

#: Who poses: the pose mode, or plain IK (:mod:`engine.authoring.ik_poser`).
POSERS = ("pose-mode", "ik")
#: The rows of each task's one-key scene baked as ``bake`` bakes it
#: (:func:`engine.authoring.pose_tasks.run_bake`).
BAKE = "bake"
#: What a drag's end calls: nothing (the pose window) or ``settle()``.
RELEASES = ("none", "settle")


@dataclass(frozen=True)
class Drag:
    """One drag of a joint's target to a goal.

    Attributes
    ----------
    joint : str
        The dragged joint.
    anchor : str or None
        Joint of the starting pose the goal is placed from (None: ``joint`` itself).
    offset : tuple of 3 floats
        Goal minus the anchor, metres, in the character's frame (+X its left, -Y its
        forward, +Z up).
    height : float or None
        The goal's height above the floor, metres, instead of the anchor's plus offset.
    turn_deg : float or None
        A turn instead: the joint's starting world rotation turned by this about the
        vertical (positive: to the character's left); the target keeps its position.
    """

    joint: str
    anchor: str | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    height: float | None = None
    turn_deg: float | None = None


@dataclass(frozen=True)
class Task:
    """A posing task: ``drags`` in order; ``allowed``: the drags a user may need."""

    name: str
    description: str
    drags: tuple[Drag, ...]
    allowed: int


#: The benchmark's tasks. Goals sit where a user would drop the joint: a hand on
#: the kneecap 8 cm in front of the knee joint, wrists 30 cm above the head joint and 12 cm
#: to each side (within 90 % of the arm's reach of the standing shoulder), the wrist 10 cm
#: above the floor 25 cm in front of the toes, wrists 12 cm outside the hip joints and
#: 8 cm above them (on the iliac crest), a 30-cm step with the foot kept level.
TASKS: tuple[Task, ...] = (
    Task("hand_to_knee", "right hand to the left knee", (Drag("rwrist", "lknee", (0.0, -0.08, 0.0)),), 1),
    Task(
        "hands_overhead",
        "both hands overhead",
        (Drag("lwrist", "upperneck", (0.12, 0.0, 0.30)), Drag("rwrist", "upperneck", (-0.12, 0.0, 0.30))),
        2,
    ),
    Task("squat", "pelvis down 40 cm", (Drag("root", offset=(0.0, 0.0, -0.40)),), 1),
    Task("head_turn", "head turned 60 deg to the left", (Drag("upperneck", turn_deg=60.0),), 1),
    Task("step_forward", "left foot a 30 cm step forward", (Drag("lankle", offset=(0.0, -0.30, 0.0)),), 1),
    Task(
        "pick_up",
        "right hand to an object on the floor in front",
        (Drag("rwrist", "rtoe", (0.0, -0.25, 0.0), height=0.10),),
        1,
    ),
    Task(
        "hands_on_hips",
        "both hands on the hips",
        (Drag("lwrist", "lhip", (0.12, 0.0, 0.08)), Drag("rwrist", "rhip", (-0.12, 0.0, 0.08))),
        2,
    ),
)
TASK_NAMES = tuple(t.name for t in TASKS)
