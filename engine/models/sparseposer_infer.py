"""Realtime inference helpers for SparsePoser: the frames a step needs, the limb IK stacked.

Both give the same pose as :meth:`engine.models.sparseposer.SparsePoser.forward` on the
full window (tests check it to 1e-5); they only remove work a realtime step does not need:

* :func:`context_frames`: the last output frame of the generator reads only the last
  few frames of its window (the receptive field of three stride-2 levels and the
  decoder, 23 frames for the shipped kernel 3), so a step feeds the generator the last
  ``context`` frames instead of ``window``.
* :class:`DenseGenerator`: each skeletal convolution as one dense matrix over the
  window's (node, tap, channel) features, with the node pooling/unpooling that precedes
  it folded in, so a level is one matrix product instead of a gather, 22 per-node
  products and a pooling product (for the shipped sizes 2.2 M weights, 8.9 MB; about
  1.4x faster than the training layout at one frame). The output convolution runs on
  the last frame only.
* :class:`StackedLimbIK`: the four limb networks as three batched matrix products
  instead of twelve small linear layers and their Python bookkeeping.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from engine.kinematics import quaternion as Q
from engine.models.sparseposer import LIMB_EE, LIMB_INDEX, LimbIK, SkeletalConv, SparsePoser

#: Frames added to the receptive field: the shorter window's own zero padding must stay
#: outside what the last frame reads (with 24 frames for a field of 23 the last frame
#: moves by 3e-7; with 32 it is bit-identical).
MARGIN = 8


def receptive_field(model: SparsePoser) -> int:
    """Number of trailing input frames the generator's last output frame depends on.

    Found from the input gradient of a random projection of the last frame of a full
    window (LeakyReLU never has a zero derivative, so a frame is read iff its gradient
    is non-zero)."""
    cfg = model.config
    gen = torch.Generator().manual_seed(0)
    x = torch.randn(1, cfg.window, 22, 8, generator=gen).requires_grad_(True)
    off = 0.1 * torch.randn(1, 22, 3, generator=gen)
    with torch.enable_grad():
        out = model.generator(x, off)[:, -1]
        (out * torch.randn(out.shape, generator=gen)).sum().backward()
    assert x.grad is not None  # x requires grad and the output depends on it
    read = torch.nonzero(x.grad.abs().sum(dim=(0, 2, 3)) > 0)
    return cfg.window - int(read[0])


def context_frames(model: SparsePoser) -> int:
    """Window length a realtime step feeds the generator: the receptive field plus
    :data:`MARGIN`, rounded up to a multiple of 8 (three stride-2 levels keep their
    phase), at most the trained window."""
    need = receptive_field(model) + MARGIN
    return min(model.config.window, 8 * math.ceil(need / 8))


def dense_conv(conv: SkeletalConv, node_map: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """One skeletal convolution as ``(D, bias)``: ``y (T', N * C_out) = x (T', N_in * K * C)
    @ D + bias``, rows of ``x`` ordered (node, tap, channel) as :func:`unfold_frames`
    gives them. ``node_map (N, N_in)`` (pooling or unpooling) maps the nodes the layer is
    fed to the nodes it reads; it is folded into ``D``. Built in float64, stored float32."""
    lin = conv.linear
    n, k, cin, cout = lin.n, lin.k, lin.c_in, lin.c_out
    gather = lin.gather.reshape(n, k, n).double()  # (out node, slot, in node)
    w = lin.weight.detach().reshape(n, k, cin, cout).double()  # (out node, slot, tap*channel, out ch)
    d = torch.einsum("isj,isco->jcio", gather, w)  # (in node, tap*channel, out node, out ch)
    if node_map is not None:
        d = torch.einsum("je,jcio->ecio", node_map.double(), d)
    return d.reshape(-1, n * cout).float().contiguous(), lin.bias.detach().reshape(-1).clone()


def unfold_frames(x: torch.Tensor, kernel: int, stride: int) -> torch.Tensor:
    """``(T, N, C)`` -> ``(T', N * kernel * C)``: each output frame's zero-padded taps,
    in the order :class:`~engine.models.sparseposer.SkeletalConv` stacks them."""
    pad = kernel // 2
    w = F.pad(x, (0, 0, 0, 0, pad, pad)).unfold(0, kernel, stride)  # (T', N, C, K)
    return w.permute(0, 1, 3, 2).reshape(w.shape[0], -1)


def upsample_frames(x: torch.Tensor) -> torch.Tensor:
    """Linear temporal upsampling ``(T, N, C) -> (2T, N, C)`` (as the generator's)."""
    t, n, c = x.shape
    y = F.interpolate(x.reshape(t, n * c).T[None], scale_factor=2, mode="linear", align_corners=False)[0]
    return y.T.reshape(2 * t, n, c)


class DenseGenerator:
    """The generator of ``model`` for one window at a time, last frame only (weights
    copied: build it again after changing the model's weights)."""

    def __init__(self, model: SparsePoser):
        g = model.generator
        # a ModuleList's items are typed Module: these are the generator's SkeletalConvs
        enc, dec = cast(list[SkeletalConv], list(g.enc)), cast(list[SkeletalConv], list(g.dec))
        self.kernel = enc[0].kernel  # the encoder's (``kernel`` setting)
        self.dec_kernel = g.out.kernel  # the decoder's (always 3)
        self.slope = g.act.negative_slope
        self.enc = [dense_conv(enc[0]), dense_conv(enc[1], g.pool0), dense_conv(enc[2], g.pool1)]
        self.dec = [
            dense_conv(dec[0], g.unpool2 @ g.pool2),
            dense_conv(dec[1], g.unpool1),
            dense_conv(dec[2], g.unpool0),
        ]
        self.out = dense_conv(g.out)
        self.enc_nodes = [enc[i].linear.n for i in range(3)]
        self.dec_nodes = [dec[i].linear.n for i in range(3)]

    def __call__(self, x: torch.Tensor, static: list[torch.Tensor], tail: int) -> torch.Tensor:
        """Last output frame ``(22, 8)`` (normalised dq) of the normalised sparse window
        ``x (T, 22, 8)``; ``static`` the generator's static features of the skeleton,
        ``tail`` as in :meth:`SparsePoserGenerator.forward`."""
        k, h = self.kernel, x
        for (d, b), n in zip(self.enc, self.enc_nodes):
            h = F.leaky_relu(torch.addmm(b, unfold_frames(h, k, 2), d), self.slope).reshape(h.shape[0] // 2, n, -1)
        k = self.dec_kernel
        for (d, b), n, s in zip(self.dec, self.dec_nodes, static[::-1]):
            h = upsample_frames(h)[-tail:]
            h = F.leaky_relu(torch.addmm(b, unfold_frames(h, k, 1), d), self.slope).reshape(len(h), n, -1) + s[0]
        d, b = self.out
        last = unfold_frames(h[-(k // 2 + 1) :], k, 1)[-1:]  # the last frame's taps (zero pad after it)
        return torch.addmm(b, last, d).reshape(h.shape[1], -1)


class StackedLimbIK:
    """The four :class:`~engine.models.sparseposer.LimbIK` networks of ``model`` as one
    batched MLP (weights copied: build it again after changing the model's weights)."""

    def __init__(self, model: SparsePoser):
        # the limbs' MLPs: Linear, LeakyReLU, Linear, LeakyReLU, Linear (items typed Module)
        nets = [ik.net for ik in cast(list[LimbIK], list(model.ik))]
        linears = [[cast(nn.Linear, n[i]) for i in (0, 2, 4)] for n in nets]
        self.weights = [torch.stack([lin[i].weight.detach().T for lin in linears]).contiguous() for i in range(3)]
        self.biases = [torch.stack([lin[i].bias.detach() for lin in linears])[:, None] for i in range(3)]
        self.slope = cast(nn.LeakyReLU, nets[0][1]).negative_slope
        self.limb = torch.tensor(LIMB_INDEX)  # (4 limbs, 4 joints)
        self.limb_index = np.array(LIMB_INDEX)
        self.ee = torch.tensor(LIMB_EE)
        self.model = model

    def mlp(self, x: torch.Tensor) -> torch.Tensor:
        """The four networks on their inputs ``x (4 limbs, B, 52)`` -> ``(4, B, 16)``
        rotation changes (the limb's generator dq, offsets x 10, normalised tracker dq)."""
        for k, (w, bias) in enumerate(zip(self.weights, self.biases)):
            x = torch.baddbmm(bias, x, w)
            if k < 2:
                x = F.leaky_relu(x, self.slope)
        return x

    def __call__(
        self, gen_out: torch.Tensor, local: torch.Tensor, offsets: torch.Tensor, target_dq: torch.Tensor
    ) -> torch.Tensor:
        """Same as :meth:`SparsePoser.refine`: ``gen_out (B, 22, 8)`` normalised, ``local
        (B, 22, 4)``, ``offsets (B, 22, 3)`` metres, ``target_dq (B, 22, 8)`` raw -> local
        rotations ``(B, 22, 4)`` with the limbs replaced."""
        b = gen_out.shape[0]
        target = self.model.normalise(target_dq)[:, self.ee]  # (B, 4, 8)
        x = torch.cat((gen_out[:, self.limb].flatten(2), offsets[:, self.limb].flatten(2) * 10.0, target), dim=-1)
        delta = self.mlp(x.transpose(0, 1)).transpose(0, 1).reshape(b, 4, 4, 4)
        new = Q.canonicalize(Q.normalize(local[:, self.limb] + delta))
        out = local.clone()
        out[:, self.limb.flatten()] = new.reshape(b, 16, 4)
        return out
