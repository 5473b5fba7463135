"""Training batches of the pose VAE: frames with their successors (the continuity loss's
pairs), and the two augmentations that make new poses from them: limb mix (one limb's
rotations from another frame) and proportion scaling (each bone's length drawn around
its own). An augmented batch's encoder input and target positions are recomputed by FK.
"""

from __future__ import annotations

import torch

from engine.kinematics.features import root_space_features
from engine.training.data import PoseData

#: Joints of each limb chain swapped by the limb-mix augmentation (hip/clavicle outwards).
LIMBS: tuple[tuple[int, ...], ...] = ((1, 2, 3, 4), (5, 6, 7, 8), (14, 15, 16, 17), (18, 19, 20, 21))


def batch_of(
    data: PoseData,
    idx: torch.Tensor,
    limb_mix: float = 0.0,
    generator: torch.Generator | None = None,
    pairs: torch.Tensor | None = None,
    bone_scale: float = 0.0,
) -> dict[str, torch.Tensor]:
    """Training batch of frames ``idx`` and their successors.

    With ``limb_mix > 0`` each pose, with that probability, takes one limb's local
    rotations from another frame drawn from ``pairs`` (and its successor from that frame's
    successor, so the pair stays a motion). With ``bone_scale > 0`` every pose's bones
    are then scaled as :func:`scale_bones` does. The encoder input and target positions
    of an augmented batch are recomputed once, by one FK pass, after both."""
    nxt = idx + 1
    b = {
        "dq": data.dq[idx],
        "rot": data.rot[idx],
        "disp": data.disp[idx],
        "pos": data.pos[idx],
        "offsets": data.offsets[idx],
        "rot_next": data.rot[nxt],
        "disp_next": data.disp[nxt],
    }
    mixed = limb_mix > 0 and pairs is not None and _mix_limbs(b, data, limb_mix, generator, pairs)
    if bone_scale > 0:
        b["offsets"] = b["offsets"] * _bone_factors(b["offsets"], bone_scale, generator)[..., None]
    if mixed or bone_scale > 0:
        b["pos"], b["dq"] = root_space_features(b["rot"], b["disp"], b["offsets"])
    return b


def _mix_limbs(
    b: dict[str, torch.Tensor], data: PoseData, limb_mix: float, generator: torch.Generator | None, pairs: torch.Tensor
) -> bool:
    """Swap one limb's rotations of a ``limb_mix`` share of the poses of ``b`` (in place);
    False when no pose was drawn."""
    n = b["rot"].shape[0]
    chosen = torch.rand(n, generator=generator) < limb_mix
    if not bool(chosen.any()):
        return False
    donor = pairs[torch.randint(len(pairs), (n,), generator=generator)]
    limb = torch.randint(len(LIMBS), (n,), generator=generator)
    mask = torch.zeros(n, data.rot.shape[1], dtype=torch.bool)
    for li, joints in enumerate(LIMBS):
        rows = chosen & (limb == li)
        mask[rows.nonzero().squeeze(1)[:, None], torch.tensor(joints)] = True
    m = mask[..., None]
    b["rot"] = torch.where(m, data.rot[donor], b["rot"])
    b["rot_next"] = torch.where(m, data.rot[donor + 1], b["rot_next"])
    return True


def _bone_factors(offsets: torch.Tensor, spread: float, generator: torch.Generator | None) -> torch.Tensor:
    """One length factor per pose and bone ``(B, J)`` in ``1 +- spread``, drawn once per
    left/right pair (:data:`engine.skeleton.MIRROR_INDEX`)."""
    from engine import skeleton as sk

    n, j = offsets.shape[:2]
    pair = torch.minimum(torch.arange(j), torch.tensor(sk.MIRROR_INDEX))  # the lower index of a pair draws
    draw = 1.0 + spread * (2.0 * torch.rand(n, j, generator=generator, dtype=offsets.dtype) - 1.0)
    return draw[:, pair]


def scale_bones(
    b: dict[str, torch.Tensor],
    spread: float,
    generator: torch.Generator | None = None,
) -> dict[str, torch.Tensor]:
    """The batch ``b`` with every pose's bone offsets (B, 22, 3) scaled by one factor per
    bone in ``1 +- spread`` (left and right copies alike), and the encoder input and
    target positions recomputed for the new proportions."""
    out = dict(b)
    out["offsets"] = b["offsets"] * _bone_factors(b["offsets"], spread, generator)[..., None]
    out["pos"], out["dq"] = root_space_features(b["rot"], b["disp"], out["offsets"])
    return out
