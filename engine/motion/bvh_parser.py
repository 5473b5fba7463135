"""Syntax of BVH files: a strict tokenizer and parser that names the line at fault.

Used by :func:`engine.motion.bvh.load_bvh`; nothing here builds joint arrays. The header is
split into tokens that remember their line, then read by an iterative descent parser
(deep hierarchies cannot hit Python's recursion limit); the motion rows are checked
line by line before numpy converts them in one go.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from engine.errors import BVHError
from engine.validation import BVH_HEADER, check_value, shown

#: Largest accepted absolute OFFSET component, in the file's units (cm, m, inches...).
MAX_OFFSET = 1e4
#: Longest HIERARCHY section, characters (a 100-joint rig takes about 10,000).
MAX_HEADER = 4_000_000
#: Data rows converted at a time (bounds the memory of the text being converted).
CHUNK = 2048

_AXES = "xyz"
_CHANNEL = re.compile(r"^([xyz])(position|rotation)$", re.IGNORECASE)
_TOKEN = re.compile(r"[{}]|[^\s{}]+")
_FRAMES = re.compile(r"^\s*frames\s*:\s*(\S*)\s*$", re.IGNORECASE)
_FRAME_TIME = re.compile(r"^\s*frame\s+time\s*:\s*(\S*)\s*$", re.IGNORECASE)
#: A number as BVH files write it: ASCII digits, sign, point, exponent. Python's ``float``
#: and ``int`` also take other scripts' digits ('\u0663') and underscores ('1_000'),
#: which other BVH readers refuse; ``str.isdigit`` even takes '\u00b2', which ``int`` does not.
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_WHOLE = re.compile(r"[0-9]+")
_NON_FINITE = ("nan", "inf", "infinity")


class _Tokens:
    """Header tokens with their 1-based line numbers and a read cursor."""

    def __init__(self, path: str, lines: list[str], stop: int):
        self.path = path
        self.items: list[tuple[str, int]] = []
        for n, line in enumerate(lines[:stop], start=1):
            self.items.extend((t, n) for t in _TOKEN.findall(line))
        self.i = 0
        if stop < len(lines):
            self.end = ("MOTION starts here", stop + 1)
        else:
            self.end = ("the file ends here (truncated?)", max(stop, 1))

    def error(self, message: str, line: int | None) -> BVHError:
        return BVHError(self.path, message, line)

    def peek(self) -> tuple[str, int] | None:
        return self.items[self.i] if self.i < len(self.items) else None

    def next(self, what: str) -> tuple[str, int]:
        tok = self.peek()
        if tok is None:
            raise self.error(f"expected {what}, but {self.end[0]}", self.end[1])
        self.i += 1
        return tok

    def rest_of_line(self, line: int) -> list[str]:
        """Consume and return the non-brace tokens left on ``line``."""
        out = []
        while (tok := self.peek()) is not None and tok[1] == line and tok[0] not in "{}":
            out.append(tok[0])
            self.i += 1
        return out

    def expect(self, text: str, where: str) -> int:
        tok, line = self.next(f"'{text}' {where}")
        if tok.upper() != text.upper():
            raise self.error(f"expected '{text}' {where}, found '{tok}'", line)
        return line


def _float(text: str) -> float:
    """``float(text)`` for a :data:`_DECIMAL` or a spelling of NaN/infinity (the callers
    name those as not finite); ``ValueError`` for anything else."""
    if _DECIMAL.fullmatch(text) is None and text.lstrip("+-").lower() not in _NON_FINITE:
        raise ValueError(f"not a BVH number: {text!r}")
    return float(text)


def _number(tokens: _Tokens, text: str, line: int, what: str) -> float:
    try:
        value = _float(text)
    except ValueError:
        raise tokens.error(f"{what}: '{text}' is not a number", line) from None
    if not math.isfinite(value):
        raise tokens.error(f"{what}: value {text} is not finite", line)
    return value


class _Hierarchy:
    """Recursive-descent parse of the HIERARCHY section (iterative: no recursion limit)."""

    def __init__(self, tokens: _Tokens):
        self.t = tokens
        self.names: list[str] = []
        self.lines: list[int] = []
        self.parents: list[int] = []
        self.offsets: list[list[float]] = []
        self.channels: list[tuple[str, ...]] = []
        self.end_sites: dict[int, np.ndarray] = {}

    def parse(self) -> None:
        t = self.t
        tok = t.peek()
        if tok is None or tok[0].upper() != "HIERARCHY":
            raise t.error("missing HIERARCHY: a BVH file starts with the word HIERARCHY", tok[1] if tok else 1)
        t.i += 1
        tok, line = t.next("ROOT")
        if tok.upper() != "ROOT":
            raise t.error(f"missing ROOT: expected 'ROOT <name>' after HIERARCHY, found '{tok}'", line)
        stack = [self._open_joint(line, -1)]
        while stack:
            tok, line = t.next(f"'}}' closing joint '{self.names[stack[-1]]}' (line {self.lines[stack[-1]]})")
            word = tok.upper()
            if tok == "}":
                stack.pop()
            elif word == "JOINT":
                stack.append(self._open_joint(line, stack[-1]))
            elif word == "END":
                self._end_site(line, stack[-1])
            elif tok == "{":
                raise t.error("unbalanced braces: '{' without a JOINT or End Site before it", line)
            elif word in ("ROOT", "MOTION"):
                raise t.error(
                    f"unbalanced braces: '{tok}' inside joint '{self.names[stack[-1]]}' "
                    f"opened on line {self.lines[stack[-1]]} (missing '}}')",
                    line,
                )
            else:
                raise t.error(f"unexpected '{tok}' in joint '{self.names[stack[-1]]}'", line)
        tok = t.peek()
        if tok is not None:
            if tok[0] == "}":
                raise t.error("unbalanced braces: '}' after the ROOT joint was closed", tok[1])
            if tok[0].upper() == "ROOT":
                raise t.error("more than one ROOT is not supported", tok[1])
            raise t.error(f"expected MOTION after the hierarchy, found '{tok[0]}'", tok[1])

    def _open_joint(self, line: int, parent: int) -> int:
        t = self.t
        name = " ".join(t.rest_of_line(line))
        if not name:
            raise t.error("joint without a name", line)
        if name in self.names:
            first = self.lines[self.names.index(name)]
            raise t.error(f"duplicated joint name '{name}' (first defined on line {first})", line)
        t.expect("{", f"after joint '{name}'")
        self.names.append(name)
        self.lines.append(line)
        self.parents.append(parent)
        self.offsets.append(self._offset(f"joint '{name}'"))
        self.channels.append(self._channels(name, line))
        return len(self.names) - 1

    def _offset(self, owner: str) -> list[float]:
        t = self.t
        tok, line = t.next(f"OFFSET of {owner}")
        if tok.upper() != "OFFSET":
            raise t.error(f"expected 'OFFSET x y z' for {owner}, found '{tok}'", line)
        values = t.rest_of_line(line)
        if len(values) != 3:
            raise t.error(f"OFFSET of {owner} needs 3 numbers, got {len(values)}", line)
        xyz = [_number(t, v, line, f"OFFSET of {owner}") for v in values]
        if max(abs(v) for v in xyz) > MAX_OFFSET:
            raise t.error(
                f"OFFSET of {owner} is implausibly large ({' '.join(values)}; limit {MAX_OFFSET:g} in any unit)",
                line,
            )
        return xyz

    def _channels(self, name: str, joint_line: int) -> tuple[str, ...]:
        t = self.t
        tok, line = t.next(f"CHANNELS of joint '{name}'")
        if tok.upper() != "CHANNELS":
            raise t.error(f"expected 'CHANNELS n ...' for joint '{name}', found '{tok}'", line)
        words = t.rest_of_line(line)
        if not words or words[0] not in ("3", "6"):
            got = words[0] if words else "nothing"
            raise t.error(f"CHANNELS of joint '{name}' must be 3 or 6, got {got}", line)
        count = int(words[0])
        names = words[1:]
        if len(names) != count:
            raise t.error(f"CHANNELS {count} of joint '{name}' lists {len(names)} channel names", line)
        parsed = [_CHANNEL.match(c) for c in names]
        for c, m in zip(names, parsed):
            if m is None:
                raise t.error(f"unknown channel '{c}' in joint '{name}' (expected X/Y/Z position/rotation)", line)
        kinds = [(m.group(1).lower(), m.group(2).lower()) for m in parsed]
        rots = [a for a, k in kinds if k == "rotation"]
        poss = [a for a, k in kinds if k == "position"]
        if sorted(rots) != list(_AXES) or (count == 6 and sorted(poss) != list(_AXES)):
            raise t.error(
                f"joint '{name}' must have one rotation channel per axis"
                + (" and one position channel per axis" if count == 6 else "")
                + f", got {' '.join(names)}",
                line,
            )
        return tuple(f"{a.upper()}{k}" for a, k in kinds)

    def _end_site(self, line: int, joint: int) -> None:
        t = self.t
        tok, line2 = t.next("'Site' after 'End'")
        if tok.upper() != "SITE":
            raise t.error(f"expected 'End Site', found 'End {tok}'", line2)
        if joint in self.end_sites:
            raise t.error(f"joint '{self.names[joint]}' has a second End Site", line)
        t.expect("{", "after End Site")
        self.end_sites[joint] = np.array(self._offset(f"the End Site of '{self.names[joint]}'"))
        t.expect("}", f"closing the End Site of '{self.names[joint]}'")


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
        frame_time = _float(time_text)
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
            _float(text)
        except ValueError:
            return BVHError(path, f"{shown(text)} is not a number", number)
    odd = next(ch for ch in line if not ch.isascii())
    return BVHError(path, f"non-ASCII character U+{ord(odd):04X} between the numbers of a motion row", number)


def _motion_data(path: str, lines: _Lines, columns: int, frames: int, frames_line: int,
                 keep: int, room: int) -> np.ndarray:  # fmt: skip
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
                raise BVHError(path, f"wrong number of values on frame {done + len(rows) + 1}: expected {columns}, "
                                     f"got {len(parts)}", lines.count)  # fmt: skip
            if done + len(rows) >= frames:
                raise BVHError(path, f"more data rows than the header's Frames: {frames} (line {frames_line})",
                               lines.count)  # fmt: skip
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
        raise BVHError(path, f"header says Frames: {frames} but only {done} data rows follow (file truncated?)",
                       frames_line)  # fmt: skip
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
    tokens = _Tokens(path, header + (["MOTION"] if motion_found else []), len(header))
    hier = _Hierarchy(tokens)
    hier.parse()
    if not motion_found:
        raise BVHError(path, "missing MOTION section after the hierarchy", src.count or 1)
    if not motion_alone:
        raise BVHError(path, "MOTION must be alone on its line", src.count)
    frames, frame_time, frames_line = _motion_header(path, src)
    columns = sum(len(c) for c in hier.channels)
    room = frames if size is None else size // (2 * columns) + 1
    data = _motion_data(path, src, columns, frames, frames_line, frames if keep is None else keep, room)
    return ParsedBVH(hier.names, hier.parents, hier.offsets, hier.channels, hier.end_sites, frame_time, data,
                     frames)  # fmt: skip
