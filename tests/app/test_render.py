"""``render``: an MP4 with exactly the promised frames, size and time base; each layout
shows its legend and every figure in its colour where expected."""

from __future__ import annotations

import colorsys
import struct
from pathlib import Path

import numpy as np
import pytest

from app.render import main, parse_size
from engine.errors import UserError
from engine.motion.bvh import save_motion_bvh
from engine.studio.clips import load_clip
from widgets import style

EXAMPLE = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"


def decode(path: Path) -> tuple[tuple[int, int], list[np.ndarray]]:
    import imageio_ffmpeg

    frames = imageio_ffmpeg.read_frames(str(path))
    meta = next(frames)
    w, h = meta["size"]
    return (w, h), [np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in frames]


def mp4_timing(path: Path) -> tuple[int, int, list[tuple[int, int]]]:
    """The video track's time scale and duration (``mdhd``) and its sample durations as
    ``(count, delta)`` runs (``stts``), read from the MP4 boxes themselves."""
    data = path.read_bytes()

    def boxes(start: int, end: int):
        while start < end:
            size, kind = struct.unpack(">I4s", data[start : start + 8])
            yield kind.decode(), start + 8, start + size
            start += size

    def find(path_: list[str], start: int = 0, end: int = len(data)) -> tuple[int, int]:
        for kind, body, stop in boxes(start, end):
            if kind == path_[0]:
                return (body, stop) if len(path_) == 1 else find(path_[1:], body, stop)
        raise AssertionError(f"no {path_[0]} box")

    trak = find(["moov", "trak"])
    mdhd, _ = find(["mdia", "mdhd"], *trak)
    version = data[mdhd]
    if version:  # 64-bit times: created, modified (8 bytes each), scale (4), duration (8)
        scale, duration = struct.unpack(">IQ", data[mdhd + 20 : mdhd + 32])
    else:
        scale, duration = struct.unpack(">II", data[mdhd + 12 : mdhd + 20])
    stts, _ = find(["mdia", "minf", "stbl", "stts"], *trak)
    (n,) = struct.unpack(">I", data[stts + 4 : stts + 8])
    runs = [struct.unpack(">II", data[stts + 8 + 8 * i : stts + 16 + 8 * i]) for i in range(n)]
    return scale, duration, runs


def hue_mask(img: np.ndarray, colour: str, tol: float = 14.0) -> np.ndarray:
    """Pixels of ``colour``'s hue (within ``tol`` degrees), saturated and bright enough
    not to be the grey-blue background, the floor or a dark shadow."""
    rgb = img.astype(float) / 255.0
    mx, mn = rgb.max(-1), rgb.min(-1)
    sat = np.where(mx > 0, (mx - mn) / np.maximum(mx, 1e-9), 0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    d = np.maximum(mx - mn, 1e-9)
    hue = np.where(mx == r, (g - b) / d % 6, np.where(mx == g, (b - r) / d + 2, (r - g) / d + 4)) * 60.0
    want = colorsys.rgb_to_hsv(*(c / 255 for c in style.hex_to_rgb(colour)))[0] * 360.0
    diff = np.abs((hue - want + 180.0) % 360.0 - 180.0)
    return (sat > 0.4) & (mx > 0.3) & (diff < tol)


@pytest.fixture(scope="module")
def short_clip(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("render") / "short.bvh"
    save_motion_bvh(path, load_clip(EXAMPLE).slice(100, 124))
    return path


def test_the_video_has_the_frame_count_size_and_time_base_and_shows_the_skeleton(short_clip, tmp_path):
    out = tmp_path / "v.mp4"
    assert main([str(short_clip), "--out", str(out), "--size", "160x120", "--no-progress"]) == 0
    size, frames = decode(out)
    assert size == (160, 120) and len(frames) == len(load_clip(short_clip)) == 24
    scale, duration, runs = mp4_timing(out)
    assert runs == [(24, scale // 60)] and scale % 60 == 0  # every frame lasts exactly 1/60 s
    assert duration == 24 * scale // 60
    orange = hue_mask(frames[12], style.RECONSTRUCTION)
    assert orange.sum() > 50  # the stick figure
    assert not hue_mask(np.full_like(frames[12], 40), style.RECONSTRUCTION).any()
    assert not list(tmp_path.glob("*.tmp*")) and [p.name for p in tmp_path.iterdir()] == ["v.mp4"]


def test_another_rate_gives_its_own_frame_count_and_time_base(short_clip, tmp_path):
    out = tmp_path / "v.mp4"
    assert (
        main(
            [
                str(short_clip),
                "--out",
                str(out),
                "--size",
                "96x64",
                "--fps",
                "30",
                "--camera",
                "side",
                "--view",
                "body",
                "--no-progress",
            ]
        )
        == 0
    )
    from engine.motion.retarget import resample_motion

    n = len(resample_motion(load_clip(short_clip), 30.0))
    size, frames = decode(out)
    assert size == (96, 64) and len(frames) == n
    scale, duration, runs = mp4_timing(out)
    assert runs == [(n, scale // 30)] and duration == n * scale // 30
    assert hue_mask(frames[n // 2], style.RECONSTRUCTION).sum() > 20


def legend_row_has(img: np.ndarray, row: tuple[str, str, tuple[int, int]], font: int) -> np.ndarray:
    """The legend row's pixels of its colour: text drawn from display point (x, y)
    (bottom-left origin) over a box about ``font`` pixels high."""
    h = img.shape[0]
    name, colour, (x, y) = row
    box = img[h - y - font - 4 : h - y + 2, x : x + font * max(2, len(name))]
    return hue_mask(box, colour)


def render_layout(clip: Path, out: Path, layout: str) -> tuple[list[np.ndarray], object]:
    """Render ``clip`` with an IK ghost in ``layout``; the decoded frames and the same
    scene built in this process (its legend rows give where the text must be)."""
    from app.render_scene import FrameRenderer, RenderOptions

    args = [
        "--size",
        "480x270",
        "--view",
        "body",
        "--sensors",
        "6",
        "--ghosts",
        "ik",
        "--truth",
        "--layout",
        layout,
        "--title",
        "Test",
        "--timecode",
        "--no-progress",
    ]
    assert main([str(clip), "--out", str(out), *args]) == 0
    size, frames = decode(out)
    assert size == (480, 270) and len(frames) == 24
    scene = FrameRenderer(
        load_clip(clip),
        RenderOptions(
            size=(480, 270),
            sensors="6",
            ghosts=("ik",),
            view="body",
            truth=True,
            layout=layout,
            title="Test",
            timecode=True,
        ),
    )
    return frames, scene


def test_overlay_layout_legend_and_colours(short_clip, tmp_path):
    frames, scene = render_layout(short_clip, tmp_path / "o.mp4", "overlay")
    try:
        img, font = frames[12], scene.texts.font
        rows = scene.texts.rows
        assert [r[:2] for r in rows] == [("ground truth", style.GROUND_TRUTH), ("ik", style.GHOSTS["ik"])]
        for row in rows:  # each name, in its colour, in its row of the legend
            assert legend_row_has(img, row, font).sum() > 15, row
        assert not hue_mask(img[:90, 300:], style.GHOSTS["ik"]).any()  # the legend is top left only
        figure = np.s_[60:, 120:360]  # below the legend, around the followed figure
        assert hue_mask(img[figure], style.GROUND_TRUTH).sum() > 500  # the shaded ground-truth body
        assert hue_mask(img[figure], style.GHOSTS["ik"]).sum() > 20  # the ghost
        # in the scene's own pixels (no compression): the ghost is thin lines over the
        # body that leave most of it in sight, not a second body
        from engine.studio.clips import sensor_presets
        from engine.studio.export import reconstruct_clip

        ik = reconstruct_clip(load_clip(short_clip), sensor_presets()["6"], (), {}, "ik").positions()[12]
        scene.draw(12, {"ik": None})
        alone = scene.image()
        scene.draw(12, {"ik": ik})
        both = scene.image()
        body = hue_mask(alone[figure], style.GROUND_TRUTH).sum()
        green, blue = hue_mask(both[figure], style.GROUND_TRUTH), hue_mask(both[figure], style.GHOSTS["ik"])
        assert green.sum() > 0.6 * body and 20 < blue.sum() < 0.5 * body
        ys, xs = np.nonzero(green)
        by, bx = np.nonzero(blue)
        assert abs(np.median(bx) - np.median(xs)) < 25 and abs(np.median(by) - np.median(ys)) < 40  # over it
        # the decoded frame is the scene's picture (upright, same place), up to compression
        assert np.abs(both.astype(int) - img.astype(int)).mean() < 6
    finally:
        scene.close()


def test_side_layout_puts_each_figure_in_its_panel(short_clip, tmp_path):
    frames, scene = render_layout(short_clip, tmp_path / "s.mp4", "side")
    try:
        img, font = frames[12], scene.texts.font
        rows = scene.texts.rows
        assert [r[2][0] for r in rows] == [round(font * 0.6), round(font * 0.6) + 240]  # one label per panel
        for row in rows:
            assert legend_row_has(img, row, font).sum() > 15, row
        left, right = img[60:, :240], img[60:, 240:]
        green, blue = hue_mask(left, style.GROUND_TRUTH).sum(), hue_mask(right, style.GHOSTS["ik"]).sum()
        assert green > 500 and blue > 500
        # not the other figure (a few pixels of the trackers' blue z axes are in both panels)
        assert hue_mask(left, style.GHOSTS["ik"]).sum() < 0.05 * blue
        assert hue_mask(right, style.GROUND_TRUTH).sum() < 0.05 * green
        # same camera: the two figures stand at the same place of their panels
        gl, bl = np.nonzero(hue_mask(left, style.GROUND_TRUTH))[1], np.nonzero(hue_mask(right, style.GHOSTS["ik"]))[1]
        assert abs(np.median(gl) - np.median(bl)) < 15
    finally:
        scene.close()


def test_ghost_colours_never_repeat_the_inputs():
    from app.render_scene import figure_colours

    assert figure_colours(style.RECONSTRUCTION, ("ik", "dragposer")) == [style.GHOSTS["ik"], style.GHOST_CYCLE[1]]
    assert figure_colours(style.GROUND_TRUTH, ("dragposer",)) == [style.GHOSTS["dragposer"]]


@pytest.mark.parametrize("text", ["160", "161x120", "0x0", "axb", "9000x100"])
def test_bad_sizes_are_named(text):
    with pytest.raises(UserError, match="--size"):
        parse_size(text)


def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "v.mp4"
    assert main([str(tmp_path / "missing.bvh"), "--out", str(out), "--no-progress"]) == 2
    assert "missing.bvh" in capsys.readouterr().err and not out.exists()
    assert main([str(EXAMPLE), "--out", str(out), "--ghosts", "ik", "--no-progress"]) == 2
    assert "--sensors" in capsys.readouterr().err
    assert main([str(EXAMPLE), "--out", str(out), "--sensors", "6", "--ghosts", "nope", "--no-progress"]) == 2
    assert "nope" in capsys.readouterr().err
    assert main([str(EXAMPLE), "--out", str(out), "--msaa", "3", "--no-progress"]) == 2
    assert "--msaa" in capsys.readouterr().err and not out.exists()


def test_a_ghost_that_cannot_run_from_the_trackers_is_refused_before_the_clip_is_read(tmp_path, capsys, monkeypatch):
    import app.render as render

    monkeypatch.setattr(render, "load_input", lambda path: pytest.fail("the clip was read before the check"))
    out = tmp_path / "v.mp4"
    assert main([str(EXAMPLE), "--out", str(out), "--sensors", "6", "--ghosts", "ik,rpm", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "--ghosts rpm: rpm runs only with tracker preset '3-head-hands' (these trackers: '6')" in err, err
    assert not out.exists()


def test_a_failure_mid_video_stops_the_encoder_and_leaves_no_file(short_clip, tmp_path, monkeypatch):
    from app.render import render_video
    from app.render_scene import FrameRenderer, RenderOptions

    pose = FrameRenderer.pose

    def failing(self, f, ghosts=None):
        if f == 5:
            raise RuntimeError("boom")
        pose(self, f, ghosts)

    monkeypatch.setattr(FrameRenderer, "pose", failing)
    with pytest.raises(RuntimeError, match="boom"):
        render_video(load_clip(short_clip), tmp_path / "v.mp4", RenderOptions(size=(64, 48)))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("msaa", [0, 4])
def test_the_window_is_set_for_throughput(msaa):
    """No multisampling unless asked, no gradient, no order-independent transparency pass
    (each costs several ms a frame on software GL: docs/performance.md)."""
    from app.render_scene import FrameRenderer, RenderOptions

    scene = FrameRenderer(load_clip(EXAMPLE).slice(0, 3), RenderOptions(size=(64, 48), msaa=msaa, sensors="6"))
    try:
        scene.draw(1)
        assert scene.window.GetMultiSamples() == msaa
        for renderer in [*scene.plotter.renderers, scene.overlay]:
            assert not renderer.GetUseOIT() and not renderer.GetGradientBackground()
        assert scene.camera.GetClippingRange() == pytest.approx((0.1, 40.0))
    finally:
        scene.close()


def test_a_30_fps_bvh_renders_at_30_fps(tmp_path):
    """It rendered at 60 fps (the studio's rate) while the same motion as a scene rendered at 30."""
    import imageio_ffmpeg

    from engine.motion.retarget import resample_motion

    clip = tmp_path / "thirty.bvh"
    save_motion_bvh(clip, resample_motion(load_clip(EXAMPLE).slice(100, 160), 30.0))
    out = tmp_path / "v.mp4"
    assert main([str(clip), "--out", str(out), "--size", "96x64", "--no-progress"]) == 0
    frames = imageio_ffmpeg.read_frames(str(out))
    meta = next(frames)
    assert meta["fps"] == pytest.approx(30.0) and sum(1 for _ in frames) == 30


def test_without_a_display_the_video_is_drawn_without_an_x_warning(short_clip, tmp_path):
    """A headless machine (no DISPLAY): the render draws the skeleton and stderr holds no
    VTK warning about an X server it never needed."""
    import os
    import subprocess
    import sys

    out = tmp_path / "h.mp4"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[2])
    args = [str(short_clip), "--out", str(out), "--size", "160x120", "--no-progress"]
    run = subprocess.run(
        [sys.executable, "-c", f"from app.render import main; raise SystemExit(main({args!r}))"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "X server" not in run.stderr and "WARN" not in run.stderr, run.stderr[-2000:]
    _size, frames = decode(out)
    assert len(frames) == 24 and hue_mask(frames[12], style.RECONSTRUCTION).sum() > 50
