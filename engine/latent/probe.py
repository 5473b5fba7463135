"""Latent debugging of a running method, frame by frame: what the CLI's ``latent``
report and the studio's latent map read after each solved frame.

:class:`LatentProbe` holds the shipped latent map and the pose bank's latents; after a
method's step, :meth:`LatentProbe.frame` turns the frame's latent and (for a method that
keeps one, :class:`SolvesInLatent`) its :class:`~engine.methods.solve_record.SolveRecord` into a
:class:`FrameProbe` of plain numpy data.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from engine.errors import UserError
from engine.latent.projection import LatentMap, default_map
from engine.latent.readouts import NearestLatents, bank_latents, flag

if TYPE_CHECKING:
    from engine.methods.solve_record import SolveRecord
    from engine.solver.optimizer import PoseOptimizer

#: What the studio and the CLI say for a method without a latent space.
NO_LATENT = (
    "{method} has no latent space: latent debugging needs DragPoser (IK, SparsePoser and RPM pose the body directly)"
)


@runtime_checkable
class SolvesInLatent(Protocol):
    """A method that solves each frame in the VAE's latent space and keeps the last solve
    (DragPoser)."""

    last_solve: "SolveRecord | None"
    optimizer: "PoseOptimizer"


@dataclass(frozen=True)
class FrameProbe:
    """One frame seen from the latent space.

    Attributes
    ----------
    frame : int
    latent : ndarray (L,)
        The frame's solution.
    xy : ndarray (2,)
        Its place on the map.
    prior : ndarray (L,) or None
        The frame's prior latent (temporal predictor or pose bank), if any.
    start : str
        Where the solve started (:data:`engine.methods.solve_record.STARTS`), "" when unknown.
    path_xy : ndarray (K, 2) or None
        The solve's iterations on the map, start first.
    nearest, norm, predictor : float
        Prior readouts (:mod:`engine.latent.readouts`; ``predictor`` NaN without a prior).
    flagged : bool
    """

    frame: int
    latent: np.ndarray
    xy: np.ndarray
    prior: np.ndarray | None
    start: str
    path_xy: np.ndarray | None
    nearest: float
    norm: float
    predictor: float
    flagged: bool

    def readouts(self) -> dict[str, float]:
        """The readouts by name (``flagged`` 0.0 / 1.0)."""
        return {"nearest": self.nearest, "norm": self.norm, "predictor": self.predictor, "flagged": float(self.flagged)}


class LatentProbe:
    """Per-frame readouts and map coordinates (module doc).

    Parameters
    ----------
    latent_map : LatentMap
    search : NearestLatents
        The training latents the ``nearest`` readout searches.
    """

    def __init__(self, latent_map: LatentMap, search: NearestLatents) -> None:
        self.map = latent_map
        self.search = search

    @classmethod
    def shipped(cls) -> "LatentProbe":
        """With the shipped map and pose bank.

        Raises
        ------
        UserError
            When ``assets/models/latent_map.npz`` is missing or belongs to another VAE.
        """
        m = default_map()
        if m is None:
            raise UserError(
                "assets/models/latent_map.npz is missing or was made for another VAE "
                "(scripts/build_latent_map.py makes it)"
            )
        return cls(m, NearestLatents(bank_latents()))

    def frame(self, frame: int, latent: np.ndarray, record: "SolveRecord | None" = None) -> FrameProbe:
        """The probe of a solved frame whose latent is ``latent (L,)``; ``record`` adds the
        prior latent, the start and the iteration path."""
        z = np.asarray(latent, dtype=np.float64).ravel()
        nearest, _ = self.search.query(z)
        norm = float(np.linalg.norm(z))
        prior, start, path_xy = None, "", None
        if record is not None:
            start = record.start
            p = record.context.prediction
            prior = None if p is None else p.detach().double().numpy().ravel()
            path = getattr(record.solution, "path", None)
            if path is not None:
                path_xy = self.map.project(np.asarray(path, dtype=np.float64))
        predictor = float(np.linalg.norm(prior - z)) if prior is not None else float("nan")
        flagged = bool(flag(self.map, np.array([nearest]), np.array([norm]))[0])
        return FrameProbe(
            frame, z, self.map.project(z), prior, start, path_xy, float(nearest), norm, predictor, flagged
        )

    def after_step(self, method: object, frame: int, latent: np.ndarray | None) -> FrameProbe | None:
        """:meth:`frame` for a method just stepped (its :class:`SolvesInLatent` record
        when it keeps one of this very latent: a frame solved another way, e.g. in a
        batched offline window, has none); None when the frame has no latent."""
        if latent is None:
            return None
        record = method.last_solve if isinstance(method, SolvesInLatent) else None
        if record is not None and not np.array_equal(
            record.solution.latent.detach().double().numpy().ravel(), np.asarray(latent, dtype=np.float64).ravel()
        ):
            record = None
        return self.frame(frame, latent, record)
