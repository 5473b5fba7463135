"""H.264 encoding beside the drawing: ffmpeg fed through a pipe from a writer thread.

The drawing loop reads each frame's pixels straight into one of a few preallocated
buffers (:meth:`VideoEncoder.buffer`) and hands it over (:meth:`VideoEncoder.submit`);
a thread writes it to ffmpeg's stdin (the write releases the interpreter lock) and
returns the buffer to the pool. ffmpeg is a process of its own, so on two cores the
encoding runs while the next frame is drawn; when the encoder falls behind, the pool
runs dry and the drawing waits for a free buffer instead of queueing frames without
bound.

Frames arrive as OpenGL reads them: rows bottom-up, RGB or RGBA. ffmpeg flips them
(``vflip``) and converts them to 4:2:0 itself, which costs less there than a numpy
copy per frame here. The binary is the one the ``imageio-ffmpeg`` wheel ships.
x264's ``veryfast`` preset encodes a 960x540 frame in ~5 ms of one core here (``medium``,
ffmpeg's default, in ~13 ms: more than the drawing) at a similar file size for this
kind of picture (flat background, few moving shapes).
"""

from __future__ import annotations

import queue
import subprocess
import threading
from fractions import Fraction
from pathlib import Path

import numpy as np

#: Buffers in flight between the drawing and ffmpeg.
POOL = 4
PRESET = "veryfast"
CRF = 20


class VideoEncoder:
    """Encode ``size`` frames at ``fps`` into ``path`` (MP4, H.264, yuv420p).

    Parameters
    ----------
    path : Path
        File to write (the caller makes it atomic).
    size : (int, int)
        Width and height in pixels (even).
    fps : float
        Frame rate; the stream's time base is its exact fraction (60 -> 1/60 s).
    channels : int
        3 (RGB) or 4 (RGBA) bytes per pixel of the submitted buffers.
    """

    def __init__(self, path: Path, size: tuple[int, int], fps: float, channels: int = 3) -> None:
        import imageio_ffmpeg

        w, h = size
        rate = Fraction(fps).limit_denominator(1001)
        pix = {3: "rgb24", 4: "rgba"}[channels]
        cmd = [
            imageio_ffmpeg.get_ffmpeg_exe(),
            "-v",
            "error",
            "-y",
            "-f",
            "rawvideo",
            "-pix_fmt",
            pix,
            "-s",
            f"{w}x{h}",
            "-framerate",
            str(rate),
            "-i",
            "-",
            "-vf",
            "vflip",
            "-c:v",
            "libx264",
            "-preset",
            PRESET,
            "-crf",
            str(CRF),
            "-pix_fmt",
            "yuv420p",
            "-r",
            str(rate),
            "-movflags",
            "+faststart",
            "-f",
            "mp4",
            str(path),
        ]
        self.frames = 0
        self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
        self._free: queue.Queue[np.ndarray] = queue.Queue()
        for _ in range(POOL):
            self._free.put(np.empty((h, w, channels), np.uint8))
        self._full: queue.Queue[np.ndarray | None] = queue.Queue()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._write, name="video-writer", daemon=True)
        self._thread.start()

    def buffer(self) -> np.ndarray:
        """A free ``(H, W, channels)`` uint8 buffer to read a frame into (waits while
        every buffer is queued for ffmpeg)."""
        self._raise_error()
        while True:
            try:
                return self._free.get(timeout=0.5)
            except queue.Empty:
                self._raise_error()

    def submit(self, buf: np.ndarray) -> None:
        """Queue ``buf`` (from :meth:`buffer`, rows bottom-up) as the next frame."""
        self._raise_error()
        self._full.put(buf)
        self.frames += 1

    def _write(self) -> None:
        stdin = self._proc.stdin
        assert stdin is not None
        while (buf := self._full.get()) is not None:
            try:
                if self._error is None:
                    stdin.write(memoryview(buf).cast("B"))
            except BaseException as exc:  # ffmpeg gone: reported on the next submit or close
                self._error = exc
            self._free.put(buf)

    def _raise_error(self) -> None:
        if self._error is not None:
            raise OSError(f"ffmpeg stopped: {self._stderr() or self._error}")

    def _stderr(self) -> str:
        self._proc.poll()
        if self._proc.returncode is None or self._proc.stderr is None:
            return ""
        return self._proc.stderr.read().decode(errors="replace").strip()

    def close(self) -> None:
        """Flush the queued frames and wait for ffmpeg to finish the file.

        Raises
        ------
        OSError
            ffmpeg failed (its message is included).
        """
        self._full.put(None)
        self._thread.join()
        if self._proc.stdin is not None:
            try:
                self._proc.stdin.close()
            except BrokenPipeError:
                pass
        err = self._proc.stderr.read().decode(errors="replace").strip() if self._proc.stderr else ""
        code = self._proc.wait()
        if code != 0 or self._error is not None:
            raise OSError(f"ffmpeg failed (exit code {code}): {err or self._error}")

    def abort(self) -> None:
        """Stop at once, leaving an incomplete file (the caller deletes it)."""
        self._full.put(None)
        self._proc.kill()
        self._thread.join(timeout=5)
        self._proc.wait()
