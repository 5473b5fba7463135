"""Drag events per second of pose mode with and without the reach rounds: the right
wrist dragged from the mean pose within reach (20 cm forward) and beyond it (40 cm
forward, 80 cm down: the floor), each event one
:meth:`engine.authoring.pose_mode.PoseMode.solve`; prints the rate and how far the wrist
ends from its target.

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/pose_reach_rate.py [--events 40] [--rounds 0 4]
"""

import argparse
import time

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode, PoseOptions
from engine.models import load_default_models

parser = argparse.ArgumentParser()
parser.add_argument("--events", type=int, default=40)
parser.add_argument("--rounds", type=int, nargs="+", default=[0, 4])
args = parser.parse_args()
torch.set_num_threads(1)
vae = load_default_models().vae
rw = sk.JOINT_INDEX["rwrist"]
for rounds in args.rounds:
    for label, by in (("within reach", (0.0, -0.2, 0.0)), ("beyond reach", (0.0, -0.4, -0.8))):
        pm = PoseMode(vae, options=PoseOptions(reach_rounds=rounds))
        start = pm.pose.positions[rw].copy()
        t0 = time.perf_counter()
        for k in range(1, args.events + 1):
            pm.set_target("rwrist", start + np.array(by) * k / args.events)
            pm.solve()
        rate = args.events / (time.perf_counter() - t0)
        print(f"reach_rounds={rounds} {label}: {rate:.0f} drag events/s, wrist {100 * pm.shortfall():.1f} cm short")
