"""Continuous solves per second of pose mode: a wrist target dragged 30 cm in EVENTS
steps, each one :meth:`engine.authoring.pose_mode.PoseMode.solve` (targets only: the
solver's fast path; ``--floor`` adds a floor constraint, which takes the reference path).

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/pose_mode_rate.py [--events 300] [--floor]
"""

import argparse
import time

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.constraints import FloorConstraint
from engine.models import load_default_models

parser = argparse.ArgumentParser()
parser.add_argument("--events", type=int, default=300)
parser.add_argument("--floor", action="store_true")
args = parser.parse_args()
torch.set_num_threads(1)
pm = PoseMode(load_default_models().vae, height=1.75)
if args.floor:
    pm.constraints.append(FloorConstraint())
lw = sk.JOINT_INDEX["lwrist"]
start = pm.pose.positions[lw].copy()
t0 = time.perf_counter()
for k in range(1, args.events + 1):
    pm.set_target("lwrist", start + np.array([0.0, -0.3, 0.0]) * min(1.0, 3 * k / args.events))
    pm.solve()
dt = time.perf_counter() - t0
err = np.linalg.norm(pm.pose.positions[lw] - start - [0, -0.3, 0])
print(f"{args.events / dt:.1f} solves/s ({1000 * dt / args.events:.2f} ms each), wrist {100 * err:.2f} cm off")
