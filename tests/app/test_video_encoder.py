"""The encoder beside the drawing: frames in order, bottom-up rows flipped, errors named."""

from __future__ import annotations

import imageio_ffmpeg
import numpy as np
import pytest

from app.video_encoder import POOL, VideoEncoder


@pytest.mark.parametrize("channels", [3, 4])
def test_frames_arrive_in_order_and_upright(tmp_path, channels):
    out = tmp_path / "v.mp4"
    enc = VideoEncoder(out, (64, 48), 25.0, channels)
    n = 3 * POOL  # more frames than buffers: they are reused
    for i in range(n):
        buf = enc.buffer()
        buf[:] = 0
        buf[:24, :, 0] = 255  # the bottom half red (GL rows run bottom-up)
        buf[24:, :, 2] = 10 * i  # the top half's blue counts the frames
        enc.submit(buf)
    enc.close()
    frames = imageio_ffmpeg.read_frames(str(out))
    assert next(frames)["size"] == (64, 48)
    decoded = [np.frombuffer(f, np.uint8).reshape(48, 64, 3) for f in frames]
    assert len(decoded) == n
    for i, img in enumerate(decoded):
        assert img[30:, :, 0].mean() > 200 and img[:18, :, 0].mean() < 40  # red at the bottom
        assert abs(img[:18, :, 2].mean() - 10 * i) < 6  # in order


def test_a_failing_ffmpeg_is_reported(tmp_path):
    enc = VideoEncoder(tmp_path / "no such dir" / "v.mp4", (32, 32), 30.0)
    with pytest.raises(OSError, match="ffmpeg"):
        for _ in range(50):  # fails on a submit once the writer has seen the broken pipe, or at close
            enc.submit(enc.buffer())
        enc.close()
