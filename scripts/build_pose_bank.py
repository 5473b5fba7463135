"""Build the pose bank of the tracker prior (engine/solver/tracker_prior.py) from prepared data.

Every frame of the training split of ``prepared/`` (mirrors included; ``dragposer-studio
data prepare``): forward kinematics gives the world positions and rotations of the bank
joints, the VAE encoder's mean gives the latent of the true pose.

    PYTHONPATH=. python scripts/build_pose_bank.py --data prepared --out assets/models/pose_bank.npz
        [--vae assets/models/vae.pt] [--k 8] [--stride 1]

``--stride N`` keeps every N-th frame of each clip (frames 0, N, 2N, ...; the previous
anchor positions of a kept frame still come from the frame ``LAG`` before it): the bank's
size sets its load time and the cost of a lookup, and neighbouring frames at 60 fps are
nearly the same pose.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.input_files import file_sha256  # noqa: E402
from engine.solver.tracker_prior import ANCHORS, BANK_JOINTS, LAG, PoseBank  # noqa: E402


def bank_from_motions(motions, vae, k: int = 8, vae_sha256: str = "", stride: int = 1) -> PoseBank:
    """A :class:`PoseBank` of every ``stride``-th frame of each of ``motions``
    (:class:`engine.motion.clip.Motion`)."""
    from engine.kinematics.fk import fk
    from engine.methods.autoencoder import AutoencoderMethod

    ae = AutoencoderMethod(vae=vae)
    cols = [sk.JOINT_INDEX[j] for j in BANK_JOINTS]
    anchors = [sk.JOINT_INDEX[a] for a in ANCHORS]
    pos, rot, prev, lat = [], [], [], []
    for motion in motions:
        p, r = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
        pos.append(p[::stride, cols])
        rot.append(r[::stride, cols])
        a = p[:, anchors]
        prev.append(np.concatenate((np.repeat(a[:1], LAG, 0), a[:-LAG]))[: len(a)][::stride])
        ae.reset(motion.skeleton, reference=motion)
        lat.append(ae._latent[::stride])
    return PoseBank(
        np.concatenate(pos),
        np.concatenate(rot),
        np.concatenate(prev),
        np.concatenate(lat).astype(np.float32),
        vae_sha256,
        k,
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default="prepared")
    ap.add_argument("--out", default="assets/models/pose_bank.npz")
    ap.add_argument("--vae", help="VAE weights (default: the shipped one)")
    ap.add_argument("--k", type=int, default=8)
    ap.add_argument("--stride", type=int, default=1, help="keep every N-th frame of each clip (default: all)")
    args = ap.parse_args()
    if args.stride < 1:
        ap.error(f"--stride must be 1 or more, got {args.stride}")

    from engine.models import load_default_models, load_models
    from engine.models.loading import DEFAULT_VAE
    from engine.motion.clip import Motion

    vae_file = Path(args.vae) if args.vae else DEFAULT_VAE
    vae = (load_models(vae_file) if args.vae else load_default_models()).vae
    data = Path(args.data)
    man = json.loads((data / "manifest.json").read_text())
    t0 = time.monotonic()
    motions = []
    for entry in man["files"]:
        if entry["split"] == "train":
            d = np.load(data / entry["shard"])
            motions.append(Motion(d["local_rot"], d["root_pos"], sk.Skeleton(offsets=d["offsets"])))
    bank = bank_from_motions(motions, vae, args.k, file_sha256(vae_file), args.stride)
    bank.save(args.out)
    print(
        f"wrote {args.out}: {len(bank)} frames (stride {args.stride}) of {len(motions)} training clips "
        f"(data hash {man.get('hash')}), "
        f"{time.monotonic() - t0:.0f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
