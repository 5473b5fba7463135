"""The benchmark's squat (pelvis 40 cm down) done by the pelvis-only drag (Shift + drag on
the hips, :meth:`engine.authoring.pose_mode.PoseMode.drag_pelvis`) in 20 drag events,
measured as ``bench --pose-tasks`` measures a pose (the shipped reference): the goal's error, the nearest real
pose, the feet, the balance margin, the lower knee's height; plus how far the toes moved
and the shins' angle from the floor. ``--back`` also moves the pelvis back (metres).

    PYTHONPATH=. python research/pelvis_only_squat.py [--back 0.1] [--reference-data PREPARED]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.authoring import pose_reference as R
from engine.authoring.pose_metrics import check_pose
from engine.authoring.pose_mode import PoseMode
from engine.authoring.pose_task_table import EVENTS, TASKS
from engine.authoring.pose_tasks import goal_errors, resolve_goals
from engine.models import load_default_models

J = sk.JOINT_INDEX


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--back", type=float, default=0.0, help="metres the pelvis also goes back (+Y)")
    p.add_argument("--reference-data", type=Path)
    args = p.parse_args(argv)
    vae = load_default_models().vae
    task = next(t for t in TASKS if t.name == "squat")
    mode = PoseMode(vae)
    offsets = mode.character.skeleton.offsets
    goals = resolve_goals(task, mode.pose, offsets, mode.heading)
    start_pose, start = mode.pose, mode.hips_handle()
    goal = np.asarray(goals[0].position, float) + [0.0, args.back, 0.0]
    for k in range(1, EVENTS + 1):
        mode.drag_pelvis(start + (goal - start) * k / EVENTS)
    pose = mode.pose
    ref = R.load_prepared(args.reference_data, offsets) if args.reference_data else R.load_shipped(offsets)
    c = check_pose(pose.local_rot, pose.root_pos, offsets)
    err = max(e["error"] for e in goal_errors(pose, goals, offsets))
    toes = max(np.linalg.norm(pose.positions[J[t]] - start_pose.positions[J[t]]) for t in ("ltoe", "rtoe"))
    shins = [
        np.degrees(
            np.arcsin(
                (pose.positions[J[s + "knee"], 2] - pose.positions[J[s + "ankle"], 2])
                / np.linalg.norm(pose.positions[J[s + "knee"]] - pose.positions[J[s + "ankle"]])
            )
        )
        for s in "lr"
    ]
    feet = "".join(s[0].upper() if d else "-" for s, d in c.feet_down.items())
    balance = "-" if c.balance_margin_cm is None else f"{c.balance_margin_cm:+.1f}"
    knee = 100.0 * min(pose.positions[J[k], 2] for k in ("lknee", "rknee"))
    print(f"reference: {ref.description}; p95 {ref.spread_summary()['p95_cm']:.1f} cm")
    print(
        f"pelvis-only squat, back {args.back:.2f} m: error {err:.1f} cm, natural {100 * ref.nearest(pose.positions):.1f} cm, "
        f"feet {feet}, balance {balance} cm, lower knee {knee:.0f} cm, toes moved {1000 * toes:.2f} mm, "
        f"shins {shins[0]:.0f} / {shins[1]:.0f} deg from the floor, trunk tilt {c.trunk_tilt_deg:.0f} deg, "
        f"limits {len(c.violations)}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
