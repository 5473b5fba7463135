"""How far a pinned joint stays from its pin with the shipped DragPoser and six trackers.

The left elbow is pinned 15 cm (x +0.10, y -0.10, z +0.05 m) from where it is on the first
frame of a window of the bundled example clip; the window is reconstructed in offline
and realtime mode for each pin weight given, and the pin residual and the mean sensor
error are printed.

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/measure_pin.py [START] [FRAMES] [WEIGHT ...]
"""

import sys

import numpy as np

from engine import skeleton as sk
from engine.constraints import PinConstraint
from engine.studio.clips import load_clip, sensor_presets
from engine.studio.export import reconstruct_clip

motion = load_clip("assets/clips/example.bvh")
start = int(sys.argv[1]) if len(sys.argv) > 1 else 200
n = int(sys.argv[2]) if len(sys.argv) > 2 else 20
clip = motion.slice(start, start + n)
sensors = sensor_presets()["6"]
gt = clip.positions()
J = sk.JOINT_INDEX["lelbow"]
target = gt[0, J] + np.array([0.10, -0.10, 0.05])
for mode in ("offline", "realtime"):
    for w in [float(x) for x in sys.argv[3:]] or [1.0, 10.0, 100.0]:
        cons = (PinConstraint(name="pin lelbow", weight=w, joint="lelbow", position=target.copy()),)
        res = reconstruct_clip(clip, sensors, cons, {"mode": mode}, "dragposer")
        p = res.positions()
        d = np.linalg.norm(p[:, J] - target, axis=1)
        sens = np.mean(
            [
                np.linalg.norm(p[:, sk.JOINT_INDEX[s.joint]] - gt[:, sk.JOINT_INDEX[s.joint]], axis=1).mean()
                for s in sensors
            ]
        )
        print(
            f"{mode:8s} w={w:6.1f} pin dist first {d[0] * 100:5.1f} cm, mean {d.mean() * 100:5.1f} cm, "
            f"last {d[-1] * 100:5.1f} cm; sensor err {sens * 100:4.1f} cm",
            flush=True,
        )
