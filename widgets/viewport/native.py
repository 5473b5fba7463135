"""A pyvista plotter in a *native* child window (VTK renders straight to X11).

pyvistaqt's ``QtInteractor`` is a ``QOpenGLWidget``: Qt then composites the whole
top-level window through OpenGL on every repaint of *any* widget in it. On software
OpenGL (Xvfb, llvmpipe) that composition costs tens to hundreds of milliseconds, so a
status-bar label or a plot update costs as much as a 3D frame. VTK's own
``QVTKRenderWindowInteractor`` (``QWidget`` base) gives VTK a native window of its own;
the rest of the window stays a plain raster window. This class puts pyvista's plotter
API on that widget, the way pyvistaqt's ``QtInteractor`` does on its own.

VTK (9.1 and later) renders into a framebuffer of its own and, at the end of each
frame, copies it to the window. Its default copy (``BlitToHardware``) also writes the
depth buffer to the window, through a full-screen shader: on Mesa's software rasterizer
that costs about as much as the rest of the frame (measured on this view at 988 x 626:
15 ms per render with it, 8 ms without). Nothing reads the window's depth (picking,
screenshots and the widgets read VTK's own framebuffers), so this window copies the
colour only (``BlitToCurrent``: the current draw buffer is the window's back buffer).
"""

from __future__ import annotations

import contextlib
from typing import Any

from PyQt6.QtCore import Qt
from PyQt6.QtGui import QGuiApplication
from pyvista import global_theme
from pyvista.plotting.plotter import BasePlotter
from pyvista.plotting.render_window_interactor import RenderWindowInteractor
from pyvistaqt import QtInteractor
from vtkmodules.qt.QVTKRenderWindowInteractor import QVTKRenderWindowInteractor


def make_plotter(parent: Any) -> Any:
    """The 3D view's plotter: a native child window on X11 (see the module doc), else
    pyvistaqt's ``QtInteractor`` (Wayland, macOS, Windows, offscreen), which needs no
    native window handle."""
    if QGuiApplication.platformName() == "xcb":
        # by default Qt makes the siblings of a native widget native too (every widget
        # along the way: dock tab bars, separators); such a window kept a stale position
        # and showed a "Latent | Live trackers" tab bar over the 3D view
        QGuiApplication.setAttribute(Qt.ApplicationAttribute.AA_DontCreateNativeWidgetSiblings)
        return NativeInteractor(parent, multi_samples=0)
    return QtInteractor(parent, auto_update=False, multi_samples=0)


class NativeInteractor(QVTKRenderWindowInteractor, BasePlotter):
    """pyvista plotter embedded as a native child window; ``render()`` draws at once.

    Parameters
    ----------
    parent : QWidget
        Parent widget.
    multi_samples : int
        MSAA samples (0 or 1 = none: software GL pays heavily for anti-aliasing).
    """

    def __init__(self, parent: Any = None, multi_samples: int = 0) -> None:
        QVTKRenderWindowInteractor.__init__(self, parent)
        BasePlotter.__init__(self)
        self.setAcceptDrops(True)  # the viewport filters drops (a .bvh opens the clip)
        self.interactor = self
        self.ren_win = self.GetRenderWindow()
        self.ren_win.SetMultiSamples(multi_samples)
        self.ren_win.SetFrameBlitModeToBlitToCurrent()  # colour only (see the module doc)
        for renderer in self.renderers:
            renderer.view_isometric()
            self.ren_win.AddRenderer(renderer)
        self.background_color = global_theme.background
        self._off_screen = False
        self.iren = RenderWindowInteractor(self, interactor=self.ren_win.GetInteractor())
        self.iren.interactor.RemoveObservers("MouseMoveEvent")
        self.iren.initialize()
        self.enable_trackball_style()
        self._first_time = False  # BasePlotter: this window renders itself
        # Until the first show nothing is on screen, and that show's paint event draws the
        # whole scene: the renders asked for while the window is built (one per actor
        # added, the camera's placement, the busy notice) would each draw a frame nobody
        # sees (15 of them, about 0.15 CPU s on software GL, before the studio's window appears).
        self.suppress_rendering = True

    def showEvent(self, event: Any) -> None:  # noqa: N802 (Qt's name)
        """Render from now on (the paint event of this show draws the first frame)."""
        self.suppress_rendering = False
        super().showEvent(event)

    def render(self) -> None:
        if getattr(self, "_closed", False):
            return
        self._rendered = True
        BasePlotter.render(self)

    def close(self) -> None:  # type: ignore[override]
        """Finalize the render window and release the interactor (idempotent)."""
        if getattr(self, "_closed", True):
            return
        render_window = self.GetRenderWindow()
        BasePlotter.close(self)
        QVTKRenderWindowInteractor.close(self)
        # release the X window and VTK's own display connection now, while the X server
        # is surely there (a test display may be gone by interpreter exit)
        render_window.Finalize()
        self._Iren.SetRenderWindow(None)
        for key in ("_RenderWindow",):
            with contextlib.suppress(AttributeError):
                setattr(self, key, None)
