"""Latent update rules (Adam, gradient steps with optional Nesterov momentum), numpy.

The same arithmetic as ``torch.optim.Adam`` / ``torch.optim.SGD`` on one float32
vector (a test checks it step by step), without the optimizer object's per-step
overhead, and shared by the solver's fast and reference paths.
"""

from __future__ import annotations

import math

import numpy as np


class LatentUpdate:
    """One update rule's state for a latent ``(L,)``.

    Parameters
    ----------
    rule : str
        ``sgd``, ``adam`` or ``adam-carry`` (Adam; the caller keeps :attr:`state`).
    lr : float
        Adam learning rate, or the step of ``sgd``.
    momentum : float
        ``sgd`` only: Nesterov momentum (0 = plain gradient steps).
    state : dict, optional
        Adam moments to continue from (``step``, ``exp_avg``, ``exp_avg_sq``).
    """

    BETAS = (0.9, 0.999)
    EPS = 1e-8

    def __init__(self, rule: str, lr: float, momentum: float = 0.0, state: dict | None = None) -> None:
        self.rule, self.lr, self.momentum = rule, float(lr), float(momentum)
        self.state = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in (state or {}).items()}

    def step(self, z: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """The next latent (new array, float32)."""
        grad = grad.astype(np.float32, copy=False)
        if self.rule == "sgd":
            if self.momentum > 0:
                buf = self.state.get("momentum_buffer")
                buf = grad.copy() if buf is None else buf * np.float32(self.momentum) + grad
                self.state["momentum_buffer"] = buf
                grad = grad + np.float32(self.momentum) * buf
            return z - np.float32(self.lr) * grad
        b1, b2 = self.BETAS
        s = self.state
        if not s:
            s.update(step=0, exp_avg=np.zeros_like(z), exp_avg_sq=np.zeros_like(z))
        s["step"] += 1
        m = s["exp_avg"] + np.float32(1 - b1) * (grad - s["exp_avg"])
        v = s["exp_avg_sq"] * np.float32(b2) + np.float32(1 - b2) * grad * grad
        s["exp_avg"], s["exp_avg_sq"] = m, v
        step_size = self.lr / (1 - b1 ** s["step"])
        denom = np.sqrt(v) / np.float32(math.sqrt(1 - b2 ** s["step"])) + np.float32(self.EPS)
        return z - np.float32(step_size) * (m / denom)
