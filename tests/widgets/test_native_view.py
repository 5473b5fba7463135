"""On X11 the 3D view is a native child window, so the rest of the window stays raster.

With pyvistaqt's QOpenGLWidget, Qt composites the whole window through (software) OpenGL
whenever any widget in it repaints; a status-bar label then cost as much as a 3D frame.
"""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture
def native_view(qtbot):
    """A shown 640x480 viewport on X11 (skips elsewhere); closed afterwards."""
    from PyQt6.QtGui import QGuiApplication

    from widgets.viewport import Viewport

    if QGuiApplication.platformName() != "xcb":
        pytest.skip("the native-window view is the X11 choice")
    v = Viewport()
    v.resize(640, 480)
    v.show()
    qtbot.waitExposed(v)
    yield v
    v.close()
    assert v.plotter._closed


def test_the_view_renders_in_a_native_window_on_x11_and_draws_the_skeleton(native_view, fake_snapshot):
    from PyQt6.QtCore import Qt
    from PyQt6.QtOpenGLWidgets import QOpenGLWidget

    from tests.widgets.test_viewport import orange_fraction
    from widgets.viewport.native import NativeInteractor

    v = native_view
    assert isinstance(v.plotter, NativeInteractor) and not isinstance(v.plotter, QOpenGLWidget)
    assert v.plotter.testAttribute(Qt.WidgetAttribute.WA_NativeWindow)
    v.show_snapshot(fake_snapshot())
    img = v.plotter.screenshot(return_img=True)
    assert orange_fraction(np.asarray(img)) > 0.001


def test_the_native_view_copies_colour_only_to_the_window_and_the_screen_shows_the_skeleton(
    native_view, qtbot, fake_snapshot
):
    """VTK's default end-of-frame copy also writes depth to the window through a
    full-screen shader (about half of a draw on Mesa's software rasterizer); the view
    copies colour only, and what X shows must still be the scene, not VTK's buffer alone."""
    import vtk
    from PyQt6.QtGui import QGuiApplication

    from tests.widgets.test_viewport import orange_fraction

    v = native_view
    window = v.plotter.render_window
    assert window.GetFrameBlitMode() == vtk.vtkOpenGLRenderWindow.BlitToCurrent
    v.show_snapshot(fake_snapshot())
    window.WaitForCompletion()
    qtbot.wait(50)
    shot = QGuiApplication.primaryScreen().grabWindow(int(v.plotter.winId())).toImage()
    shot = shot.convertToFormat(shot.Format.Format_RGB888)
    w, h = shot.width(), shot.height()
    img = np.frombuffer(shot.constBits().asstring(shot.bytesPerLine() * h), np.uint8)
    img = img.reshape(h, shot.bytesPerLine())[:, : 3 * w].reshape(h, w, 3)
    assert orange_fraction(img) > 0.001  # read back from the X server, not from VTK


def test_the_native_view_draws_nothing_before_its_first_show_and_then_the_scene(qtbot, monkeypatch, fake_snapshot):
    """Building the view adds a dozen actors and places the camera, each of which asked
    for a render of a window not on screen yet; the first show's paint draws the scene."""
    from PyQt6.QtGui import QGuiApplication

    import widgets.viewport.viewport as viewport_module
    from tests.widgets.test_viewport import orange_fraction
    from widgets.viewport import Viewport

    if QGuiApplication.platformName() != "xcb":
        pytest.skip("the native-window view is the X11 choice")
    renders = []
    make = viewport_module.make_plotter

    def counted(parent):
        plotter = make(parent)
        plotter.render_window.AddObserver("StartEvent", lambda *_: renders.append(1))
        return plotter

    monkeypatch.setattr(viewport_module, "make_plotter", counted)
    v = Viewport()
    v.set_notice("loading")
    v.show_clip_frame(fake_snapshot().positions)
    assert renders == []
    v.resize(640, 480)
    v.show()
    qtbot.waitExposed(v)
    try:
        v.show_snapshot(fake_snapshot())
        assert renders
        assert orange_fraction(np.asarray(v.plotter.screenshot(return_img=True))) > 0.001
    finally:
        v.close()
