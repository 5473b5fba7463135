"""Ablation (docs/accuracy.md "Held-out clips"): a naive elbow bend goal.
After the solve and the reach step, each tracked arm swivels about its shoulder-wrist
line by the share F of the angle towards an elbow hint: the point one forearm behind the
wrist along the hand tracker's rest direction (a straight wrist). Wraps the solver's
after-solve step (``engine.methods.dragposer.finish``) for this process only.

    PYTHONPATH=. python research/elbow_hint_experiment.py F SENSORS MAX_FRAMES FILE...

F = 0 reproduces the shipped solver; F = 1 on the validation files gave 16.6 deg against
10.15 (preset 6, 150 frames).
"""

import sys

import numpy as np

sys.path.insert(0, ".")
import engine.methods.dragposer as dp
from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk

F = float(sys.argv[1])
SENS = sys.argv[2]
MAXF = int(sys.argv[3])
orig = dp.finish
J = sk.JOINT_INDEX
ARMS = [(J["lwrist"], J["lelbow"], J["lshoulder"]), (J["rwrist"], J["relbow"], J["rshoulder"])]


def finish(local_rot, root_pos, offsets, reach_to, turn_to, share=0.0):
    local = orig(local_rot, root_pos, offsets, reach_to, {})[0] if reach_to else np.array(local_rot, dtype=np.float64)
    if F > 0:
        for w, e, s in ARMS:
            if w not in turn_to:
                continue
            p, g = fk(local, root_pos, offsets)
            a = p[w] - p[s]
            a /= np.linalg.norm(a)
            L = np.linalg.norm(offsets[w])
            q = np.asarray(turn_to[w], float)
            q /= np.linalg.norm(q)
            d = Q.rotate(q, offsets[w] / L)
            h = p[w] - L * d
            pe = p[e] - p[s]
            pe -= (pe @ a) * a
            ph = h - p[s]
            ph -= (ph @ a) * a
            ne, nh = np.linalg.norm(pe), np.linalg.norm(ph)
            if ne < 0.02 or nh < 0.02:
                continue  # nearly straight arm or hint on the axis: no swivel
            th = np.arctan2(np.cross(pe, ph) @ a, pe @ ph)
            r = Q.from_axis_angle(a, F * th)
            local[s] = Q.mul(Q.conjugate(g[sk.PARENTS[s]]), Q.mul(r, g[s]))
    return orig(local, root_pos, offsets, {}, turn_to, share)


dp.finish = finish
from engine.methods import get_method, run_method
from engine.motion.retarget import load_motion
from engine.tracking import simulate

m = get_method("dragposer", mode="realtime")
errs = []
pos = []
for f in sys.argv[4:]:
    mo = load_motion(f, max_frames=MAXF)
    rec, _ = run_method(m, simulate(mo, SENS), mo.skeleton, progress=False, reference=mo)
    errs.append(np.degrees(Q.angle(Q.normalize(mo.local_rot), Q.normalize(rec.local_rot))))
    gp_, _ = fk(mo.local_rot, mo.root_pos, mo.skeleton.offsets)
    rp_, _ = fk(rec.local_rot, rec.root_pos, mo.skeleton.offsets)
    pos.append(100 * np.linalg.norm(gp_ - rp_, axis=-1))
E = np.concatenate(errs)
P = np.concatenate(pos)
names = ["lshoulder", "rshoulder", "lwrist", "rwrist"]
print(
    f"F={F} {SENS} rot {E.mean():.3f} pos {P.mean():.3f} | "
    + " ".join(f"{n} {E[:, J[n]].mean():.1f}" for n in names)
    + f" | elbow pos {P[:, J['lelbow']].mean():.2f}/{P[:, J['relbow']].mean():.2f}"
)
