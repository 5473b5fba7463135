"""How far the arm no target holds moves while the other wrist is dragged (issue 50's
*dragging one wrist moves the free arm*): typical drags of the right wrist from the
neutral pose, 20 events each; the left wrist's and left shoulder's moves, cm.

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/free_arm_drift.py [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse

import numpy as np

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.authoring.pose_options import options_from_dict

J = sk.JOINT_INDEX
#: Right-wrist drags in the character's frame (+X its left, -Y forward, +Z up), metres.
DRAGS = {
    "forward 30": (0.0, -0.30, 0.0),
    "out 30": (-0.30, 0.0, 0.0),
    "up 40": (0.0, -0.10, 0.40),
    "across 25": (0.25, -0.15, 0.05),
    "down 15": (0.0, -0.05, -0.15),
    "overhead": (-0.05, -0.05, 0.75),
}


def run(vae, offset, options, events: int = 20) -> dict[str, float]:
    mode = PoseMode(vae, options=options)
    start = mode.pose.positions.copy()
    w = J["rwrist"]
    for k in range(1, events + 1):
        mode.set_target("rwrist", start[w] + np.asarray(offset) * k / events)
        mode.solve()
    p = mode.pose.positions
    d = lambda j: 100 * float(np.linalg.norm(p[J[j]] - start[J[j]]))  # noqa: E731
    return {
        "err": 100 * float(np.linalg.norm(p[w] - start[w] - offset)),
        "lwrist": d("lwrist"),
        "lelbow": d("lelbow"),
        "lshoulder": d("lshoulder"),
        "chest": d("chest"),
        "root": d("root"),
        "arm": 100
        * float(np.linalg.norm(p[J["lwrist"]] - start[J["lwrist"]] - p[J["lshoulder"]] + start[J["lshoulder"]])),
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--set", action="append", default=[])
    a = ap.parse_args()
    import torch

    from engine.models import load_default_models

    torch.set_num_threads(1)
    vals = {}
    for s in a.set:
        k, v = s.split("=", 1)
        vals[k] = {"true": True, "false": False}.get(v.lower(), v)
        if isinstance(vals[k], str):
            vals[k] = float(v)
    options = options_from_dict(vals, "--set")
    vae = load_default_models().vae
    print(
        f"{'drag':12s} {'err':>5s} {'lwrist':>6s} {'lelbow':>6s} {'lshoul':>6s} {'chest':>6s} {'root':>6s} {'arm':>6s}"
    )
    for name, off in DRAGS.items():
        r = run(vae, off, options)
        print(
            f"{name:12s} "
            + " ".join(f"{r[k]:6.1f}" for k in ("err", "lwrist", "lelbow", "lshoulder", "chest", "root", "arm"))
        )


if __name__ == "__main__":
    main()
