"""What the engine publishes for the studio's latent-debugging views (plain numpy data;
computed by :mod:`engine.studio.latent_debug`, drawn by ``widgets/latent_*``).

* :class:`LatentView` — every solved frame of a latent-space method: its place on the
  latent map, its solve's iteration path, the prior readouts and the flag.
* :class:`LatentDetail` — on request (:class:`~engine.studio.commands.InspectLatent`),
  for the frame on screen: the term forces along its solve, the dimension sweep and,
  for a chosen joint, each dimension's influence on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LatentView:
    """One solved frame seen from the latent space.

    Attributes
    ----------
    frame : int
    latent : ndarray (L,)
    xy : ndarray (2,)
        Map coordinates of the frame's latent.
    path_xy : ndarray (K, 2) or None
        The solve's iterations on the map, start first (None: not recorded).
    start : str
        Where the solve started (``predictor``, ``pose bank``, ``previous frame``,
        ``zero latent``; "" unknown).
    nearest, norm, predictor : float
        Prior readouts (docs/latent.md; ``predictor`` NaN without a prior latent).
    flagged : bool
        The flag rule's verdict.
    """

    frame: int
    latent: np.ndarray
    xy: np.ndarray
    path_xy: np.ndarray | None
    start: str
    nearest: float
    norm: float
    predictor: float
    flagged: bool

    def readouts(self) -> dict[str, float]:
        """What a history entry keeps: ``x, y, nearest, norm, predictor, flagged`` (0/1)."""
        return {
            "x": float(self.xy[0]),
            "y": float(self.xy[1]),
            "nearest": self.nearest,
            "norm": self.norm,
            "predictor": self.predictor,
            "flagged": float(self.flagged),
        }


@dataclass(frozen=True)
class LatentDetail:
    """The frame on screen, inspected (module doc).

    Attributes
    ----------
    frame : int
    names : tuple of str
        The solve's terms, ``T``.
    forces : ndarray (K, T, L)
        Each term's force (minus the gradient of its weighted loss) at each iteration.
    plane : ndarray (K, T, 2)
        The forces projected on the map plane.
    sweep : ndarray (L, 3, 22, 3)
        World joints, metres, of the latent with dimension ``d`` at -2, 0, +2 sigma.
    motion : ndarray (L, 22)
        How far each joint moves relative to the root in each dimension's sweep, metres.
    joint : str
        The joint ``influence`` is about ("" none).
    influence : ndarray (L,) or None
        Norm of d position(joint) / d z_d, metres per latent unit.
    ms : float
        Time the inspection took on the engine.
    """

    frame: int
    names: tuple[str, ...]
    forces: np.ndarray
    plane: np.ndarray
    sweep: np.ndarray
    motion: np.ndarray
    joint: str = ""
    influence: np.ndarray | None = None
    ms: float = 0.0
