"""The engine thread's latent-debugging state: a :class:`LatentView` per solved frame and,
on request, a :class:`LatentDetail` of the frame on screen (:mod:`engine.studio.latent_views`).

The readouts cost about half a millisecond a frame (one nearest-neighbour search among
the bank's 96 072 latents), so they run on every frame of a latent-space method; the
forces and the sweep (about a second) only when the studio asks.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from engine.progress import CancelCheck, Cancelled
from engine.studio.latent_views import LatentDetail, LatentView

#: The note when the map file cannot be used (the studio shows it in the map panel).
NO_MAP = "no latent map: assets/models/latent_map.npz is missing or belongs to another VAE"


class LatentDebug:
    """See the module doc. ``view`` and ``detail`` are what the next snapshot carries;
    ``note`` says why there is none."""

    def __init__(self) -> None:
        self._probe: Any = None
        self._probe_failed = ""
        self.view: LatentView | None = None
        self.detail: LatentDetail | None = None
        self.note = ""

    def _get_probe(self) -> Any:
        if self._probe is None and not self._probe_failed:
            from engine.errors import UserError
            from engine.latent.probe import LatentProbe

            try:
                self._probe = LatentProbe.shipped()
            except UserError:
                self._probe_failed = NO_MAP
        return self._probe

    def after_solve(self, method: Any, frame: int, latent: np.ndarray | None) -> LatentView | None:
        """The view of the frame ``method`` just solved (None without a latent; ``note``
        then says why). Drops the previous frame's detail."""
        from engine.latent.probe import NO_LATENT

        self.detail = None
        self.view = None
        if latent is None:
            self.note = NO_LATENT.format(method=getattr(method, "name", "this method"))
            return None
        probe = self._get_probe()
        if probe is None or np.size(latent) != probe.map.latent_dim:
            self.note = (
                self._probe_failed or f"latent of size {np.size(latent)}: the latent map is {probe.map.latent_dim}-D"
            )
            return None
        p = probe.after_step(method, frame, latent)
        self.note = ""
        self.view = LatentView(
            frame,
            np.asarray(p.latent, float),
            np.asarray(p.xy, float),
            p.path_xy,
            p.start,
            p.nearest,
            p.norm,
            p.predictor,
            p.flagged,
        )
        return self.view

    def inspect(self, method: Any, joint: str = "", cancelled: CancelCheck | None = None) -> str:
        """Compute the :class:`LatentDetail` of the last solved frame; returns an error
        message ("" when done). ``cancelled()`` is asked between the forces' steps and the
        sweep's dimensions: True stops the work (about a second, several on a busy machine)
        and leaves the detail as it was."""
        from engine.latent.forces import record_forces
        from engine.latent.probe import NO_LATENT, SolvesInLatent
        from engine.latent.sweep import dimension_sweep, joint_influence

        if not isinstance(method, SolvesInLatent) or method.last_solve is None:
            return NO_LATENT.format(method=getattr(method, "name", "this method"))
        probe = self._get_probe()
        if probe is None or self.view is None:
            return self._probe_failed or "no solved frame to inspect yet"
        t0 = time.perf_counter()
        rec = method.last_solve
        try:
            f = record_forces(method.optimizer, rec, probe.map, cancelled)
            sweep = dimension_sweep(
                method.optimizer, rec.context, self.view.latent, probe.map.sigma, cancelled=cancelled
            )
        except Cancelled:
            return "cancelled"
        assert f.plane is not None  # projected on probe.map
        influence = joint_influence(method.optimizer, rec.context, self.view.latent, joint) if joint else None
        self.detail = LatentDetail(
            self.view.frame,
            f.names,
            f.forces,
            f.plane,
            sweep.poses,
            sweep.motion,
            joint,
            influence,
            1000.0 * (time.perf_counter() - t0),
        )
        return ""
