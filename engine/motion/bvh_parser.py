"""Syntax of BVH files: a strict parser that names the line at fault.

Used by :func:`engine.motion.bvh.load_bvh`; nothing here builds joint arrays. The header
goes to :mod:`engine.motion.bvh_syntax` (tokens that remember their line, an iterative
descent parser); the motion rows are checked line by line here before numpy converts
them in one go.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from engine.errors import BVHError
from engine.motion.bvh_syntax import Hierarchy, Tokens, plain_float
from engine.validation import BVH_HEADER, check_value, shown

#: Longest HIERARCHY section, characters (a 100-joint rig takes about 10,000).
MAX_HEADER = 4_000_000
#: Data rows converted at a time (bounds the memory of the text being converted).
CHUNK = 2048

_FRAMES = re.compile(r"^\s*frames\s*:\s*(\S*)\s*$", re.IGNORECASE)
_FRAME_TIME = re.compile(r"^\s*frame\s+time\s*:\s*(\S*)\s*$", re.IGNORECASE)
_WHOLE = re.compile(r"[0-9]+")


class _Lines:
    """Numbered lines pulled one at a time from any iterable (a file streams)."""

    def __init__(self, lines: Iterable[str]):
        self._it = iter(lines)
        self.count = 0  # 1-based number of the last line read

    def next(self) -> str | None:
        line = next(self._it, None)
        if line is not None:
            self.count += 1
        return line

    def next_nonblank(self) -> str | None:
        while (line := self.next()) is not None and not line.strip():
            pass
        return line


def _motion_header(path: str, lines: _Lines) -> tuple[int, float, int]:
    """Parse ``Frames:`` and ``Frame Time:`` after the MOTION line.

    Returns the frame count, the frame time (s) and the 1-based line of ``Frames:``.
    """
    values = []
    for pattern, label in ((_FRAMES, "Frames: <count>"), (_FRAME_TIME, "Frame Time: <seconds>")):
        line = lines.next_nonblank()
        if line is None:
            raise BVHError(path, f"unexpected end of file, expected '{label}' (file truncated?)", lines.count)
        m = pattern.match(line)
        if m is None:
            raise BVHError(path, f"expected '{label}', found {shown(line.strip(), 60)}", lines.count)
        values.append((m.group(1), lines.count))
    (frames_text, frames_line), (time_text, time_line) = values
    if _WHOLE.fullmatch(frames_text) is None:
        raise BVHError(path, f"Frames must be a whole number, got {shown(frames_text)}", frames_line)
    if int(frames_text[:12]) == 0:
        raise BVHError(path, "the file has zero frames", frames_line)
    frames = int(frames_text[:12]) if len(frames_text) <= 12 else 10**12  # no 5000-digit int()
    try:
        frame_time = plain_float(time_text)
    except ValueError:
        raise BVHError(path, f"Frame Time {shown(time_text)} is not a number", time_line) from None
    if not math.isfinite(frame_time) or frame_time <= 0:
        raise BVHError(path, f"Frame Time must be a positive number of seconds, got {shown(time_text)}", time_line)
    check_value(BVH_HEADER["Frames"], frames, f"{path}:{frames_line}", "Frames")
    check_value(BVH_HEADER["Frame Time"], frame_time, f"{path}:{time_line}", "Frame Time")
    return frames, frame_time, frames_line


def _convert(path: str, rows: list[list[str]], numbers: list[int]) -> np.ndarray:
    """One chunk of data rows as floats; every value finite, else the line at fault."""
    try:
        data = np.array(rows, dtype=np.float64)
    except ValueError:
        data = None
    if data is None or not np.isfinite(data).all():
        for row, n in zip(rows, numbers):  # slow path, only to name the culprit
            for text in row:
                try:
                    value = float(text)
                except ValueError:
                    raise BVHError(path, f"{shown(text)} is not a number", n) from None
                if not math.isfinite(value):
                    raise BVHError(path, f"value {shown(text)} is not finite", n)
        raise BVHError(path, "unreadable motion data", numbers[0])  # numpy and float() disagree
    return data


def _unplain_row(path: str, parts: list[str], line: str, number: int) -> BVHError:
    """The error for a data row holding a non-ASCII character or an underscore."""
    for text in parts:
        try:
            plain_float(text)
        except ValueError:
            return BVHError(path, f"{shown(text)} is not a number", number)
    odd = next(ch for ch in line if not ch.isascii())
    return BVHError(path, f"non-ASCII character U+{ord(odd):04X} between the numbers of a motion row", number)


def _motion_data(
    path: str, lines: _Lines, columns: int, frames: int, frames_line: int, keep: int, room: int
) -> np.ndarray:
    """Parse the data rows, CHUNK at a time; every row is checked, the first ``keep`` kept.

    ``room`` bounds the rows the rest of the file can hold (each value takes at least
    two bytes), so a header claiming millions of frames allocates nothing it cannot fill.
    Returns an array (min(F, keep), columns)."""
    out = np.empty((min(frames, keep, room), columns))
    rows: list[list[str]] = []
    numbers: list[int] = []  # 1-based line of each row
    done = 0
    while True:
        line = lines.next()
        if line is not None:
            parts = line.split()
            if not parts:
                continue
            if not line.isascii() or "_" in line:  # isascii() is O(1) on a str
                raise _unplain_row(path, parts, line, lines.count)
            if len(parts) != columns:
                raise BVHError(
                    path,
                    f"wrong number of values on frame {done + len(rows) + 1}: expected {columns}, got {len(parts)}",
                    lines.count,
                )
            if done + len(rows) >= frames:
                raise BVHError(
                    path, f"more data rows than the header's Frames: {frames} (line {frames_line})", lines.count
                )
            rows.append(parts)
            numbers.append(lines.count)
        if rows and (len(rows) == CHUNK or line is None):
            data = _convert(path, rows, numbers)
            take = max(0, min(len(rows), out.shape[0] - done))
            out[done : done + take] = data[:take]
            done += len(rows)
            rows, numbers = [], []
        if line is None:
            break
    if done < frames:
        raise BVHError(
            path, f"header says Frames: {frames} but only {done} data rows follow (file truncated?)", frames_line
        )
    return out


@dataclass(frozen=True)
class ParsedBVH:
    """What a BVH file says, checked but not yet turned into per-joint arrays.

    Attributes
    ----------
    names, parents, offsets, channels, end_sites
        The hierarchy in file order (see :class:`engine.motion.bvh.RawBVH`); ``offsets`` is a
        list of J ``[x, y, z]`` in file units.
    frame_time : float
        Seconds per frame, > 0.
    data : ndarray (K, C)
        Every channel value of the first K kept frames, finite, C = total channel count.
    frames : int
        Frames F in the file (all checked), K <= F.
    """

    names: list[str]
    parents: list[int]
    offsets: list[list[float]]
    channels: list[tuple[str, ...]]
    end_sites: dict[int, np.ndarray]
    frame_time: float
    data: np.ndarray
    frames: int = 0


def parse_bvh_text(path: str, text: str, keep: int | None = None) -> ParsedBVH:
    """Parse and validate the text of a BVH file; raise :class:`BVHError` naming the line."""
    return parse_bvh_lines(path, text.splitlines(), keep, len(text))


def parse_bvh_lines(path: str, lines: Iterable[str], keep: int | None = None, size: int | None = None) -> ParsedBVH:
    """Parse and validate a BVH file given as lines (an open text file streams).

    Every row is checked, but only the first ``keep`` frames are kept (all by default):
    ``info`` and ``reconstruct --max-frames`` read a 200,000-frame file in little memory.
    ``size`` (bytes or characters of the file) bounds what the data can hold."""
    src = _Lines(lines)
    header: list[str] = []
    chars = 0
    motion_found = motion_alone = False
    while (line := src.next()) is not None:
        first = line.split(None, 1)[:1]
        if first and first[0].upper() == "MOTION":
            motion_found, motion_alone = True, len(line.split()) == 1
            break
        header.append(line)
        chars += len(line)
        if chars > MAX_HEADER:
            raise BVHError(path, f"the HIERARCHY section is longer than {MAX_HEADER:,} characters", src.count)
    tokens = Tokens(path, header + (["MOTION"] if motion_found else []), len(header))
    hier = Hierarchy(tokens)
    hier.parse()
    if not motion_found:
        raise BVHError(path, "missing MOTION section after the hierarchy", src.count or 1)
    if not motion_alone:
        raise BVHError(path, "MOTION must be alone on its line", src.count)
    frames, frame_time, frames_line = _motion_header(path, src)
    columns = sum(len(c) for c in hier.channels)
    room = frames if size is None else size // (2 * columns) + 1
    data = _motion_data(path, src, columns, frames, frames_line, frames if keep is None else keep, room)
    return ParsedBVH(hier.names, hier.parents, hier.offsets, hier.channels, hier.end_sites, frame_time, data, frames)
