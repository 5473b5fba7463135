"""Latent update rules (Adam, gradient steps with optional Nesterov momentum), numpy.

The same arithmetic as ``torch.optim.Adam`` / ``torch.optim.SGD`` on one float32
vector (a test checks it step by step), without the optimizer object's per-step
overhead, and shared by the solver's fast and reference paths.
"""

from __future__ import annotations

import math

import numpy as np


class LatentUpdate:
    """One update rule's state for latents ``(..., L)``: one latent frame by frame, or a
    row per frame of the batched solve (:meth:`step_rows`), each row with its own moments
    and step count.

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
        b1, b2 = self.BETAS
        self._factors = (np.float32(1 - b1), np.float32(b2), np.float32(1 - b2), np.float32(self.EPS))

    def step(self, z: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """The next latents (new array, float32) of ``z`` with gradients ``grad``, same shape."""
        grad = grad.astype(np.float32, copy=False)
        if self.rule == "sgd":
            if self.momentum > 0:
                buf = self.state.get("momentum_buffer")
                buf = grad.copy() if buf is None else buf * np.float32(self.momentum) + grad
                self.state["momentum_buffer"] = buf
                grad = grad + np.float32(self.momentum) * buf
            return z - np.float32(self.lr) * grad
        s = self.state
        if not s:
            s.update(step=np.zeros(z.shape[:-1]), exp_avg=np.zeros_like(z), exp_avg_sq=np.zeros_like(z))
        s["step"] = s["step"] + 1
        return z - self._adam(s["exp_avg"], s["exp_avg_sq"], grad, s["step"])

    def step_rows(self, z: np.ndarray, grad: np.ndarray, rows: np.ndarray) -> None:
        """Step rows ``rows`` of ``z (C, L)`` in place with their gradients ``grad (len(rows), L)``;
        the state holds every row (plain steps keep none)."""
        grad = grad.astype(np.float32, copy=False)
        if self.rule == "sgd":
            z[rows] -= np.float32(self.lr) * grad
            return
        s = self.state
        if not s:
            s.update(step=np.zeros(len(z)), exp_avg=np.zeros_like(z), exp_avg_sq=np.zeros_like(z))
        s["step"][rows] += 1
        m, v = s["exp_avg"][rows], s["exp_avg_sq"][rows]
        z[rows] -= self._adam(m, v, grad, s["step"][rows])
        s["exp_avg"][rows], s["exp_avg_sq"][rows] = m, v

    def restart_row(self, row: int) -> None:
        """Row ``row`` starts with fresh moments (rule ``adam``: a new frame)."""
        if self.state:
            self.state["step"][row] = 0
            self.state["exp_avg"][row] = 0.0
            self.state["exp_avg_sq"][row] = 0.0

    def _adam(self, m: np.ndarray, v: np.ndarray, grad: np.ndarray, n: float | np.ndarray) -> np.ndarray:
        """Adam's step for moments ``m``, ``v`` (updated in place with ``grad``) at step
        counts ``n`` (one, or one per row): in place, with the float32 factors made once
        (a dozen numpy calls for one latent, which every realtime iteration takes)."""
        c1, c2, c3, eps = self._factors
        t = grad - m
        t *= c1
        m += t  # m + (1 - b1) (g - m)
        v *= c2
        np.multiply(c3, grad, out=t)
        t *= grad
        v += t  # b2 v + (1 - b2) g g
        b1, b2 = self.BETAS
        root: np.floating | np.ndarray
        size: np.floating | np.ndarray
        if isinstance(n, float):  # one latent: the same float64 factors as scalars (fewer numpy calls)
            one = float(n)
            root, size = np.float32(math.sqrt(1 - b2**one)), np.float32(self.lr / (1 - b1**one))
        else:
            k = np.asarray(n, dtype=np.float64)[..., None]
            root, size = np.sqrt(1 - b2**k).astype(np.float32), (self.lr / (1 - b1**k)).astype(np.float32)
        d = np.sqrt(v)
        d /= root
        d += eps
        np.divide(m, d, out=d)
        d *= size
        return d
