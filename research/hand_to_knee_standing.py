"""The benchmark's hand-to-knee task (right wrist to 8 cm in front of the left knee) done
in one drag of 20 events through :class:`engine.authoring.pose_mode.PoseMode`, as
``bench --pose-tasks`` drags it: does the body reach the knee standing (trunk bent,
knees slightly bent, feet planted) or crouch?

Reports the wrist's error, how far the pelvis dropped from its standing height (cm), the
trunk tilt, both knees' flexion, how far each foot joint moved, the balance margin, the
lower knee's height and the nearest real pose (:mod:`engine.authoring.pose_metrics`,
:mod:`engine.authoring.pose_reference`: ``./prepared`` when it has a manifest, else the
shipped 9 validation files); ``--settle`` also settles after the drag, ``--set
NAME=VALUE`` sets a :class:`~engine.authoring.pose_options.PoseOptions` field, and
``--task`` runs another task of the table the same way (``pick_up``, ``squat``).

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/hand_to_knee_standing.py [--settle] [--set crouch_share=0.5] [--task pick_up]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.authoring import pose_reference as R
from engine.authoring.pose_metrics import check_pose
from engine.authoring.pose_task_table import EVENTS, TASKS
from engine.authoring.pose_tasks import drag, goal_errors, split_options, task_start
from engine.models import load_default_models

J = sk.JOINT_INDEX
FOOT = ("lankle", "ltoe", "rankle", "rtoe")


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--task", default="hand_to_knee")
    p.add_argument("--settle", action="store_true", help="settle after the drag")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--events", type=int, default=EVENTS)
    args = p.parse_args(argv)
    vae = load_default_models().vae
    task = next(t for t in TASKS if t.name == args.task)
    init, solve, _ = split_options(args.set)
    mode, goals, _ = task_start(task, vae, init)
    offsets = mode.character.skeleton.offsets
    start = mode.pose.positions.copy()
    for g in goals:
        drag(mode, g, offsets, args.events, solve)
    if args.settle:
        mode.settle()
    pose = mode.pose
    prepared = Path("prepared")
    ref = R.load_prepared(prepared, offsets) if (prepared / "manifest.json").exists() else R.load_shipped(offsets)
    c = check_pose(pose.local_rot, pose.root_pos, offsets)
    err = max(e["error"] for e in goal_errors(pose, goals, offsets))
    drop = 100.0 * (start[0, 2] - pose.positions[0, 2])
    back = 100.0 * (pose.positions[0, 1] - start[0, 1])
    feet = ", ".join(f"{j} {100 * np.linalg.norm(pose.positions[J[j]] - start[J[j]]):.1f}" for j in FOOT)
    down = "".join(s[0].upper() if d else "-" for s, d in c.feet_down.items())
    balance = "-" if c.balance_margin_cm is None else f"{c.balance_margin_cm:+.1f}"
    knee = 100.0 * min(pose.positions[J[k], 2] for k in ("lknee", "rknee"))
    spread = ref.spread_summary()
    print(f"reference: {ref.description}; spread median {spread['median_cm']:.1f}, p95 {spread['p95_cm']:.1f} cm")
    print(
        f"{task.name}{' + settle' if args.settle else ''} {' '.join(args.set)}: error {err:.1f} cm, "
        f"pelvis drop {drop:.1f} cm (back {back:+.1f}), trunk tilt {c.trunk_tilt_deg:.0f} deg, "
        f"knee flexion L {c.flexion_deg['lknee']:.0f} / R {c.flexion_deg['rknee']:.0f} deg, lower knee {knee:.0f} cm, "
        f"feet {down}, balance {balance} cm, natural {100 * ref.nearest(pose.positions):.1f} cm, "
        f"limits {len(c.violations)}"
    )
    print(f"foot joints moved (cm): {feet}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
