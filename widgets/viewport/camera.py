"""Camera presets of the 3D view, around a focus point on the character.

The canonical character faces -Y with its left side to +X and Z up (see
:mod:`engine.skeleton`), so *front* looks from -Y, *side* from the character's left
(+X) and *top* straight down with the character's forward pointing down the screen.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: preset -> (camera offset from the focus in metres, view-up vector)
CAMERA_PRESETS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "home": ((2.0, -3.4, 0.5), (0.0, 0.0, 1.0)),
    "front": ((0.0, -4.0, 0.2), (0.0, 0.0, 1.0)),
    "side": ((4.0, 0.0, 0.2), (0.0, 0.0, 1.0)),
    "top": ((0.0, 0.0, 5.0), (0.0, 1.0, 0.0)),
}
VIEW_ANGLE_DEG = 35.0


def place_camera(camera: Any, preset: str, focus: np.ndarray) -> None:
    """Point a VTK/PyVista ``camera`` at ``focus`` (3,) metres from ``preset``'s direction."""
    offset, up = CAMERA_PRESETS[preset]
    camera.focal_point = tuple(float(v) for v in focus)
    camera.position = tuple(float(v) for v in np.asarray(focus, float) + offset)
    camera.up = up
    camera.view_angle = VIEW_ANGLE_DEG
