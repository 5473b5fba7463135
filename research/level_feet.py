"""Would a rule for the feet's orientation help where the feet's trackers give positions
only (preset ``6x3dof``)? IK keeps a 3-DoF foot level along the pelvis heading, and its
toes beat DragPoser's by about 3 cm on other labs' performers (docs/accuracy.md, "What
the remaining `dragposer/` gaps are made of").

    PYTHONPATH=. python research/level_feet.py RULE FILE... [--mode realtime|offline] [--max-frames N]
        [--json OUT.json]

RULE is ``none`` (the solve and its reach, setting ``level_feet`` off), ``flat`` (after
the solve each ankle keeps the yaw the decoder gave its foot, with no pitch or roll),
``heading`` (each ankle takes the pelvis's yaw, IK's rule: the setting ``level_feet``
itself, on) or ``turn`` (each foot turned about the vertical until its yaw is the
pelvis's, keeping the decoder's pitch and roll). ``flat`` and ``turn`` are applied after
DragPoser's reach and rotation steps to both ankles. Runs ``dragposer-studio evaluate
--sensors 6x3dof --set level_feet=...`` in this process (``--jobs 1``) and prints its
table.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.kinematics import quat_np as Q  # noqa: E402
from engine.kinematics.fk import fk_joints, fk_positions  # noqa: E402
from engine.solver import limb_ik  # noqa: E402

ANKLES = (sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"])


def ankle_targets(local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, rule: str) -> dict[int, np.ndarray]:
    """World rotation ``(4,)`` of each ankle under ``rule`` (``flat``: the yaw of the
    ankle's own world rotation; ``turn``: the ankle's world rotation turned about +Z from
    its own yaw to the root's)."""
    level = Q.heading(np.asarray(local_rot[0], dtype=np.float64))
    _, rots = fk_joints(
        np.asarray(local_rot, dtype=np.float64), np.asarray(root_pos, dtype=np.float64), offsets, list(ANKLES)
    )
    own = [np.asarray(r, dtype=np.float64) for r in rots]
    if rule == "flat":
        return {j: Q.heading(r) for j, r in zip(ANKLES, own)}
    return {j: Q.mul(level, Q.mul(Q.conjugate(Q.heading(r)), r)) for j, r in zip(ANKLES, own)}


def with_rule(finish, rule: str):
    """``finish`` (engine.solver.limb_ik.finish) followed by the ankles' rule."""

    def wrapped(local_rot, root_pos, offsets, reach_targets, rotation_targets, neck_twist_share=0.0, level=()):
        local, pos = finish(local_rot, root_pos, offsets, reach_targets, rotation_targets, neck_twist_share, level)
        local = limb_ik.adopt_local(local, pos[0], offsets, ankle_targets(local, pos[0], offsets, rule))
        local = np.array(local, dtype=np.float64)
        return local, fk_positions(local, np.asarray(pos[0], dtype=np.float64), offsets)

    return wrapped


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rule", choices=("none", "flat", "heading", "turn"))
    ap.add_argument("--mode", default="realtime", choices=("realtime", "offline"))
    ap.add_argument("files", nargs="+")
    ap.add_argument("--max-frames", type=int)
    ap.add_argument("--json")
    args = ap.parse_args()
    import engine.methods.dragposer as dp
    import engine.methods.dragposer_batch as dpb
    from engine.cli.main import main as cli

    if args.rule in ("flat", "turn"):
        dp.finish = with_rule(dp.finish, args.rule)
        dpb.finish = with_rule(dpb.finish, args.rule)
    level = "true" if args.rule == "heading" else "false"
    argv = [
        "evaluate",
        *args.files,
        "--method",
        "dragposer",
        "--sensors",
        "6x3dof",
        "--jobs",
        "1",
        "--no-progress",
        "--set",
        f"level_feet={level}",
        "--mode",
        args.mode,
    ]
    argv += ["--max-frames", str(args.max_frames)] if args.max_frames else []
    argv += ["--json", args.json] if args.json else []
    return cli(argv) or 0


if __name__ == "__main__":
    sys.exit(main())
