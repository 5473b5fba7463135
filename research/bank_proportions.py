"""Does the pose bank find better neighbours when every performer's tracker readings are
first scaled to one body's proportions?

The bank's features are metres: a tracked joint relative to the anchor (hips, or else the
head), the anchor's height, its displacement. Performers and rigs differ in size: the
``dragposer/`` clips put the head joint 0.68 m of bone above the hips where the training
clips' median is 0.43, so a standing performer's readings look like no training frame. Here
each reading relative to the anchor is scaled by (the training median / this body) of the
bone-chain length between the anchor and that joint, and the anchor's height and
displacement by the same ratio for the chain from the anchor down to the ankle, in the bank
and in the query alike.

    PYTHONPATH=. python research/bank_proportions.py FILE... [--sensors 4] [--max-frames 600] [--data prepared]

Prints, as ``legs_prior_proxy.py bank`` does (each frame's prior latent decoded and put on
the true root, no solver), the mean error of the leg joints and of all joints, cm, for the
bank rebuilt here without and with the scaling.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))

from build_pose_bank import bank_from_motions  # noqa: E402

from engine import skeleton as sk  # noqa: E402
from engine.motion.clip import Motion  # noqa: E402
from engine.solver import tracker_prior as TP  # noqa: E402
from research.legs_prior_proxy import LEGS, Variant, _clips, prior_errors  # noqa: E402

#: What is scaled: the relative positions ("rel") and/or the anchor's height and displacement ("height").
PARTS = {"rel", "height"}


def _path(a: int, b: int) -> list[int]:
    """Joints whose bones join ``a`` and ``b`` (each joint's bone is the one to its parent)."""
    up_a, up_b = [a], [b]
    while up_a[-1] > 0:
        up_a.append(sk.PARENTS[up_a[-1]])
    while up_b[-1] > 0:
        up_b.append(sk.PARENTS[up_b[-1]])
    common = next(j for j in up_a if j in up_b)
    return up_a[: up_a.index(common)] + up_b[: up_b.index(common)]


def chain_lengths(offsets: np.ndarray) -> np.ndarray:
    """``(A, S + 1)``: for each anchor, the bone length to each bank joint, then to the left ankle."""
    length = np.linalg.norm(offsets, axis=-1)
    out = np.zeros((len(TP.ANCHORS), len(TP.BANK_JOINTS) + 1))
    for i, a in enumerate(TP.ANCHORS):
        for k, j in enumerate((*TP.BANK_JOINTS, "lankle")):
            out[i, k] = length[_path(sk.JOINT_INDEX[a], sk.JOINT_INDEX[j])].sum()
    return out


def scaled(pos: np.ndarray, prev: np.ndarray, ratio: np.ndarray, a: int, cols: list[int]) -> tuple:
    """``pos (..., S, 3)`` of the bank joints ``cols`` and the anchor's earlier position
    ``prev (..., 3)``, scaled about the anchor ``a`` (an index in ``cols``) by ``ratio (..., A, S + 1)``."""
    ai = TP.ANCHORS.index(TP.BANK_JOINTS[cols[a]])
    r_rel = ratio[..., ai, :][..., cols] if "rel" in PARTS else np.ones_like(ratio[..., ai, :][..., cols])
    r_h = ratio[..., ai, -1] if "height" in PARTS else np.ones_like(ratio[..., ai, -1])
    anchor = pos[..., a, :]
    out = anchor[..., None, :] + (pos - anchor[..., None, :]) * r_rel[..., None]
    new_anchor = anchor.copy()
    new_anchor[..., 2] *= r_h
    out = out + (new_anchor - anchor)[..., None, :]
    new_prev = new_anchor - (anchor - prev) * r_h[..., None]
    return out, new_prev


class ScaledVariant(Variant):
    def __init__(self, bank, ratios, clip_ratios, joints) -> None:
        self.ratios, self.clip_ratios = ratios, clip_ratios
        self.cols = [TP.BANK_JOINTS.index(j) for j in joints]
        super().__init__(bank, joints=joints)

    def _bank_features(self) -> np.ndarray:
        b, a = self.bank, self.a
        ai = TP.ANCHORS.index(self.joints[a])
        pos, prev = scaled(b.positions[:, self.cols], b.prev_anchor[:, ai], self.ratios, a, self.cols)
        return TP.features(pos, b.rotations[:, self.cols], a, prev)

    def latents(self, pos: np.ndarray, rot: np.ndarray, k: int) -> torch.Tensor:
        h, a = pos.shape[1] - 1, self.a
        r = np.broadcast_to(self.clip_ratios, (len(pos), *self.clip_ratios.shape))
        now, prev = scaled(pos[:, -1], pos[:, h - TP.LAG, a], r, a, self.cols)
        q = torch.as_tensor((TP.features(now, rot[:, -1], a, prev) - self.mean) / self.std, dtype=torch.float32)
        near = torch.cat(
            [(self.norms[None] - 2 * c @ self.table.T).topk(k, dim=1, largest=False).indices for c in q.split(256)]
        )
        return self.bank._latents[near].mean(1)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--data", default="prepared")
    ap.add_argument("--stride", type=int, default=4)
    args = ap.parse_args()
    from engine.models import load_default_models

    vae = load_default_models().vae
    data = Path(args.data)
    man = json.loads((data / "manifest.json").read_text())
    motions, lengths, rows = [], [], []
    for entry in man["files"]:
        if entry["split"] == "train":
            d = np.load(data / entry["shard"])
            motions.append(Motion(d["local_rot"], d["root_pos"], sk.Skeleton(offsets=d["offsets"])))
            lengths.append(chain_lengths(d["offsets"]))
            rows.append(len(range(0, len(d["local_rot"]), args.stride)))
    bank = bank_from_motions(motions, vae, 24, "", args.stride)
    lengths = np.array(lengths)
    ref = np.median(lengths, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.where(lengths > 0, ref / lengths, 1.0)
    row_ratios = np.repeat(ratios, rows, axis=0)
    assert len(row_ratios) == len(bank)
    clips = _clips(args.files, args.max_frames, args.sensors)
    joints = tuple(j for j in clips[0][2].joints if j in TP.BANK_JOINTS)
    print("combination", joints, "reference lengths (anchor root):", ref[0].round(3))
    print(f"{'bank':<40} {'legs cm':>8} {'all cm':>7}")
    base = Variant(bank, joints=joints)
    e = prior_errors(clips, base, vae, 24)
    print(f"{'metres (as shipped)':<40} {e[:, LEGS].mean():8.2f} {e.mean():7.2f}", flush=True)
    for parts in ({"rel", "height"}, {"height"}, {"rel"}):
        PARTS.clear()
        PARTS.update(parts)
        scaled_variant = ScaledVariant(bank, row_ratios, np.ones_like(ref), joints)
        errs = []
        for c in clips:
            with np.errstate(divide="ignore", invalid="ignore"):
                cl = chain_lengths(c[1].skeleton.offsets)
                scaled_variant.clip_ratios = np.where(cl > 0, ref / cl, 1.0)
            errs.append(prior_errors([c], scaled_variant, vae, 24))
        e = np.concatenate(errs)
        name = "scaled: " + " and ".join(sorted(parts))
        print(f"{name:<40} {e[:, LEGS].mean():8.2f} {e.mean():7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
