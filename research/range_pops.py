"""Range re-solve: the largest joint step and the feet's sliding, before and after an edit.

For each BVH file: a floor-contact re-solve of its last 70 frames and of 61 frames from
its middle (blend 8); prints the largest joint step over the edited frames against the
limit (``engine.authoring.range_edit.step_limit``) and the foot joints whose mean
horizontal step, over the steps where the clip has them down on both frames, grew.

    PYTHONPATH=. python research/range_pops.py ../shared/data/mocap/cmu_iclone/005_04.bvh ...
"""

import sys

import numpy as np
import torch

from engine import skeleton as sk
from engine.authoring.range_edit import edit_range, step_limit
from engine.constraints import FloorConstraint
from engine.models import load_default_models
from engine.motion.retarget import load_motion

torch.set_num_threads(1)
vae = load_default_models().vae
FLOOR = FloorConstraint(name="floor")

for path in sys.argv[1:]:
    m = load_motion(path)
    n = len(m)
    for s, e in ((n - 70, n - 1), (n // 2, n // 2 + 60)):
        ed = edit_range(vae, m, s, e, [FLOOR], blend=8)
        a, b = m.positions(), ed.motion.positions()
        r0, r1 = max(ed.first - 1, 0), min(ed.last + 2, n)
        steps = np.linalg.norm(np.diff(b[r0:r1], axis=0), axis=-1)
        worse = []
        for name in ("ltoe", "rtoe", "lankle", "rankle"):
            j = sk.JOINT_INDEX[name]
            down = a[r0:r1, j, 2] < FLOOR.floor_height + FLOOR.contact_height
            both = down[1:] & down[:-1]
            if both.any():
                was = np.linalg.norm(np.diff(a[r0:r1, j, :2], axis=0), axis=-1)[both].mean()
                now = np.linalg.norm(np.diff(b[r0:r1, j, :2], axis=0), axis=-1)[both].mean()
                if now > was + 1e-6:
                    worse.append(f"{name} {was * 100:.2f} -> {now * 100:.2f} cm/frame")
        print(
            f"{path}: {s}-{e}: largest step {steps.max() * 100:.1f} cm (limit "
            f"{step_limit(m, ed.first, ed.last) * 100:.1f}); slid more: {', '.join(worse) or 'none'}",
            flush=True,
        )
