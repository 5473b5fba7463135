"""Does a refactor of the solver, the kinematics or a method leave every result as it was?

``save OUT.npz`` runs a fixed set of solves on the bundled clip with the ``engine`` found
on the import path (run it from each tree with ``PYTHONPATH`` set to that tree) and
stores every frame's positions, local rotations and latent; ``compare A.npz B.npz``
prints the largest difference of each array and exits 1 when any differs by more than
``--atol`` (default 0: bit for bit).

The cases cover the root rules (6-DoF hip, 3-DoF hip, head anchor, integrated root), the
numpy and the autograd objectives, realtime, offline frame by frame, the batched offline
solve, a user constraint, a scene's four (look-at, floor, pin, distance; realtime and
offline), IK and the after-solve limb steps (``level_feet``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
CLIP = ROOT / "assets" / "clips" / "example.bvh"
SCENE = ROOT / "assets" / "scenes" / "look_floor_pin_distance.json"  # look-at, floor, pin, distance


def _dragposer(motion, tracking, frames: int, constraints=(), **kw) -> dict[str, np.ndarray]:
    from engine.methods.dragposer import create

    m = create(prepare_bank=False, **kw)
    m.reset(motion.skeleton, motion.fps)
    if constraints:
        m.set_constraints(list(constraints))
    results = [m.step(tracking.frame(i)) for i in range(frames)]
    return _stack(results)


def _stack(results) -> dict[str, np.ndarray]:
    out = {
        "positions": np.stack([r.positions for r in results]),
        "local_rot": np.stack([r.local_rot for r in results]),
    }
    if results[0].latent is not None:
        out["latent"] = np.stack([r.latent for r in results])
    return out


def save(path: Path, frames: int) -> None:
    from engine.constraints import PinConstraint
    from engine.methods.dragposer import create
    from engine.methods.ik import IKMethod
    from engine.motion.retarget import load_motion
    from engine.scene import load_scene
    from engine.tracking import simulate

    torch.set_num_threads(1)
    motion = load_motion(CLIP).slice(0, frames)
    arrays: dict[str, np.ndarray] = {}

    def put(case: str, values: dict[str, np.ndarray]) -> None:
        for k, v in values.items():
            arrays[f"{case}/{k}"] = np.asarray(v)
        print(case, flush=True)

    for preset in ("6", "6x3dof", "4", "3-head-hands", "5"):
        tracking = simulate(motion, preset)
        put(f"realtime-{preset}", _dragposer(motion, tracking, frames, iterations=10))
        put(f"ik-{preset}", _ik(IKMethod, motion, tracking, frames))
    tracking = simulate(motion, "3-head-hands")
    put("integrated-3-head-hands", _dragposer(motion, tracking, frames, iterations=10, root_anchor="none"))
    put("reference-3-head-hands", _dragposer(motion, tracking, 8, iterations=10, fast=False))
    tracking = simulate(motion, "6")
    put("reference-6", _dragposer(motion, tracking, 8, iterations=10, fast=False))
    pin = PinConstraint(name="pin", joint="lknee", position=np.array([0.1, -0.1, 0.5]))
    put("pin-6", _dragposer(motion, tracking, frames, [pin], iterations=10))
    put("offline-4", _dragposer(motion, simulate(motion, "4"), frames // 2, mode="offline"))
    scene = load_scene(SCENE)[0]
    put("scene-6", _dragposer(motion, tracking, frames, scene, iterations=10))
    put("scene-offline-6", _dragposer(motion, tracking, frames // 2, load_scene(SCENE)[0], mode="offline"))
    m = create(mode="offline", prepare_bank=False)
    m.reset(motion.skeleton, motion.fps)
    batched = m.solve_clip([tracking.frame(i) for i in range(frames)])
    assert batched is not None, "the batched solve did not take the clip"
    put("batched-6", _stack(batched))
    tracking = simulate(motion, "6x3dof")
    put("level-feet-6x3dof", _dragposer(motion, tracking, frames, iterations=10, level_feet=True))
    m = create(prepare_bank=False)
    m.reset(motion.skeleton, motion.fps)
    put("decode", {"positions": m.decode_latent(np.linspace(-1.0, 1.0, m.latent_dim))})
    put("features", _features(motion))
    np.savez(path, **arrays)


def _ik(cls, motion, tracking, frames: int) -> dict[str, np.ndarray]:
    m = cls()
    m.reset(motion.skeleton, motion.fps)
    r = [m.step(tracking.frame(i)) for i in range(frames)]
    return {"positions": np.stack([x.positions for x in r]), "local_rot": np.stack([x.local_rot for x in r])}


def _features(motion) -> dict[str, np.ndarray]:
    from engine.kinematics.features import motion_from_pose, pose_from_motion

    rot, disp = pose_from_motion(motion.local_rot, motion.root_pos)
    back = motion_from_pose(rot, disp)
    rot_t, disp_t = pose_from_motion(torch.from_numpy(motion.local_rot), torch.from_numpy(motion.root_pos))
    back_t = motion_from_pose(rot_t, disp_t)
    return {
        "rot": rot,
        "disp": disp,
        **{f"back{i}": np.asarray(b) for i, b in enumerate(back)},
        **{f"torch-back{i}": b.numpy() for i, b in enumerate(back_t)},
    }


def compare(a: Path, b: Path, atol: float) -> int:
    x, y = np.load(a), np.load(b)
    bad = 0
    for k in sorted(set(x.files) | set(y.files)):
        if k not in x.files or k not in y.files:
            print(f"{k}: only in {'the first' if k in x.files else 'the second'}")
            bad += 1
            continue
        d = float(np.max(np.abs(x[k] - y[k]))) if x[k].shape == y[k].shape else float("inf")
        print(f"{k:<40} max abs diff {d:.3g}")
        bad += d > atol
    print(f"{bad} of {len(set(x.files) | set(y.files))} arrays differ by more than {atol}")
    return 1 if bad else 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("save")
    s.add_argument("out", type=Path)
    s.add_argument("--frames", type=int, default=24)
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    c.add_argument("--atol", type=float, default=0.0)
    args = ap.parse_args()
    if args.cmd == "save":
        with tempfile.TemporaryDirectory():
            save(args.out, args.frames)
    else:
        sys.exit(compare(args.a, args.b, args.atol))


if __name__ == "__main__":
    main()
