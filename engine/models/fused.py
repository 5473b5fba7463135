"""The pose decoder as a few dense layers, with its input gradient derived by hand.

Every stage of :meth:`engine.models.vae.PoseVAE.decode` between two activations is
affine: an unpooling copy followed by a skeletal linear layer (a gather and per-node
weights). Each such stage is therefore exactly one dense matrix and bias, read off by
feeding the stage the unit vectors (in float64, then stored in float32 like the model).
The decoder becomes six matrix-vector products with LeakyReLU in between, and its
gradient with respect to the latent is the same products transposed, which is what the
solver needs per iteration; no autograd graph, no per-node gathers.

The last stage folds in the quaternion identity bias and the displacement's
de-normalisation, so its output is ``(q_raw (22*4), disp (3))`` in metres.
"""

from __future__ import annotations

import copy

import numpy as np
import torch

from engine.models.skeletal import level_sizes


class DenseDecoder:
    """Dense, gradient-aware copy of a :class:`PoseVAE` decoder (numpy, one latent at a time).

    Parameters
    ----------
    vae : PoseVAE
        Source model (not modified).

    Attributes
    ----------
    weights : list of ndarray (out, in), float32
    biases : list of ndarray (out,), float32
    slope : float
        LeakyReLU negative slope (after every stage but the last).
    """

    def __init__(self, vae) -> None:
        m = copy.deepcopy(vae).double().eval()
        n = level_sizes()
        ch = m.config.channels
        ident = torch.tensor([1.0, 0.0, 0.0, 0.0], dtype=torch.float64)

        def last(x):
            x = x.reshape(-1, n[0], ch[0])
            q = (m.to_rot(x) + ident).flatten(1)
            disp = m.to_disp(x[:, 0]) * m.disp_std + m.disp_mean
            return torch.cat((q, disp), dim=1)

        stages = [
            (m.config.latent, lambda x: m.from_latent(x)),
            (n[3] * ch[3], lambda x: m.dec[0](torch.matmul(m.unpool2, x.reshape(-1, n[3], ch[3]))).flatten(1)),
            (n[2] * ch[2], lambda x: m.dec[1](torch.matmul(m.unpool1, x.reshape(-1, n[2], ch[2]))).flatten(1)),
            (n[1] * ch[1], lambda x: m.dec[2](torch.matmul(m.unpool0, x.reshape(-1, n[1], ch[1]))).flatten(1)),
            (n[0] * ch[0], lambda x: m.dec[3](x.reshape(-1, n[0], ch[0])).flatten(1)),
            (n[0] * ch[0], last),
        ]
        self.weights, self.biases = [], []
        with torch.no_grad():
            for size, f in stages:
                eye = torch.eye(size, dtype=torch.float64)
                bias = f(torch.zeros(1, size, dtype=torch.float64))[0]
                w = (f(eye) - bias).T  # (out, in)
                self.weights.append(np.ascontiguousarray(w.numpy(), dtype=np.float32))
                self.biases.append(bias.numpy().astype(np.float32))
        self.slope = float(m.config.negative_slope)
        self.latent = int(m.config.latent)
        self._gates: list[np.ndarray] = []

    def forward(self, z: np.ndarray) -> np.ndarray:
        """``z (L,)`` float32 -> ``(q_raw (88,), disp (3,))`` concatenated, float32.

        Remembers the activation slopes for the next :meth:`backward`."""
        x = z
        self._gates = []
        last = len(self.weights) - 1
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            x = w @ x + b
            if i < last:
                gate = np.where(x > 0, np.float32(1.0), np.float32(self.slope))
                self._gates.append(gate)
                x = x * gate
        return x

    def backward(self, grad_out: np.ndarray) -> np.ndarray:
        """Gradient w.r.t. the latent ``(L,)`` of a loss whose gradient w.r.t. the last
        :meth:`forward` output is ``grad_out (91,)``."""
        g = grad_out.astype(np.float32, copy=False)
        for i in range(len(self.weights) - 1, -1, -1):
            if i < len(self._gates):
                g = g * self._gates[i]
            g = g @ self.weights[i]
        return g
