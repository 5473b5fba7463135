"""Ablation (docs/optimizer.md "After the solve"): spread each 6-DoF tracker's
rotation correction, its twist about the limb, into the chain above it, by wrapping the
solver's after-solve step (``engine.methods.dragposer.finish``) for this process only.

    PYTHONPATH=. python research/twist_spread_experiment.py NECK ARM LEG realtime FILE...

NECK: share of the head correction's twist about the neck bone put on the lower neck.
ARM / LEG: share of the wrist's (ankle's) twist about the shoulder-wrist (hip-ankle)
line put on the whole limb, a swivel that moves no end joint. Preset 6, the first 150
frames of each file; prints Rot / Pos and per-joint errors. The figures in docs/optimizer.md were
taken before NECK became the setting ``neck_twist_share`` (default 0.5), which the
solver now applies after this step: today ``0 ARM LEG`` reproduces the rows
``0.5 ARM LEG`` of docs/optimizer.md.
"""

import sys

import numpy as np

sys.path.insert(0, ".")
import engine.methods.dragposer as dp
from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk

NECK, ARM, LEG = map(float, sys.argv[1:4])
MODE = sys.argv[4]
orig = dp.finish
J = sk.JOINT_INDEX


def slerp_id(q, f):
    q = q if q[0] >= 0 else -q
    ang = 2 * np.arccos(np.clip(q[0], -1, 1))
    s = np.sin(ang / 2)
    if s < 1e-9:
        return np.array([1, 0, 0, 0.0])
    ax = q[1:] / s
    a = f * ang
    return np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * ax])


def twist_part(delta, ax):
    p = (delta[1:] @ ax) * ax
    tw = np.concatenate([[delta[0]], p])
    n = np.linalg.norm(tw)
    return tw / n if n > 1e-9 else np.array([1, 0, 0, 0.0])


CHAINS = (
    [("upperneck", "lowerneck", "upperneck", NECK)]
    + [(e, r, e, ARM) for e, r in (("lwrist", "lshoulder"), ("rwrist", "rshoulder"))]
    + [(e, r, e, LEG) for e, r in (("lankle", "lhip"), ("rankle", "rhip"))]
)


def finish(local_rot, root_pos, offsets, reach_to, turn_to, share=0.0):
    local = orig(local_rot, root_pos, offsets, reach_to, {})[0] if reach_to else np.array(local_rot, dtype=np.float64)
    for end, top, _axis_to, f in CHAINS:
        e, t = J[end], J[top]
        if f <= 0 or e not in turn_to:
            continue
        p, g = fk(local, root_pos, offsets)
        tg = np.asarray(turn_to[e], dtype=np.float64)
        tg = tg / np.linalg.norm(tg)
        delta = Q.mul(tg, Q.conjugate(g[e]))
        ax = p[e] - p[t] if end != "upperneck" else Q.rotate(g[t], offsets[e])
        ax = ax / np.linalg.norm(ax)
        d = slerp_id(twist_part(delta, ax), f)
        local[t] = Q.mul(Q.conjugate(g[sk.PARENTS[t]]), Q.mul(d, g[t]))
    return orig(local, root_pos, offsets, {}, turn_to, share)


dp.finish = finish
from engine.methods import get_method, run_method
from engine.motion.retarget import load_motion
from engine.tracking import simulate

m = get_method("dragposer", mode=MODE)
errs = []
pos = []
for f in sys.argv[5:]:
    mo = load_motion(f, max_frames=150)
    rec, _ = run_method(m, simulate(mo, "6"), mo.skeleton, progress=False, reference=mo)
    errs.append(np.degrees(Q.angle(Q.normalize(mo.local_rot), Q.normalize(rec.local_rot))))
    gp_, _ = fk(mo.local_rot, mo.root_pos, mo.skeleton.offsets)
    rp_, _ = fk(rec.local_rot, rec.root_pos, mo.skeleton.offsets)
    pos.append(100 * np.linalg.norm(gp_ - rp_, axis=-1))
E = np.concatenate(errs)
P = np.concatenate(pos)
names = ["lowerneck", "upperneck", "lshoulder", "rshoulder", "lwrist", "rwrist", "lhip", "rhip", "lankle", "rankle"]
print(
    f"neck={NECK} arm={ARM} leg={LEG} rot {E.mean():.3f} pos {P.mean():.3f} | "
    + " ".join(f"{n} {E[:, J[n]].mean():.1f}" for n in names)
    + f" | elbow pos {P[:, J['lelbow']].mean():.2f}/{P[:, J['relbow']].mean():.2f}"
    + f" knee pos {P[:, J['lknee']].mean():.2f}/{P[:, J['rknee']].mean():.2f}"
)
