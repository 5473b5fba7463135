"""Far wrist reaches from the neutral pose (issue 50, defect 5: *a 50 cm outward wrist
drag ends 8.0 cm from its goal*): the right wrist dragged 50 cm out or forward, 30 cm
out or forward, and 30 cm forward and 20 cm down, 20 events each, as
``tests/engine/authoring/test_reach_stance.py`` drags it; per drag the wrist's distance
from its goal, how far the pelvis moved, the centre of mass's distance from the middle
of the feet's support and its margin inside their support polygon, the trunk's tilt, the
shoulder's distance from the goal and the arm's length.

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/far_reach.py [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse

import numpy as np

from engine import skeleton as sk
from engine.authoring.pose_metrics import centre_of_mass, check_pose, trunk_tilt_deg
from engine.authoring.pose_mode import PoseMode
from engine.authoring.pose_root import support_middle
from engine.authoring.pose_tasks import split_options
from engine.models import load_default_models

J = sk.JOINT_INDEX
#: Right-wrist drags in the character's frame (+X its left, -Y forward, +Z up), metres.
DRAGS = {
    "out 50": (-0.5, 0.0, 0.0),
    "forward 50": (0.0, -0.5, 0.0),
    "out 30": (-0.3, 0.0, 0.0),
    "forward 30": (0.0, -0.3, 0.0),
    "forward 30 down 20": (0.0, -0.3, -0.2),
}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    args = p.parse_args()
    init, _, _ = split_options(args.set)
    vae = load_default_models().vae
    print("drag                 err cm  pelvis  com-mid  margin  tilt  shoulder-goal  arm")
    for name, offset in DRAGS.items():
        m = PoseMode(vae, **init)
        start = m.pose.positions.copy()
        goal = start[J["rwrist"]] + np.asarray(offset)
        for k in range(1, 21):
            m.set_target("rwrist", start[J["rwrist"]] + np.asarray(offset) * k / 20)
            m.solve()
        q = m.pose.positions
        com = centre_of_mass(q)[:2]
        margin = check_pose(m.pose.local_rot, m.pose.root_pos, m.character.skeleton.offsets).balance_margin_cm
        arm = np.linalg.norm(q[J["relbow"]] - q[J["rshoulder"]]) + np.linalg.norm(q[J["rwrist"]] - q[J["relbow"]])
        print(
            f"{name:20s} {100 * np.linalg.norm(q[J['rwrist']] - goal):6.1f} {100 * np.linalg.norm(q[0, :2] - start[0, :2]):7.1f}"
            f" {100 * np.linalg.norm(com - support_middle(m.planted)):8.1f} {margin if margin is None else round(margin, 1)!s:>7}"
            f" {trunk_tilt_deg(q):5.0f} {100 * np.linalg.norm(q[J['rshoulder']] - goal):14.1f} {100 * arm:5.1f}"
        )


if __name__ == "__main__":
    main()
