"""Wheel zoom toward the point under the mouse, as Blender's "zoom to mouse position".

VTK's camera styles dolly toward the focal point, the centre of the view, wherever the
mouse is. Here a wheel turn scales the camera about the world point under the mouse on
the focal plane: the position and the focal point both move toward it by the same
factor, so that point stays under the mouse, the view's direction is kept and the
distance to the focal point shrinks (or grows) by the factor. The zoom then also moves
the point the camera orbits about toward what the user pointed at.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Distance factor of one wheel notch (120 eighths of a degree): VTK's own wheel dolly
#: (1.1 ** (MotionFactor 10 * 0.2)).
NOTCH_FACTOR = 1.21


def focal_plane_point(renderer: Any, x: float, y: float) -> np.ndarray:
    """The world point ``(3,)`` metres at VTK display pixel ``(x, y)`` (origin bottom
    left) on the plane through the camera's focal point that faces the camera."""
    fp = renderer.GetActiveCamera().GetFocalPoint()
    renderer.SetWorldPoint(*fp, 1.0)
    renderer.WorldToDisplay()
    depth = renderer.GetDisplayPoint()[2]
    renderer.SetDisplayPoint(float(x), float(y), depth)
    renderer.DisplayToWorld()
    w = np.asarray(renderer.GetWorldPoint(), float)
    return w[:3] / w[3]


def zoom_about(camera: Any, point: np.ndarray, factor: float) -> None:
    """Scale the ``camera`` about ``point (3,)``: distances to the focal point divided by
    ``factor`` (> 1 zooms in), ``point`` kept where it is on screen."""
    p = np.asarray(point, float)
    pos, fp = np.asarray(camera.GetPosition(), float), np.asarray(camera.GetFocalPoint(), float)
    camera.SetPosition(*(p + (pos - p) / factor))
    camera.SetFocalPoint(*(p + (fp - p) / factor))


class WheelZoom:
    """Zooms ``plotter``'s camera toward the mouse on each Qt wheel event handed to
    :meth:`wheel` (the viewport's event filter takes them before VTK's style)."""

    def __init__(self, plotter: Any) -> None:
        self._plotter = plotter

    def wheel(self, event: Any) -> None:
        """Zoom for a ``QWheelEvent`` on the plotter's widget: ``angleDelta`` in eighths
        of a degree (a notch is 120; a touchpad sends less), at the event's position."""
        notches = event.angleDelta().y() / 120.0
        if notches == 0:
            return
        widget = self._plotter
        ratio = widget.devicePixelRatioF()
        pos = event.position()
        x, y = pos.x() * ratio, (widget.height() - pos.y() - 1) * ratio
        self.zoom_at(x, y, NOTCH_FACTOR**notches)

    def zoom_at(self, x: float, y: float, factor: float) -> None:
        """Zoom by ``factor`` toward VTK display pixel ``(x, y)`` and draw."""
        renderer = self._plotter.renderer
        zoom_about(renderer.GetActiveCamera(), focal_plane_point(renderer, x, y), factor)
        renderer.ResetCameraClippingRange()
        self._plotter.render()
