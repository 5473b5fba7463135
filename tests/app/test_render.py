"""``render``: an MP4 with exactly the promised frames and size, showing the skeleton."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from app.render import main, parse_size
from engine.motion.bvh import save_motion_bvh
from engine.errors import UserError
from engine.studio.clips import load_clip

EXAMPLE = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"


def decode(path: Path) -> tuple[tuple[int, int], list[np.ndarray]]:
    import imageio_ffmpeg

    frames = imageio_ffmpeg.read_frames(str(path))
    meta = next(frames)
    w, h = meta["size"]
    return (w, h), [np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in frames]


def orange(img: np.ndarray) -> int:
    """Pixels of the motion's colour (#ff8a1f, shaded): red high, green mid, blue low."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return int(((r > 150) & (g > 50) & (g < 0.8 * r) & (b < 0.45 * r)).sum())


@pytest.fixture(scope="module")
def short_clip(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("render") / "short.bvh"
    save_motion_bvh(path, load_clip(EXAMPLE).slice(100, 124))
    return path


def test_the_video_has_the_frame_count_and_size_and_shows_the_skeleton(short_clip, tmp_path):
    out = tmp_path / "v.mp4"
    assert main([str(short_clip), "--out", str(out), "--size", "160x120", "--no-progress"]) == 0
    size, frames = decode(out)
    assert size == (160, 120) and len(frames) == len(load_clip(short_clip)) == 24
    assert orange(frames[12]) > 50  # the stick figure
    assert orange(np.zeros_like(frames[12])) == 0 and orange(frames[12][:8]) == 0  # not the background
    assert not list(tmp_path.glob("*.tmp*")) and [p.name for p in tmp_path.iterdir()] == ["v.mp4"]


def test_another_rate_sensors_a_ghost_side_camera_and_body_view(short_clip, tmp_path):
    out = tmp_path / "v.mp4"
    assert main([str(short_clip), "--out", str(out), "--size", "96x64", "--fps", "30", "--sensors", "6",
                 "--ghosts", "ik", "--camera", "side", "--view", "body", "--no-progress"]) == 0  # fmt: skip
    from engine.motion.retarget import resample_motion

    size, frames = decode(out)
    assert size == (96, 64) and len(frames) == len(resample_motion(load_clip(short_clip), 30.0))
    assert orange(frames[len(frames) // 2]) > 20


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
