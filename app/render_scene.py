"""The off-screen scene of ``render``: figures, trackers, legend, title and time code.

Two layouts (``RenderOptions.layout``):

* ``overlay``: the input motion is drawn as the studio draws the reconstruction
  (shaded body or thick sticks, opaque) and each ghost as the studio draws ghosts, a
  thin translucent stick figure in an overlay renderer that shares the camera
  (:class:`widgets.viewport.ghosts.GhostSkeleton`), so no two opaque bodies ever share
  a place.
* ``side``: one panel per figure, left to right, each drawn opaque in its colour,
  all looking through one shared camera (a figure that drifts away from the input
  shows as drifting).

A legend names each figure in its colour (top left; in ``side``, above each panel);
an optional title sits above it and an optional time code bottom right. Trackers are
the studio's :class:`widgets.viewport.sensors.SensorMarkers` (yellow spheres, axes on
6-DoF trackers), in every panel.

The window is set up for throughput on software GL: no multisampling unless asked,
a plain background (a gradient cost ~4 ms a frame at 960x540 under llvmpipe), no
order-independent transparency pass (~4 ms; the only translucent surfaces are the
floor shadows and the ghosts' lines), the studio's two lights, a fixed clipping range
and one ``Render`` per frame, read back into the caller's buffer with no copy.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

VIEWS = ("sticks", "body")
CAMERAS = ("front", "side", "follow")
LAYOUTS = ("overlay", "side")
#: Height of the camera's focus above the floor, metres (about the chest).
FOCUS_HEIGHT = 1.0
#: Near and far clipping planes, metres: the camera stays 2.5-4.5 m from the focus
#: and the floor grid is 10 m across.
CLIPPING = (0.1, 40.0)


@dataclass(frozen=True)
class RenderOptions:
    """What a video shows; the CLI's ``render`` options and the studio's Export video dialog."""

    size: tuple[int, int] = (960, 540)
    sensors: str | None = None
    ghosts: tuple[str, ...] = ()
    view: str = "sticks"
    camera: str = "follow"
    layout: str = "overlay"
    #: The input is the ground truth the trackers come from: green, named so in the legend.
    truth: bool = False
    title: str = ""
    timecode: bool = False
    #: Multisampling (anti-aliasing) samples; 0 is fastest on software GL.
    msaa: int = 0
    #: First and last frame of the motion drawn (inclusive, counted from 0 as the
    #: studio's timeline counts them); None: every frame. The ghosts solve that part
    #: alone, starting at its first frame (:func:`app.render.render_video`).
    frames: tuple[int, int] | None = None


@dataclass
class Figure:
    """One figure of the video: its legend name, its colour, whether it is a ghost (posed
    from the ghosts' solve) or the input, and the drawables that show it."""

    name: str
    color: str
    ghost: bool = False
    drawables: list = field(default_factory=list)


def figure_colours(main: str, ghosts: tuple[str, ...]) -> list[str]:
    """Colours of the ghosts: the studio's colour of each method, or the next unused
    colour of the ghost cycle where that one is taken (DragPoser's orange against the
    orange input)."""
    from widgets import style

    used, out = {main.lower()}, []
    for i, name in enumerate(ghosts):
        colour = style.ghost_color(name, i)
        if colour.lower() in used:
            colour = next((c for c in style.GHOST_CYCLE if c.lower() not in used), colour)
        used.add(colour.lower())
        out.append(colour)
    return out


class FrameRenderer:
    """An off-screen scene of ``motion``; :meth:`draw` poses frame f and renders it once,
    :meth:`read_into` copies the picture into a buffer (rows bottom-up, as GL reads).

    Parameters
    ----------
    motion : engine.motion.clip.Motion
        The input motion (the first figure).
    options : RenderOptions
        Layout, view, camera, trackers, texts (``options.frames`` is not read here: the
        caller hands over the part to draw, see :func:`app.render.render_video`).
    first_frame : int
        The clip's frame number of ``motion``'s first frame (a part of a clip): the time
        code shows the clip's time and frame numbers.
    clip_frames : int or None
        Frames in the whole clip, for the time code's "frame f/last" (None: ``motion``'s).
    """

    def __init__(
        self, motion: Any, options: RenderOptions, first_frame: int = 0, clip_frames: int | None = None
    ) -> None:
        import pyvista as pv
        import vtk

        from widgets import style
        from widgets.viewport.camera import VIEW_ANGLE_DEG

        self.options = o = options
        self.fps = float(motion.fps)
        self.num_frames = len(motion)
        self.first_frame = first_frame
        self.clip_frames = clip_frames if clip_frames is not None else first_frame + len(motion)
        self.positions = motion.positions()
        main = (style.GROUND_TRUTH, "ground truth") if o.truth else (style.RECONSTRUCTION, motion.name or "motion")
        self.figures = [Figure(main[1], main[0])]
        for name, colour in zip(o.ghosts, figure_colours(main[0], o.ghosts)):
            self.figures.append(Figure(name, colour, ghost=True))
        panels = len(self.figures) if o.layout == "side" else 1
        w, h = o.size
        theme = pv.themes.DocumentTheme()
        theme.load_theme(pv.global_theme)
        theme.multi_samples = o.msaa
        self.plotter = pv.Plotter(off_screen=True, window_size=[w, h], shape=(1, panels), border=False, theme=theme)
        self.window = self.plotter.render_window
        self.camera = self.plotter.renderers[0].GetActiveCamera()
        self.camera.SetViewAngle(VIEW_ANGLE_DEG)
        self.trackers = _Trackers(motion, o.sensors) if o.sensors else None
        self.sensor_markers = []
        for panel in range(panels):
            self._build_panel(panel)
        self.overlay = vtk.vtkRenderer()
        self.window.SetNumberOfLayers(2)
        self.overlay.SetLayer(1)
        self.overlay.SetActiveCamera(self.camera)
        self.overlay.InteractiveOff()
        self.overlay.SetUseOIT(False)  # the ghosts are lines: plain blending suffices
        self.window.AddRenderer(self.overlay)
        if o.layout == "overlay":
            from widgets.viewport.ghosts import GhostSkeleton

            for fig in self.figures[1:]:
                fig.drawables.append(GhostSkeleton(self.overlay, fig.color))
        self.texts = _Texts(self.overlay, o, self.figures, panels)
        self._centre = np.array([*self.positions[:, 0, :2].mean(axis=0), FOCUS_HEIGHT])
        self._pixels: dict[int, Any] = {}

    def _build_panel(self, panel: int) -> None:
        from widgets import style
        from widgets.viewport.body import BodyActor
        from widgets.viewport.floor import FloorGrid
        from widgets.viewport.sensors import SensorMarkers
        from widgets.viewport.skeleton import SkeletonActor
        from widgets.viewport.viewport import keep_key_lights

        p, o = self.plotter, self.options
        p.subplot(0, panel)
        renderer = p.renderer
        renderer.SetBackground(*style.hex_to_unit_rgb(style.BACKGROUND_TOP))
        renderer.SetUseOIT(False)
        keep_key_lights(renderer)
        renderer.SetActiveCamera(self.camera)
        FloorGrid(p)
        make = BodyActor if o.view == "body" else SkeletonActor
        shown = self.figures[panel : panel + 1] if o.layout == "side" else self.figures[:1]
        for fig in shown:
            fig.drawables.append(make(p, fig.color, name=f"figure-{panel}"))
        if self.trackers is not None:
            markers = SensorMarkers(p, lambda joint, position: None)
            self.trackers.draw(markers, 0)  # builds its actors in this panel
            self.sensor_markers.append(markers)

    def draw(self, f: int, ghosts: dict[str, np.ndarray] | None = None) -> None:
        """Pose every figure at frame ``f`` (``ghosts``: ``{method: (J, 3)}``) and render once."""
        self.pose(f, ghosts)
        self.window.Render()

    def pose(self, f: int, ghosts: dict[str, np.ndarray] | None = None) -> None:
        """Move every drawable, the camera and the time code to frame ``f`` (no drawing)."""
        from widgets.viewport.camera import CAMERA_PRESETS

        ghosts = ghosts or {}
        for fig in self.figures:
            pos = self.positions[f] if not fig.ghost else ghosts.get(fig.name)
            for d in fig.drawables:
                d.update(pos)
        if self.trackers is not None:
            for markers in self.sensor_markers:
                self.trackers.draw(markers, f)
        if self.options.camera == "follow":
            focus, (offset, up) = np.array([*self.positions[f, 0, :2], FOCUS_HEIGHT]), CAMERA_PRESETS["home"]
        else:
            focus, (offset, up) = self._centre, CAMERA_PRESETS[self.options.camera]
        self.camera.SetFocalPoint(*focus)
        self.camera.SetPosition(*(focus + offset))
        self.camera.SetViewUp(*up)
        self.camera.SetClippingRange(*CLIPPING)
        self.texts.set_time(self.first_frame + f, self.clip_frames, self.fps)

    def read_into(self, buf: np.ndarray) -> None:
        """Copy the rendered frame into ``buf`` ``(H, W, 3 or 4)`` uint8, rows bottom-up."""
        import vtk

        key = id(buf)
        arr = self._pixels.get(key)
        if arr is None or arr[1] is not buf:
            vtk_arr = vtk.vtkUnsignedCharArray()
            vtk_arr.SetVoidArray(buf, buf.size, 1)  # VTK writes into buf itself
            arr = self._pixels[key] = (vtk_arr, buf)
        w, h = self.options.size
        if buf.shape[2] == 4:
            self.window.GetRGBACharPixelData(0, 0, w - 1, h - 1, 1, arr[0], 0)
        else:
            self.window.GetPixelData(0, 0, w - 1, h - 1, 1, arr[0], 0)

    def image(self) -> np.ndarray:
        """The rendered frame as ``(H, W, 3)`` uint8, top row first (tests, screenshots)."""
        w, h = self.options.size
        buf = np.empty((h, w, 3), np.uint8)
        self.read_into(buf)
        return buf[::-1].copy()

    def close(self) -> None:
        self._pixels.clear()
        self.window.RemoveRenderer(self.overlay)
        self.plotter.close()


def preset_sensors(preset: str) -> tuple:
    """The sensors of tracker preset ``preset`` (:class:`engine.errors.UserError` naming
    the known ones when there is none of that name)."""
    from engine.errors import UserError
    from engine.studio.clips import sensor_presets

    presets = sensor_presets()
    if preset not in presets:
        raise UserError(f"--sensors: unknown preset {preset!r}; known: {', '.join(sorted(presets))}")
    return presets[preset]


class _Trackers:
    """The trackers of preset ``preset`` simulated on ``motion`` (as the studio shows a clip's)."""

    def __init__(self, motion: Any, preset: str) -> None:
        from engine.studio.clip_source import ClipSource

        self.sensors = preset_sensors(preset)
        source = ClipSource(motion)
        source.set_sensors(self.sensors)
        self.joints = tuple(s.joint for s in self.sensors)
        self.axes = tuple(s.dof == 6 for s in self.sensors)
        frames = [source.frame(f).readings for f in range(len(motion))]
        self.pos = np.array([[r[j].position for j in self.joints] for r in frames], float).reshape(len(motion), -1, 3)
        self.rot = np.array([[r[j].rotation for j in self.joints] for r in frames], float).reshape(len(motion), -1, 4)
        self.connected = np.array([[r[j].connected for j in self.joints] for r in frames], bool)

    def draw(self, markers: Any, f: int) -> None:
        markers.update(self.joints, self.pos[f], self.rot[f], self.connected[f], self.axes)


class _Texts:
    """Legend, title and time code as text actors of the overlay renderer (display pixels).

    Texts are rasterised again only when they change, so the legend and the title cost
    nothing after the first frame; the time code changes every frame (~0.2 ms)."""

    def __init__(self, renderer: Any, options: RenderOptions, figures: list[Figure], panels: int) -> None:
        w, h = options.size
        self.font = max(10, round(h / 30))
        pad = round(self.font * 0.6)
        self.rows: list[tuple[str, str, tuple[int, int]]] = []  # name, colour, bottom-left pixel (tests)
        self.renderer = renderer
        top = h - pad
        if options.title:
            title = self._text(options.title, "#ffffff", round(self.font * 1.3))
            top -= round(self.font * 1.3 * 1.25)
            title.SetDisplayPosition(pad, top)
            top -= round(self.font * 0.4)
        step = round(self.font * 1.45)
        for i, fig in enumerate(figures):
            label = fig.name if options.layout == "side" or not fig.ghost else f"{fig.name} (ghost)"
            actor = self._text(label, fig.color, self.font, box=True)
            if options.layout == "side":
                x, y = pad + i * (w // panels), top - step
            else:
                x, y = pad, top - step * (i + 1)
            actor.SetDisplayPosition(x, y)
            self.rows.append((fig.name, fig.color, (x, y)))
        if options.layout == "side" and panels > 1:
            self._separators(w, top if options.title else h, panels)  # under the title
        self.time = self._text("", "#d0d4dc", self.font, mono=True) if options.timecode else None
        if self.time is not None:
            self.time.GetTextProperty().SetJustificationToRight()
            self.time.SetDisplayPosition(w - pad, pad)

    def _text(self, text: str, colour: str, size: int, box: bool = False, mono: bool = False) -> Any:
        import vtk

        from widgets import style

        actor = vtk.vtkTextActor()
        actor.SetInput(text)
        prop = actor.GetTextProperty()
        prop.SetColor(*style.hex_to_unit_rgb(colour))
        prop.SetFontSize(size)
        prop.BoldOn()
        if mono:
            prop.SetFontFamilyToCourier()
        if box:  # a dark box keeps the name readable over the floor or a figure
            prop.SetBackgroundColor(0.05, 0.06, 0.08)
            prop.SetBackgroundOpacity(0.6)
        actor.PickableOff()
        self.renderer.AddViewProp(actor)
        return actor

    def _separators(self, w: int, top: int, panels: int) -> None:
        """A dark vertical line between side-by-side panels, so their floors do not read as one."""
        import vtk

        from widgets import style

        pts, lines = vtk.vtkPoints(), vtk.vtkCellArray()
        for i in range(1, panels):
            x = i * w / panels
            lines.InsertNextCell(2, [pts.InsertNextPoint(x, 0, 0), pts.InsertNextPoint(x, top, 0)])
        poly = vtk.vtkPolyData()
        poly.SetPoints(pts)
        poly.SetLines(lines)
        mapper = vtk.vtkPolyDataMapper2D()
        mapper.SetInputData(poly)
        actor = vtk.vtkActor2D()
        actor.SetMapper(mapper)
        actor.GetProperty().SetColor(*style.hex_to_unit_rgb(style.BACKGROUND_BOTTOM))
        actor.GetProperty().SetLineWidth(3)
        self.renderer.AddViewProp(actor)

    def set_time(self, f: int, n: int, fps: float) -> None:
        """Show the time of frame ``f`` of an ``n``-frame clip and its number as the
        studio's timeline shows it: counted from 0, over the last frame's."""
        if self.time is not None:
            t = f / fps
            self.time.SetInput(f"{int(t // 60):02d}:{t % 60:05.2f}  frame {f}/{n - 1}")
