"""Probe (issue 13): a prior that sees the trackers, without training, by nearest neighbours.

The oracle ablation (``scripts/oracle_prior.py``, docs/accuracy.md) shows that a prior
as good as the truth would take the sparse sets to 1.5-1.6 cm. This probe asks how much
of that a prior built from the *current trackers* recovers. It indexes the training
clips (``prepared/`` shards, train split, mirrors included) by tracker features of the
sensor set (tracked joints relative to the anchor (hips, else head) in the anchor's
heading frame, the anchor's height, the tracked rotations without heading, and the
anchor's displacement over the last 4 frames) and stores each frame's true latent (VAE
encoder mean). While solving, each frame's prior target is the mean latent of the ``k``
training frames nearest to that frame's own tracker features (causal: only this and
earlier frames' trackers are used). Everything else is the shipped solver.

    PYTHONPATH=. python scripts/knn_prior_probe.py FILE... --sensors 4 [--max-frames 150]
        [--weights 0.1,1] [--k 8] [--prepared prepared]

Not a shipped method: a measurement of what a tracker-conditioned prior could give.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.kinematics import quaternion as Q  # noqa: E402

LAG = 4


def features(pos: np.ndarray, rot: np.ndarray, anchor: int) -> np.ndarray:
    """Tracker features ``(F, D)`` from tracked world positions ``(F, S, 3)`` and
    rotations ``(F, S, 4)``; ``anchor`` indexes the anchor sensor."""
    f = len(pos)
    fwd = Q.rotate(rot[:, anchor], np.broadcast_to(np.array([0.0, -1.0, 0.0]), (f, 3)))
    yaw = np.arctan2(fwd[:, 0], -fwd[:, 1])  # heading about +Z, 0 when facing -Y
    half = -0.5 * yaw
    unyaw = np.stack((np.cos(half), np.zeros(f), np.zeros(f), np.sin(half)), -1)  # (F, 4)
    rel = pos - pos[:, anchor : anchor + 1]
    rel = Q.rotate(unyaw[:, None], rel)
    others = [i for i in range(pos.shape[1]) if i != anchor]
    r = Q.mul(np.broadcast_to(unyaw[:, None], rot.shape), rot)
    m = Q.to_matrix(r)[..., :2].reshape(f, -1)  # first two columns, per sensor
    prev = np.concatenate((np.repeat(pos[:1, anchor], LAG, 0), pos[:-LAG, anchor]))[:f]
    vel = Q.rotate(unyaw, pos[:, anchor] - prev)
    return np.concatenate((rel[:, others].reshape(f, -1), pos[:, anchor, 2:3], 0.5 * m, 2.0 * vel), -1)


def build_index(prepared: Path, joints: list[int], anchor: int):
    """(features (N, D), latents (N, L)) of every training frame."""
    from engine.kinematics.fk import fk
    from engine.methods.autoencoder import AutoencoderMethod
    from engine.motion import Motion

    man = json.loads((prepared / "manifest.json").read_text())
    ae = AutoencoderMethod()
    feats, lats = [], []
    for entry in man["files"]:
        if entry["split"] != "train":
            continue
        d = np.load(prepared / entry["shard"])
        motion = Motion(d["local_rot"], d["root_pos"], sk.Skeleton(offsets=d["offsets"]))
        pos, wrot = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
        feats.append(features(pos[:, joints], wrot[:, joints], anchor))
        ae.reset(motion.skeleton, reference=motion)
        lats.append(ae._latent)
    return np.concatenate(feats), np.concatenate(lats)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int, default=150)
    ap.add_argument("--weights", default="0.1,1")
    ap.add_argument("--k", type=int, default=8)
    ap.add_argument("--prepared", default="prepared")
    args = ap.parse_args()

    from engine.methods import get_method, run_method
    from engine.metrics import evaluate_motion
    from engine.retarget import load_motion
    from engine.tracking import simulate

    clips = [load_motion(f, max_frames=args.max_frames) for f in args.files]
    tracks = [simulate(m, args.sensors) for m in clips]
    names = list(tracks[0].joints)
    joints = [sk.JOINT_INDEX[n] for n in names]
    anchor = names.index("root") if "root" in names else names.index("upperneck")
    feats, lats = build_index(Path(args.prepared), joints, anchor)
    mean, std = feats.mean(0), feats.std(0) + 1e-6
    table = torch.as_tensor((feats - mean) / std, dtype=torch.float32)  # brute force: ~5 ms a query
    lat_t = torch.as_tensor(lats, dtype=torch.float32)
    print(f"index: {len(feats)} training frames, {feats.shape[1]} features, sensors {names}", flush=True)

    def knn_latent(track, frame: int) -> torch.Tensor:
        lo = max(0, frame - LAG)
        p, r = track.positions[lo : frame + 1], track.rotations[lo : frame + 1]
        if len(p) < LAG + 1:  # pad the start of the clip with its first frame
            p = np.concatenate((np.repeat(p[:1], LAG + 1 - len(p), 0), p))
            r = np.concatenate((np.repeat(r[:1], LAG + 1 - len(r), 0), r))
        x = features(p, r, anchor)[-1]
        q = torch.as_tensor((x - mean) / std, dtype=torch.float32)
        idx = ((table - q) ** 2).sum(1).topk(args.k, largest=False).indices
        return lat_t[idx].mean(0)

    for w in (float(x) for x in args.weights.split(",")):
        method = get_method("dragposer", mode="realtime")
        method.configure(temporal_weight=w)
        reset = method.reset
        rows = []
        for motion, track in zip(clips, tracks):

            def patched_reset(*a, _track=track, **kw):
                reset(*a, **kw)  # builds a new schedule: its prediction is replaced after
                method.schedule.prediction = lambda frame, *_, **__: (knn_latent(_track, frame), "")

            method.reset = patched_reset
            rec, _ = run_method(method, track, motion.skeleton, progress=False, reference=motion)
            rows.append((len(motion), evaluate_motion(motion, rec)))
        n = sum(k for k, _ in rows)
        agg = {key: sum(k * r[key] for k, r in rows) / n for key in ("pos_cm", "rot_deg", "ee_cm")}
        print(f"knn prior k={args.k} temporal_weight {w:<5g} Pos {agg['pos_cm']:6.2f} cm  Rot {agg['rot_deg']:5.1f} deg  "
              f"EE {agg['ee_cm']:6.2f} cm", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
