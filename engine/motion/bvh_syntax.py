"""The HIERARCHY section of a BVH file and its numbers: a tokenizer whose tokens remember
their line and an iterative descent parser (deep hierarchies cannot hit Python's
recursion limit), used by :mod:`engine.motion.bvh_parser`."""

from __future__ import annotations

import math
import re

import numpy as np

from engine.errors import BVHError

#: Largest accepted absolute OFFSET component, in the file's units (cm, m, inches...).
MAX_OFFSET = 1e4

_AXES = "xyz"
_CHANNEL = re.compile(r"^([xyz])(position|rotation)$", re.IGNORECASE)
_TOKEN = re.compile(r"[{}]|[^\s{}]+")
#: A number as BVH files write it: ASCII digits, sign, point, exponent. Python's ``float``
#: and ``int`` also take other scripts' digits ('\u0663') and underscores ('1_000'),
#: which other BVH readers refuse; ``str.isdigit`` even takes '\u00b2', which ``int`` does not.
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = ("nan", "inf", "infinity")


class Tokens:
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


def plain_float(text: str) -> float:
    """``float(text)`` for a :data:`_DECIMAL` or a spelling of NaN/infinity (the callers
    name those as not finite); ``ValueError`` for anything else."""
    if _DECIMAL.fullmatch(text) is None and text.lstrip("+-").lower() not in _NON_FINITE:
        raise ValueError(f"not a BVH number: {text!r}")
    return float(text)


def _number(tokens: Tokens, text: str, line: int, what: str) -> float:
    try:
        value = plain_float(text)
    except ValueError:
        raise tokens.error(f"{what}: '{text}' is not a number", line) from None
    if not math.isfinite(value):
        raise tokens.error(f"{what}: value {text} is not finite", line)
    return value


class Hierarchy:
    """Recursive-descent parse of the HIERARCHY section (iterative: no recursion limit)."""

    def __init__(self, tokens: Tokens):
        self.t = tokens
        self.names: list[str] = []
        self.lines: list[int] = []
        self.parents: list[int] = []
        self.offsets: list[list[float]] = []
        self.channels: list[tuple[str, ...]] = []
        self.end_sites: dict[int, np.ndarray] = {}

    def parse(self) -> None:
        t = self.t
        first = t.peek()
        if first is None or first[0].upper() != "HIERARCHY":
            raise t.error("missing HIERARCHY: a BVH file starts with the word HIERARCHY", first[1] if first else 1)
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
        after = t.peek()
        if after is not None:
            if after[0] == "}":
                raise t.error("unbalanced braces: '}' after the ROOT joint was closed", after[1])
            if after[0].upper() == "ROOT":
                raise t.error("more than one ROOT is not supported", after[1])
            raise t.error(f"expected MOTION after the hierarchy, found '{after[0]}'", after[1])

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
        parsed = []
        for c in names:
            m = _CHANNEL.match(c)
            if m is None:
                raise t.error(f"unknown channel '{c}' in joint '{name}' (expected X/Y/Z position/rotation)", line)
            parsed.append(m)
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
