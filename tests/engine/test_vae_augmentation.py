"""The VAE's proportion augmentation (``bone_scale``): one factor per bone in the range,
shared by left and right, and the encoder input and target positions of the new build."""

from __future__ import annotations

import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.features import encoder_input, root_space_fk
from engine.training.vae_batches import scale_bones


def _batch(n: int = 64) -> dict:
    g = torch.Generator().manual_seed(1)
    rot = Q.normalize(torch.randn(n, sk.NUM_JOINTS, 4, generator=g, dtype=torch.float64))
    offsets = torch.as_tensor(sk.Skeleton.canonical().offsets, dtype=torch.float64).expand(n, -1, -1).clone()
    disp = torch.randn(n, 3, generator=g, dtype=torch.float64) * 0.01
    pos, _ = root_space_fk(rot, offsets)
    return {"rot": rot, "disp": disp, "offsets": offsets, "pos": pos, "dq": encoder_input(rot, disp, offsets)}


def test_bones_scale_within_the_spread_alike_on_both_sides():
    b = _batch()
    out = scale_bones(b, 0.15, torch.Generator().manual_seed(0))
    length = b["offsets"].norm(dim=-1)
    bones = length[0] > 1e-6
    ratio = out["offsets"].norm(dim=-1)[:, bones] / length[:, bones]
    assert ratio.min() >= 0.85 - 1e-9 and ratio.max() <= 1.15 + 1e-9
    assert ratio.std() > 0.05  # the factors do vary
    for a, c in sk.MIRROR_PAIRS:
        torch.testing.assert_close(
            out["offsets"].norm(dim=-1)[:, sk.JOINT_INDEX[a]] / length[:, sk.JOINT_INDEX[a]],
            out["offsets"].norm(dim=-1)[:, sk.JOINT_INDEX[c]] / length[:, sk.JOINT_INDEX[c]],
        )


def test_targets_and_encoder_input_follow_the_new_build():
    b = _batch()
    out = scale_bones(b, 0.15, torch.Generator().manual_seed(0))
    pos, _ = root_space_fk(b["rot"], out["offsets"])
    torch.testing.assert_close(out["pos"], pos)
    torch.testing.assert_close(out["dq"], encoder_input(b["rot"], b["disp"], out["offsets"]))
    assert (out["pos"] - b["pos"]).abs().max() > 0.01
    torch.testing.assert_close(out["rot"], b["rot"])  # the pose itself is unchanged
    unchanged = scale_bones(b, 0.0)
    torch.testing.assert_close(unchanged["pos"], b["pos"])
