"""The ``latent`` command's outputs: a PNG report and a JSON file of a :class:`LatentTrace`.

The figure (matplotlib's Agg canvas, no GUI toolkit) has the latent map on the left,
with the training density (log scale), the clip's trajectory coloured by frame, the
flagged frames (red crosses) and the iteration path of the frame farthest from the
training latents, labelled by where its solve started; on the right the readouts over
time with the flag thresholds dashed and the flagged frames shaded, and the per-frame
position error.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from engine.atomic import write_bytes, write_text
from engine.latent.projection import LatentMap
from engine.latent.trace import LatentTrace

#: Figure size, inches, at :data:`DPI`: a 1200 x 700 pixel image.
SIZE = (12.0, 7.0)
DPI = 100
FLAG = "#d62728"


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``[start, end)`` index runs where ``flags`` is true."""
    f = np.concatenate([[False], np.asarray(flags, bool), [False]])
    edges = np.flatnonzero(np.diff(f.astype(int)))
    return list(zip(edges[::2], edges[1::2]))


def render_report(trace: LatentTrace, latent_map: LatentMap, out: str | Path, method: str = "dragposer") -> None:
    """Draw the report of ``trace`` on ``latent_map`` to the PNG ``out`` (atomically)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=SIZE, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(4, 2, width_ratios=(1.0, 1.15))
    _draw_map(fig.add_subplot(grid[:, 0]), fig, trace, latent_map)
    frames = np.array([p.frame for p in trace.probes])
    flags = trace.column("flagged") > 0
    rows = (
        ("nearest", "nearest training\nlatent", latent_map.nn_threshold),
        ("norm", "latent norm", latent_map.norm_threshold),
        ("predictor", "prior latent to\nsolution", None),
    )
    axes: list[Any] = []
    for r, (key, label, threshold) in enumerate(rows):
        ax = fig.add_subplot(grid[r, 1], sharex=axes[0] if axes else None)
        ax.plot(frames, trace.column(key), lw=1.0, color="#1f77b4")
        if threshold is not None and np.isfinite(threshold):
            ax.axhline(threshold, ls="--", lw=0.8, color=FLAG, label="flag threshold")
        ax.set_ylabel(label, fontsize=8)
        axes.append(ax)
    ax = fig.add_subplot(grid[3, 1], sharex=axes[0])
    if len(trace.pos_cm):
        ax.plot(frames, trace.pos_cm, lw=1.0, color="#2ca02c")
    ax.set_ylabel("Pos error cm", fontsize=8)
    ax.set_xlabel("frame")
    axes.append(ax)
    for a in axes:
        for s, e in _runs(flags):
            a.axvspan(frames[s] - 0.5, frames[e - 1] + 0.5, color=FLAG, alpha=0.18, lw=0)
        a.tick_params(labelsize=7)
    axes[0].legend(fontsize=7, loc="upper right")
    corr = trace.correlation("nearest")
    axes[0].set_title(
        f"{trace.name} ({method}): {len(trace.flagged_frames)} of {len(frames)} frames flagged; "
        f"nearest vs Pos error r = {corr['pearson']:.2f}",
        fontsize=9,
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    write_bytes(out, buf.getvalue())


def _draw_map(ax: Any, fig: Any, trace: LatentTrace, m: LatentMap) -> None:
    """The map panel (module doc)."""
    ax.imshow(
        np.log1p(m.density),
        extent=tuple(m.extent),
        origin="lower",
        cmap="Greys",
        aspect="auto",
        interpolation="bilinear",
    )
    xy = trace.xy
    frames = np.arange(len(xy))
    ax.plot(xy[:, 0], xy[:, 1], lw=0.5, color="#888888", alpha=0.6)
    sc = ax.scatter(xy[:, 0], xy[:, 1], c=frames, cmap="viridis", s=9, zorder=3)
    fig.colorbar(sc, ax=ax, label="frame", shrink=0.8)
    flagged = trace.column("flagged") > 0
    if flagged.any():
        ax.scatter(xy[flagged, 0], xy[flagged, 1], marker="x", color=FLAG, s=30, zorder=4, label="flagged")
    worst = int(np.nanargmax(trace.column("nearest"))) if len(xy) else -1
    path = trace.probes[worst].path_xy if worst >= 0 else None
    if path is not None and len(path) > 1:
        ax.plot(
            path[:, 0],
            path[:, 1],
            "-o",
            ms=2.5,
            lw=1.0,
            color="#ff7f0e",
            zorder=5,
            label=f"frame {trace.probes[worst].frame}: iterations",
        )
        ax.annotate(
            f"start ({trace.probes[worst].start})",
            path[0],
            fontsize=7,
            color="#ff7f0e",
            xytext=(4, 4),
            textcoords="offset points",
        )
    ax.set_xlim(m.extent[0], m.extent[1])
    ax.set_ylim(m.extent[2], m.extent[3])
    ax.set_xlabel(f"PC 1 ({100 * m.explained[0]:.1f} % of variance)")
    ax.set_ylabel(f"PC 2 ({100 * m.explained[1]:.1f} % of variance)")
    ax.set_title("Latent map: training density (grey), clip by frame", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="lower right")


def write_json(trace: LatentTrace, latent_map: LatentMap, out: str | Path, method: str = "dragposer") -> None:
    """Write the trace's summary, the map's figures and every frame's readouts as JSON."""
    doc = {
        "method": method,
        "map": {
            "explained": latent_map.explained.tolist(),
            "nn_threshold": latent_map.nn_threshold,
            "norm_threshold": latent_map.norm_threshold,
        },
        "summary": trace.summary(),
        "frames": trace.frames_json(),
    }
    write_text(out, json.dumps(doc, indent=1, allow_nan=False) + "\n")
