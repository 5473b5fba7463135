"""Whether a method's elbow error is a constant offset: the mean error vector of each
elbow in the true chest frame, per clip, beside the mean error length, and each clip's
mean local wrist rotation (angle and axis), realtime, first frames of each clip.

    PYTHONPATH=. python research/elbow_bias.py FILES... [--sensors 6] [--methods ik,dragposer]
                                               [--max-frames 600]

A bias that is most of the mean error and the same on every clip of one rig points at
how that rig's arms were retargeted or held, not at the frame-by-frame solve. The chest
frame is the canonical one: +X the character's left, -Y forward, +Z up.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.methods import get_method, run_method
from engine.motion.retarget import load_motion
from engine.tracking import simulate

J = sk.JOINT_INDEX


def mean_rotation(q: np.ndarray) -> tuple[float, np.ndarray]:
    """Angle (degrees) and axis of the normalised mean of unit quaternions ``q (F, 4)``."""
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)
    m = q.mean(0)
    m /= np.linalg.norm(m)
    return float(np.degrees(2 * np.arccos(min(abs(m[0]), 1.0)))), m[1:] / max(np.linalg.norm(m[1:]), 1e-12)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--methods", default="ik,dragposer")
    ap.add_argument("--max-frames", type=int, default=600)
    a = ap.parse_args()
    methods = {n: get_method(n, mode="realtime") for n in a.methods.split(",")}
    for path in a.files:
        motion = load_motion(path)
        if a.max_frames:
            motion = motion.slice(0, a.max_frames)
        truth, world = motion.fk()
        chest = Q.to_matrix(Q.normalize(world[:, J["chest"]]))  # (F, 3, 3)
        wrists = []
        for side in "lr":
            ang, axis = mean_rotation(motion.local_rot[:, J[side + "wrist"]])
            wrists.append(f"{side}wrist {ang:4.1f} deg about {np.round(axis, 2)}")
        print(f"{path.name}: {', '.join(wrists)}")
        tracking = simulate(motion, a.sensors)
        for name, method in methods.items():
            rec, _ = run_method(method, tracking, motion.skeleton, progress=False, reference=motion, light=True)
            pos, _ = rec.fk()
            cells = []
            for side in "lr":
                j = J[side + "elbow"]
                err = 100 * np.einsum("fji,fj->fi", chest, pos[:, j] - truth[:, j])  # cm, chest frame
                bias = err.mean(0)
                cells.append(
                    f"{side}elbow bias {np.round(bias, 1)} |bias| {np.linalg.norm(bias):.1f} "
                    f"mean error {np.linalg.norm(err, axis=1).mean():.1f} cm"
                )
            print(f"  {name:10s} " + " | ".join(cells))


if __name__ == "__main__":
    main()
