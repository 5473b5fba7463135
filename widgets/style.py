"""Colours shared by the viewport, the plots and the panels (one palette, one place)."""

from __future__ import annotations

import colorsys

#: Reconstruction of the selected method.
RECONSTRUCTION = "#ff8a1f"
#: Ground truth of the loaded clip (green, as in the DragPoser paper's figures).
GROUND_TRUTH = "#3fae55"
#: Other methods drawn as ghosts, by name; unknown names cycle through GHOST_CYCLE.
GHOSTS = {"ik": "#4da3ff", "autoencoder": "#c77dff", "dragposer": "#ff8a1f", "sparseposer": "#ff5fa2", "rpm": "#ffd60a"}
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


def term_colour(index: int) -> str:
    """The ``index``-th loss term's colour (in order of first appearance).

    Hues step by the golden angle (137.5 degrees), so any number of terms get distinct
    colours and each new one lands far from the last; saturation and brightness
    alternate too. A cycle of ten repeated itself from the eleventh term (a look-at and
    the hips' sensor were both blue with six trackers, a floor and a distance).
    """
    hue = (0.08 + index * 0.381966) % 1.0
    sat = 0.72 if index % 3 else 0.55
    val = 1.0 if index % 2 == 0 else 0.82
    r, g, b = colorsys.hsv_to_rgb(hue, sat, val)
    return "#{:02x}{:02x}{:02x}".format(*(int(round(255 * c)) for c in (r, g, b)))


def ghost_color(name: str, index: int = 0) -> str:
    return GHOSTS.get(name, GHOST_CYCLE[index % len(GHOST_CYCLE)])


def hex_to_rgb(color: str) -> tuple[int, int, int]:
    c = color.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)


def hex_to_unit_rgb(color: str) -> tuple[float, float, float]:
    """``color`` as VTK takes it: red, green, blue in 0-1."""
    r, g, b = hex_to_rgb(color)
    return r / 255.0, g / 255.0, b / 255.0
