"""Fitting the small perceptrons of :class:`engine.models.perceptron.Perceptron` (the stance
classifier, the heading network): standardised inputs, two hidden ReLU layers, Adam, shuffled
batches, everything seeded so a command reproduces its file bit for bit."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def fit_perceptron(
    x: np.ndarray,
    y: np.ndarray,
    loss: Callable,
    hidden: int,
    epochs: int,
    lr: float,
    seed: int = 0,
    cosine: bool = False,
    batch: int = 512,
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """Fit ``loss(outputs (B, O), targets (B, ...)) -> scalar tensor`` over inputs ``x (N, D)``
    and targets ``y (N, ...)`` (O: ``y``'s last size, 1 for a vector); Adam (weight decay
    1e-4), its rate annealed to 0 along a cosine over all steps when ``cosine``.

    Returns
    -------
    mean, std : ndarray (D,)
        The input standardisation (float64; ``std`` plus 1e-6).
    weights, biases : tuple of ndarray
        The three layers, ``x @ w + b`` (float64).
    """
    import torch

    torch.manual_seed(seed)
    mean = x.mean(0, dtype=np.float64)
    std = x.std(0, dtype=np.float64) + 1e-6
    xt = torch.as_tensor((x - mean) / std, dtype=torch.float32)
    yt = torch.as_tensor(y, dtype=torch.float32)
    net = torch.nn.Sequential(
        torch.nn.Linear(x.shape[1], hidden),
        torch.nn.ReLU(),
        torch.nn.Linear(hidden, hidden),
        torch.nn.ReLU(),
        torch.nn.Linear(hidden, 1 if y.ndim == 1 else y.shape[-1]),
    )
    opt = torch.optim.Adam(net.parameters(), lr=lr, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, epochs * -(-len(xt) // batch)) if cosine else None
    gen = torch.Generator().manual_seed(seed)
    for _ in range(epochs):
        order = torch.randperm(len(xt), generator=gen)
        for i in range(0, len(xt), batch):
            b = order[i : i + batch]
            value = loss(net(xt[b]), yt[b])
            opt.zero_grad()
            value.backward()
            opt.step()
            if sched is not None:
                sched.step()
    layers = [m for m in net if isinstance(m, torch.nn.Linear)]
    return (
        mean,
        std,
        tuple(m.weight.detach().double().numpy().T.copy() for m in layers),
        tuple(m.bias.detach().double().numpy().copy() for m in layers),
    )
