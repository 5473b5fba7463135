"""Measure baked BVH files as ``bench --pose-tasks`` rows: each a task's one-key scene
baked by some build of ``bake`` (for instance the one before bakes were posed by pose
mode), against the task's goals, with the benchmark's measures and reference.

    PYTHONPATH=. python research/pose_task_bvh.py TASK=FILE.bvh ... [--reference-data PREPARED]

(the reference: ``--reference-data``, a prepared folder's val split, else the shipped
poses of the 9 validation files, every 4th frame, as ``bench --pose-tasks`` without a
prepared folder).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from engine import skeleton as sk
from engine.authoring import pose_reference as R
from engine.authoring import pose_tasks as T
from engine.authoring.character import Pose
from engine.kinematics.fk import fk
from engine.models import load_default_models
from engine.motion.bvh import load_bvh


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="+", metavar="TASK=FILE.bvh")
    p.add_argument("--reference-data", type=Path)
    args = p.parse_args(argv)
    vae = load_default_models().vae
    tasks = {t.name: t for t in T.TASKS}
    rows = []
    for item in args.files:
        name, path = item.split("=", 1)
        mode, goals, feet = T.task_start(tasks[name], vae, {})
        offsets = mode.character.skeleton.offsets
        if not rows:
            ref = (
                R.load_prepared(args.reference_data, offsets, 4) if args.reference_data else R.load_shipped(offsets, 4)
            )
        raw = load_bvh(path)  # baked on this character's skeleton: its rotations as written
        assert list(raw.names) == list(sk.JOINT_NAMES), path
        local, root = raw.local_quaternions()[0], raw.positions[0, 0]
        pose = Pose(mode.pose.latent, local, root, fk(local, root, offsets)[0])
        rows.append(T.measure_pose(tasks[name], "bvh", pose, goals, offsets, ref, feet, 0.0))
    p95 = ref.spread_summary()["p95_cm"]
    print(f"reference: {ref.description}; p95 {p95:.1f} cm")
    print(
        f"{'task':<15} {'err cm':>6} {'natural':>7} {'spread':>6} {'limits':>6} {'feet':>4} {'balance':>7} {'knee':>5}"
    )
    for r in rows:
        c = r.check
        feet = "".join(s[0].upper() if d else "-" for s, d in c.feet_down.items())
        bal = "-" if c.balance_margin_cm is None else f"{c.balance_margin_cm:.1f}"
        err = r.max_position_error_cm
        print(
            f"{r.task:<15} {'-' if err is None else f'{err:.1f}':>6} {r.naturalness_cm:>7.1f} "
            f"{'in' if r.within_spread else 'out':>6} {len(c.violations):>6} {feet:>4} {bal:>7} {r.knee_height_cm:>5.0f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
