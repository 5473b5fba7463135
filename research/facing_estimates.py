"""How far the body facings read off the trackers are from the true pelvis heading.

    PYTHONPATH=. python research/facing_estimates.py [FILE.bvh ...] [--sensors 3-head-hands]
        [--max-frames 200]

For every file (default: the validation files) the trackers are simulated without noise
and, per frame, three facings are compared with the truth's pelvis heading (the angle
about the vertical, as ``research/stability_check.py`` measures it): the head tracker's
heading, the hands' left-right line (:func:`engine.solver.pose.body_facing` on the
wrists) and both together (:func:`engine.solver.pose.head_hands_facing`, what DragPoser's
``hands_heading_limit`` bounds the reference heading by; docs/optimizer.md). Prints the
mean and worst difference in degrees. No solve runs: it takes seconds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "research"))

from stability_check import _val_files, heading_angle_deg  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="BVH files (default: the validation files)")
    ap.add_argument("--sensors", default="3-head-hands", help="a preset with the head and both hands")
    ap.add_argument("--max-frames", type=int, default=200, help="first N frames of each file (0: whole files)")
    args = ap.parse_args()

    from engine.kinematics import quaternion as Q
    from engine.motion.retarget import load_motion
    from engine.solver.pose import body_facing, head_hands_facing
    from engine.tracking import simulate

    print(f"{'file':<24} {'head':>13} {'hands':>13} {'head+hands':>13}   (mean / worst deg)")
    for path in args.files or _val_files():
        motion = load_motion(path, max_frames=args.max_frames or None)
        tr = simulate(motion, args.sensors, noise_pos_m=0.0, seed=0)
        head, lw, rw = (tr.joints.index(j) for j in ("upperneck", "lwrist", "rwrist"))
        ident = np.array([1.0, 0.0, 0.0, 0.0])
        hands_only = [
            body_facing({"lwrist": p[lw], "rwrist": p[rw]}, (("lwrist", "rwrist", 1.0),)) for p in tr.positions
        ]
        both = [
            head_hands_facing(r[head], {"lwrist": p[lw], "rwrist": p[rw]}) for p, r in zip(tr.positions, tr.rotations)
        ]
        cells = []
        for est in (Q.heading(tr.rotations[:, head]), hands_only, both):
            q = np.array([ident if e is None else e for e in est])
            d = heading_angle_deg(motion.local_rot[:, 0], q)
            cells.append(f"{d.mean():5.1f} / {d.max():5.1f}")
        print(f"{Path(path).parent.name + '/' + Path(path).stem:<24} {cells[0]:>13} {cells[1]:>13} {cells[2]:>13}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
