"""Colours shared by the viewport, the plots and the panels (one palette, one place)."""

from __future__ import annotations

#: Reconstruction of the selected method.
RECONSTRUCTION = "#ff8a1f"
#: Ground truth of the loaded clip (green, as in the DragPoser paper's figures).
GROUND_TRUTH = "#3fae55"
#: Other methods drawn as ghosts, by name; unknown names cycle through GHOST_CYCLE.
GHOSTS = {"ik": "#4da3ff", "autoencoder": "#c77dff", "dragposer": "#ff8a1f", "sparseposer": "#ff5fa2",
          "rpm": "#ffd60a"}
GHOST_CYCLE = ("#4da3ff", "#c77dff", "#ffd60a", "#ff5fa2")
SENSOR = "#ffe14d"
SENSOR_LOST = "#ff3b30"
GIZMO = "#00e5ff"
BACKGROUND_TOP = "#2b2f3a"
BACKGROUND_BOTTOM = "#12141a"
FLOOR = "#3a4150"
FLOOR_PLANE = "#1b1e25"
PLOT_BACKGROUND = "#171a21"
PLOT_FOREGROUND = "#c8ccd4"
#: Loss-term curves, in order of first appearance.
TERM_CYCLE = (
    "#ff8a1f", "#4da3ff", "#4cd964", "#c77dff", "#ffd60a", "#ff5fa2", "#00e5ff",
    "#b0b8c8", "#ff3b30", "#a0e515",
)  # fmt: skip


def ghost_color(name: str, index: int = 0) -> str:
    return GHOSTS.get(name, GHOST_CYCLE[index % len(GHOST_CYCLE)])


def hex_to_rgb(color: str) -> tuple[int, int, int]:
    c = color.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)
