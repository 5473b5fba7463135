"""A clip's reconstruction traced through the latent space, frame by frame: what the
``latent`` command draws and writes (:mod:`engine.latent.report`).

The method is stepped one frame at a time (never a batched whole-clip solve), so every
frame keeps its solve's record and iteration path.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.errors import UserError
from engine.latent.probe import NO_LATENT, FrameProbe, LatentProbe, SolvesInLatent

if TYPE_CHECKING:
    from engine.methods.base import Method
    from engine.motion.clip import Motion
    from engine.tracking.simulate import Tracking


@dataclass
class LatentTrace:
    """Per-frame latent readouts of one reconstructed clip.

    Attributes
    ----------
    name : str
        The clip's name.
    probes : list of FrameProbe
        One per frame, in order.
    pos_cm : ndarray (F,)
        Each frame's mean joint position error against the ground truth, cm (no root
        alignment, as ``pos_cm`` of ``evaluate``).
    iterations : ndarray (F,) int
    """

    name: str
    probes: list[FrameProbe] = field(default_factory=list)
    pos_cm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def column(self, name: str) -> np.ndarray:
        """A readout (``nearest``, ``norm``, ``predictor``, ``flagged``) of every frame, ``(F,)``."""
        return np.array([getattr(p, name) for p in self.probes], dtype=float)

    @property
    def xy(self) -> np.ndarray:
        """Map coordinates of every frame's latent, ``(F, 2)``."""
        return np.array([p.xy for p in self.probes]).reshape(-1, 2)

    @property
    def flagged_frames(self) -> list[int]:
        return [p.frame for p in self.probes if p.flagged]

    def correlation(self, readout: str = "nearest") -> dict[str, float]:
        """Pearson and Spearman correlation of a readout with :attr:`pos_cm` over the
        frames (NaN with fewer than 3 frames or no spread)."""
        x, y = self.column(readout), np.asarray(self.pos_cm, float)
        ok = np.isfinite(x) & np.isfinite(y)
        x, y = x[ok], y[ok]
        if len(x) < 3 or x.std() == 0 or y.std() == 0:
            return {"pearson": float("nan"), "spearman": float("nan")}
        rank = lambda a: np.argsort(np.argsort(a)).astype(float)  # noqa: E731 (ties are rare in floats)
        return {"pearson": float(np.corrcoef(x, y)[0, 1]), "spearman": float(np.corrcoef(rank(x), rank(y))[0, 1])}

    def summary(self) -> dict[str, Any]:
        """Plain-JSON figures: frames, flagged frames, readout percentiles, correlations."""
        out: dict[str, Any] = {"clip": self.name, "frames": len(self.probes), "flagged": self.flagged_frames}
        for name in ("nearest", "norm", "predictor"):
            col = self.column(name)
            col = col[np.isfinite(col)]
            out[name] = (
                {q: float(np.percentile(col, p)) for q, p in (("p50", 50), ("p90", 90), ("max", 100))}
                if col.size
                else {}
            )
        if len(self.pos_cm):
            out["pos_cm"] = float(np.mean(self.pos_cm))
            out["correlation_nearest_pos"] = self.correlation("nearest")
        return out

    def frames_json(self) -> list[dict[str, Any]]:
        """One plain dict per frame (NaN written as None)."""
        rows = []
        for i, p in enumerate(self.probes):
            row: dict[str, Any] = {
                "frame": p.frame,
                "x": float(p.xy[0]),
                "y": float(p.xy[1]),
                "start": p.start,
                "iterations": int(self.iterations[i]) if len(self.iterations) else 0,
            }
            row.update({k: (None if not np.isfinite(v) else v) for k, v in p.readouts().items()})
            row["flagged"] = bool(p.flagged)
            if len(self.pos_cm):
                row["pos_cm"] = float(self.pos_cm[i])
            rows.append(row)
        return rows


def trace_clip(
    method: "Method", tracking: "Tracking", motion: "Motion", probe: LatentProbe, progress: bool = False
) -> LatentTrace:
    """Reconstruct ``motion``'s simulated ``tracking`` with ``method`` frame by frame and
    probe every frame.

    Raises
    ------
    UserError
        When the method has no latent space (:data:`engine.latent.probe.NO_LATENT`).
    """
    from tqdm import tqdm

    from engine.methods import driver
    from engine.metrics import position_error_cm

    if not isinstance(method, SolvesInLatent):
        raise UserError(NO_LATENT.format(method=method.name))
    driver.reset(method, motion.skeleton, tracking.fps, motion)
    trace = LatentTrace(motion.name)
    rec = np.zeros((len(tracking), 22, 3))
    iters = np.zeros(len(tracking), int)
    for i in tqdm(range(len(tracking)), desc=f"latent {motion.name}", unit="frame", disable=not progress, leave=False):
        res = driver.step(method, tracking.frame(i))
        p = probe.after_step(method, i, res.latent)
        if p is None:
            raise UserError(NO_LATENT.format(method=method.name))
        trace.probes.append(p)
        rec[i], iters[i] = res.positions, res.iterations
    gt, _ = motion.fk()
    trace.pos_cm = position_error_cm(gt[: len(rec)], rec)
    trace.iterations = iters
    return trace
