"""Where a method's error sits: mean position (cm) and local rotation (degrees) error per joint of one or more methods
on the same clips and tracker preset, side by side, realtime.

    PYTHONPATH=. python research/per_joint_error.py ../shared/data/mocap/dragposer/*.bvh \
        --sensors 6 --methods ik,dragposer --max-frames 600 [--set tracker_prior=both]

Each clip is loaded and retargeted as ``evaluate`` does, the trackers simulated by
:func:`engine.tracking.simulate`, and each method run by :func:`engine.methods.run_method`;
the per-joint figure is the mean over all frames of all clips of the world distance
between the reconstructed and the true joint (``evaluate``'s Pos, before the mean over
joints).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.cli.method_options import apply_settings
from engine.kinematics import quaternion as Q
from engine.methods import get_method, run_method
from engine.motion.retarget import load_motion
from engine.tracking import simulate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--methods", default="ik,dragposer")
    ap.add_argument("--max-frames", type=int, default=0)
    ap.add_argument("--set", action="append", default=[], help="optimizer setting for dragposer, key=value")
    a = ap.parse_args()
    names = a.methods.split(",")
    errors: dict[str, list[np.ndarray]] = {n: [] for n in names}
    angles: dict[str, list[np.ndarray]] = {n: [] for n in names}
    methods = {n: get_method(n, mode="realtime") for n in names}  # run_method resets each per clip
    if "dragposer" in methods:
        apply_settings(methods["dragposer"], "dragposer", a.set)
    for path in a.files:
        motion = load_motion(path)
        if a.max_frames:
            motion = motion.slice(0, a.max_frames)
        truth, _ = motion.fk()
        tracking = simulate(motion, a.sensors)
        for name, method in methods.items():
            rec, _ = run_method(method, tracking, motion.skeleton, progress=False, reference=motion, light=True)
            pos, _ = rec.fk()
            errors[name].append(100 * np.linalg.norm(pos - truth, axis=-1))
            angles[name].append(np.degrees(Q.angle(Q.normalize(motion.local_rot), Q.normalize(rec.local_rot))))
    per = {n: np.concatenate(e).mean(axis=0) for n, e in errors.items()}
    rot = {n: np.concatenate(e).mean(axis=0) for n, e in angles.items()}
    print(f"{'joint':16s}" + "".join(f"{n + ' cm':>14s}" for n in names) + "".join(f"{n + ' deg':>14s}" for n in names))
    for j, joint in enumerate(sk.JOINT_NAMES):
        cells = [f"{per[n][j]:14.2f}" for n in names] + [f"{rot[n][j]:14.2f}" for n in names]
        print(f"{joint:16s}" + "".join(cells))
    means = [f"{per[n].mean():14.2f}" for n in names] + [f"{rot[n].mean():14.2f}" for n in names]
    print(f"{'mean':16s}" + "".join(means))


if __name__ == "__main__":
    main()
