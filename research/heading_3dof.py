"""How far the pelvis heading is from the truth with position-only trackers (``6x3dof``):
the facings read off the trackers and the reconstructed pelvis of IK and DragPoser, per clip.

    PYTHONPATH=. python research/heading_3dof.py ../shared/data/mocap/dragposer/*.bvh \
        [--sensors 6x3dof] [--max-frames 600] [--set key=value]

Per clip and overall, the mean (and 90th percentile) angle in degrees about the vertical between
the truth's pelvis facing and: the body facing of the feet and hands (:func:`engine.solver.pose.body_facing`,
feet and hands alike, as both methods read it), the same with the hands at half weight (DragPoser's
until 2026-12-07), the shipped heading network's (:mod:`engine.models.heading`, on the trackers' last
half second), and the pelvis each method reconstructs (realtime; ``--methods ""`` for none).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "research"))

from stability_check import heading_angle_deg  # noqa: E402

from engine import skeleton as sk  # noqa: E402
from engine.cli.method_options import apply_settings  # noqa: E402
from engine.methods import get_method, run_method  # noqa: E402
from engine.models.heading import JOINTS, default_heading_model, window_frames  # noqa: E402
from engine.motion.retarget import load_motion  # noqa: E402
from engine.solver.pose import LATERAL_PAIRS, body_facing  # noqa: E402
from engine.tracking import simulate  # noqa: E402


def facings(tracking, pairs) -> np.ndarray:
    """Per frame heading ``(F, 4)`` read off the tracked positions (identity where none)."""
    out = []
    for i in range(len(tracking)):
        pts = {j: tracking.positions[i, s] for s, j in enumerate(tracking.joints) if tracking.connected[i, s]}
        f = body_facing(pts, pairs, min_length=1e-3)
        out.append(np.array([1.0, 0, 0, 0]) if f is None else f)
    return np.array(out)


def network_error(net, tracking, truth: np.ndarray) -> np.ndarray:
    """Per frame, degrees between the truth's pelvis heading ``truth (F, 4)`` and the heading
    network's on the simulated trackers (all six connected)."""
    k = window_frames(tracking.fps)
    pos = tracking.positions[:, [tracking.joints.index(j) for j in JOINTS]]
    padded = np.concatenate([np.repeat(pos[:1], k - 1, axis=0), pos])
    windows = np.lib.stride_tricks.sliding_window_view(padded, k, axis=0).transpose(0, 3, 1, 2)
    yaw = net.yaw(windows)
    return heading_angle_deg(truth, np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=-1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path)
    ap.add_argument("--sensors", default="6x3dof")
    ap.add_argument("--methods", default="ik,dragposer")
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--set", action="append", default=[], help="optimizer setting for dragposer, key=value")
    a = ap.parse_args()
    names = [n for n in a.methods.split(",") if n]
    net = default_heading_model()
    assert net is not None, "assets/models/heading.npz is missing"
    methods = {n: get_method(n, mode="realtime") for n in names}
    if "dragposer" in methods:
        apply_settings(methods["dragposer"], "dragposer", a.set)
    cols = ["facing", "facing hands/2", "network", *names]
    allv: dict[str, list[np.ndarray]] = {c: [] for c in cols}
    print(f"{'clip':28s}" + "".join(f"{c:>16s}" for c in cols))
    for path in a.files:
        motion = load_motion(path)
        if a.max_frames:
            motion = motion.slice(0, a.max_frames)
        tracking = simulate(motion, a.sensors)
        truth = motion.local_rot[:, sk.JOINT_INDEX["root"]]
        half = tuple((left, right, 0.5 if left == "lwrist" else w) for left, right, w in LATERAL_PAIRS)
        v = {
            "facing": heading_angle_deg(truth, facings(tracking, LATERAL_PAIRS)),
            "facing hands/2": heading_angle_deg(truth, facings(tracking, half)),
            "network": network_error(net, tracking, truth),
        }
        for n, m in methods.items():
            rec, _ = run_method(m, tracking, motion.skeleton, progress=False, reference=motion, light=True)
            v[n] = heading_angle_deg(truth, rec.local_rot[:, 0])
        for c in cols:
            allv[c].append(v[c])
        print(f"{path.name[:28]:28s}" + "".join(f"{v[c].mean():8.1f}/{np.percentile(v[c], 90):6.1f} " for c in cols))
    print(
        f"{'all':28s}"
        + "".join(
            f"{np.concatenate(allv[c]).mean():8.1f}/{np.percentile(np.concatenate(allv[c]), 90):6.1f} " for c in cols
        )
    )


if __name__ == "__main__":
    main()
