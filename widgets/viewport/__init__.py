"""The 3D viewport: a held pyvistaqt interactor plus one adapter class per drawable."""

from widgets.viewport.viewport import Viewport

__all__ = ["Viewport"]
