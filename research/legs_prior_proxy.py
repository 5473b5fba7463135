"""Where preset 4 loses to IK on other labs' performers, and what the pose bank's
features change in the legs (docs/accuracy.md, "Other labs' performers: the head, not the
legs").

    PYTHONPATH=. python research/legs_prior_proxy.py joints FILE... [--sensors 4] [--max-frames N]
        [--set KEY=VALUE ...] [--save OUT.npz]
    PYTHONPATH=. python research/legs_prior_proxy.py bank FILE... [--sensors 4] [--max-frames N]

``joints`` runs DragPoser (realtime, the profile of the preset, ``--set`` applied) and IK
on the simulated trackers of each file and prints, per file and per joint, the mean
position error of both (cm), and the error by the hips' horizontal speed (standing,
walking...).

``gap`` reads the errors ``joints --save`` wrote and splits DragPoser's gap to IK by joint
(each joint's share of the mean over the 22), and gives two oracles that bound what a
rule for the unobserved legs could gain: IK's legs on the standing frames (hips under
0.1 m/s), and on every frame, the better of the two methods per leg joint.

    PYTHONPATH=. python research/legs_prior_proxy.py gap OUT.npz

``bank`` is a fast screen of pose-bank variants without the solver: each frame's prior
latent (the mean latent of the nearest bank frames, as :class:`PoseBank` gives it, by a
batched brute-force search with the same answer), decoded and placed on the true root
(the hip tracker's pose); printed is the mean error of the leg joints and of all joints
over the files, for the shipped features and k, other k, per-block feature weights
(anchor height, displacement, rotations, relative positions), longer displacement
histories (8 and 16 frames, read from the bank's consecutive rows, which are 4 frames
apart within a clip) and the prior latent averaged over time (exponential, factor a).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.kinematics import quaternion as Q  # noqa: E402
from engine.kinematics.fk import fk  # noqa: E402
from engine.solver import tracker_prior as TP  # noqa: E402

LEGS = [sk.JOINT_INDEX[n] for n in ("lhip", "lknee", "lankle", "ltoe", "rhip", "rknee", "rankle", "rtoe")]
PRESET4 = ("root", "upperneck", "lwrist", "rwrist")


def _clips(files, max_frames, sensors):
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    out = []
    for f in files:
        m = load_motion(f, max_frames=max_frames)
        out.append((Path(f).stem, m, simulate(m, sensors), fk(m.local_rot, m.root_pos, m.skeleton.offsets)[0]))
    return out


def joints_main(args) -> None:
    from engine.config import parse_overrides
    from engine.methods import get_method, run_method
    from engine.solver import OptimizerSettings

    errs: dict[str, list[np.ndarray]] = {"dragposer": [], "ik": []}
    speeds = []
    print(f"{'file':<44}{'frames':>7} {'DragPoser':>9} {'IK':>6}")
    for name, m, tr, gt in _clips(args.files, args.max_frames, args.sensors):
        row = []
        for meth in errs:
            method = get_method(meth, mode="realtime")
            if meth == "dragposer" and args.set:
                method.configure(**parse_overrides(OptimizerSettings, args.set))
            rec, _ = run_method(method, tr, m.skeleton, progress=False, reference=m)
            e = 100.0 * np.linalg.norm(fk(rec.local_rot, rec.root_pos, m.skeleton.offsets)[0] - gt, axis=-1)
            errs[meth].append(e)
            row.append(e.mean())
        v = np.linalg.norm(np.diff(gt[:, 0, :2], axis=0), axis=-1) * m.fps
        speeds.append(np.r_[v[:1], v])
        print(f"{name:<44}{len(m):7d} {row[0]:9.2f} {row[1]:6.2f}")
    e = {k: np.concatenate(v) for k, v in errs.items()}
    print(f"\n{'joint':<11} {'DragPoser':>9} {'IK':>6}")
    for j, n in enumerate(sk.JOINT_NAMES):
        print(f"{n:<11} {e['dragposer'][:, j].mean():9.2f} {e['ik'][:, j].mean():6.2f}")
    print(f"{'mean':<11} {e['dragposer'].mean():9.2f} {e['ik'].mean():6.2f}")
    v = np.concatenate(speeds)
    if args.save:
        np.savez_compressed(args.save, dragposer=e["dragposer"], ik=e["ik"], hip_speed=v)
        print(f"per-frame, per-joint errors (cm) and hip speeds (m/s) written to {args.save}")
    for lo, hi in ((0, 0.1), (0.1, 0.3), (0.3, 0.8), (0.8, np.inf)):
        sel = (v >= lo) & (v < hi)
        if sel.any():
            print(
                f"hips {lo}-{hi} m/s: {100 * sel.mean():3.0f} % of frames, DragPoser {e['dragposer'][sel].mean():.2f}"
                f" (legs {e['dragposer'][sel][:, LEGS].mean():.2f}), IK {e['ik'][sel].mean():.2f}"
                f" (legs {e['ik'][sel][:, LEGS].mean():.2f})"
            )


STANDING = 0.1  # m/s of the hips' horizontal speed


def gap_shares(dragposer: np.ndarray, ik: np.ndarray) -> dict[str, float]:
    """Each joint's share (cm) of the difference between DragPoser's and IK's mean
    position error over all joints; ``dragposer``, ``ik``: (F, J) errors in cm. The
    shares sum to the difference of the means."""
    d = (dragposer - ik).mean(axis=0) / dragposer.shape[1]
    return {n: float(d[j]) for j, n in enumerate(sk.JOINT_NAMES)}


def leg_oracles(dragposer: np.ndarray, ik: np.ndarray, hip_speed: np.ndarray) -> dict[str, float]:
    """Mean error over all joints (cm) if DragPoser's leg joints took IK's error on the
    standing frames (``standing``), or the smaller of the two per leg joint and frame
    (``best_legs``); ``as_measured`` and ``ik`` for reference."""
    standing = dragposer.copy()
    still = hip_speed < STANDING
    standing[np.ix_(still, LEGS)] = ik[np.ix_(still, LEGS)]
    best = dragposer.copy()
    best[:, LEGS] = np.minimum(dragposer[:, LEGS], ik[:, LEGS])
    return {
        "as_measured": float(dragposer.mean()),
        "standing": float(standing.mean()),
        "best_legs": float(best.mean()),
        "ik": float(ik.mean()),
    }


def gap_main(args) -> None:
    data = np.load(args.files[0])
    dp, ik, v = data["dragposer"], data["ik"], data["hip_speed"]
    shares = gap_shares(dp, ik)
    print(f"{'joint':<11} {'share of the gap (cm)':>22}")
    for name, share in sorted(shares.items(), key=lambda kv: -abs(kv[1])):
        print(f"{name:<11} {share:22.3f}")
    print(f"{'sum':<11} {sum(shares.values()):22.3f}")
    for name, value in leg_oracles(dp, ik, v).items():
        print(f"{name:<13} {value:.2f} cm")


def _clip_rows_back(bank: TP.PoseBank, steps: int) -> np.ndarray:
    """Row index ``steps`` rows earlier in the same clip (the clip's first row at its start):
    within a clip a row's ``prev_anchor`` is the previous row's anchor position."""
    same = np.r_[False, (bank.prev_anchor[1:, 0] == bank.positions[:-1, 0]).all(-1)]
    start = np.maximum.accumulate(np.where(same, 0, np.arange(len(bank))))
    return np.maximum(np.arange(len(bank)) - steps, start)


class Variant:
    """A brute-force prior lookup of the combination ``joints`` with extra displacement lags
    (frames, multiples of :data:`TP.LAG`) and per-column weights on the standardised features."""

    def __init__(self, bank: TP.PoseBank, joints=PRESET4, lags=(), weights=None) -> None:
        self.bank, self.joints, self.lags = bank, joints, tuple(lags)
        self.a = TP.anchor_index(joints)
        x = self._bank_features()
        self.mean, self.std = x.mean(0), x.std(0) + 1e-6
        self.w = torch.ones(x.shape[1]) if weights is None else torch.as_tensor(weights, dtype=torch.float32)
        self.table = torch.as_tensor((x - self.mean) / self.std, dtype=torch.float32) * self.w
        self.norms = (self.table * self.table).sum(1)

    def _bank_features(self) -> np.ndarray:
        b, a = self.bank, self.a
        cols = [TP.BANK_JOINTS.index(j) for j in self.joints]
        pos, rot = b.positions[:, cols], b.rotations[:, cols]
        out = [TP.features(pos, rot, a, b.prev_anchor[:, TP.ANCHORS.index(self.joints[a])])]
        unyaw = Q.conjugate(Q.heading(rot[:, a]))
        for lag in self.lags:
            out.append(2.0 * Q.rotate(unyaw, pos[:, a] - pos[_clip_rows_back(b, lag // TP.LAG), a]))
        return np.concatenate(out, -1)

    def history(self) -> int:
        return max((TP.LAG, *self.lags))

    def latents(self, pos: np.ndarray, rot: np.ndarray, k: int) -> torch.Tensor:
        """Prior latents ``(F, L)`` of windows ``pos (F, H+1, S, 3)``, ``rot (F, H+1, S, 4)``."""
        h, a = pos.shape[1] - 1, self.a
        x = [TP.features(pos[:, -1], rot[:, -1], a, pos[:, h - TP.LAG, a])]
        unyaw = Q.conjugate(Q.heading(rot[:, -1, a]))
        for lag in self.lags:
            x.append(2.0 * Q.rotate(unyaw, pos[:, -1, a] - pos[:, h - lag, a]))
        q = torch.as_tensor((np.concatenate(x, -1) - self.mean) / self.std, dtype=torch.float32) * self.w
        near = torch.cat(
            [(self.norms[None] - 2 * c @ self.table.T).topk(k, dim=1, largest=False).indices for c in q.split(256)]
        )
        return self.bank._latents[near].mean(1)


def prior_errors(clips, variant: Variant, vae, k: int, average: float = 0.0) -> np.ndarray:
    """Per-frame, per-joint error (cm) ``(sum F, 22)`` of the decoded prior on the true root."""
    out = []
    for _, m, tr, gt in clips:
        idx = [tr.joints.index(j) for j in variant.joints]
        h = variant.history()
        w = np.clip(np.arange(len(tr))[:, None] + np.arange(-h, 1)[None], 0, None)
        z = variant.latents(tr.positions[:, idx][w].astype(np.float64), tr.rotations[:, idx][w].astype(np.float64), k)
        for i in range(1, len(z)) if average > 0 else ():
            z[i] = average * z[i - 1] + (1.0 - average) * z[i]
        with torch.no_grad():
            local = vae.decode(z)[0].double().numpy()
        local[:, 0] = m.local_rot[:, 0]
        out.append(100.0 * np.linalg.norm(fk(local, m.root_pos, m.skeleton.offsets)[0] - gt, axis=-1))
    return np.concatenate(out)


def bank_main(args) -> None:
    from engine.models import load_default_models

    clips = _clips(args.files, args.max_frames, args.sensors)
    vae, bank = load_default_models().vae, TP.default_bank()
    if bank is None:
        raise SystemExit("no shipped pose bank for the shipped VAE")
    base = Variant(bank)
    d = base.table.shape[1]
    blocks = {
        "height": [9],
        "displacement": [d - 3, d - 2, d - 1],
        "rotations": list(range(10, d - 3)),
        "relative positions": list(range(9)),
    }
    rows = [("shipped (k 24)", base, 24, 0.0), ("k 8", base, 8, 0.0), ("k 64", base, 64, 0.0)]
    for name, cols in blocks.items():
        for f in (3.0, 6.0) if name == "height" else (0.5, 2.0):
            w = np.ones(d)
            w[cols] = f
            rows.append((f"{name} x{f:g}", Variant(bank, weights=w), 24, 0.0))
    for lags in ((8,), (16,), (8, 16)):
        rows.append((f"displacement also over {', '.join(map(str, lags))} frames", Variant(bank, lags=lags), 24, 0.0))
    for a in (0.5, 0.8, 0.9):
        rows.append((f"prior averaged over time, a {a:g}", base, 24, a))
    print(f"{'variant':<44} {'legs cm':>8} {'all cm':>7}")
    for name, variant, k, a in rows:
        e = prior_errors(clips, variant, vae, k, a)
        print(f"{name:<44} {e[:, LEGS].mean():8.2f} {e.mean():7.2f}", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("joints", "bank", "gap"))
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--save", metavar="OUT.npz", help="joints: also write the per-frame errors")
    args = ap.parse_args()
    {"joints": joints_main, "bank": bank_main, "gap": gap_main}[args.what](args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
