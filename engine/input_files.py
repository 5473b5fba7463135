"""Reading files that come from outside: bytes, UTF-8 text, JSON and TOML, all bounded.

Each reader first checks the file with :func:`engine.validation.check_input_file`
(regular file, size limit of its kind in :data:`engine.validation.MAX_BYTES`) and never
reads past that limit. Every failure is one :class:`~engine.validation.ValidationError`
line naming the file and, where there is one, the line: a byte that is not UTF-8, a
JSON or TOML syntax error, nesting deeper than :data:`MAX_JSON_DEPTH`, a number with
too many digits. Checking the parsed values is the caller's part (the schemas of
:mod:`engine.validation`).
"""

from __future__ import annotations

import json
import os
import stat
import tomllib
from pathlib import Path
from typing import Any

from engine.validation import MAX_BYTES, ValidationError, check_input_file, one_line

#: Deepest JSON nesting accepted (scenes are 3-4 levels deep).
MAX_JSON_DEPTH = 64


def read_input_bytes(path: str | Path, kind: str, max_bytes: int | None = None) -> bytes:
    """The bytes of a checked input file (:func:`check_input_file`), never more than the limit."""
    path = check_input_file(path, kind, max_bytes)
    limit = MAX_BYTES.get(kind, 1 << 30) if max_bytes is None else max_bytes
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # swapped after the check
            raise ValidationError(f"{path}: not a regular file; expected a {kind}")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise ValidationError(f"{path}: cannot read {kind} ({exc.strerror or exc})") from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise ValidationError(f"{path}: {kind} is larger than the limit of {limit:,} bytes")
    return data


def read_input_text(path: str | Path, kind: str) -> str:
    """The text of a checked input file (:func:`read_input_bytes`); not UTF-8 is an error
    naming the file and the line of the bad byte."""
    raw = read_input_bytes(path, kind)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise ValidationError(f"{path}:{line}: {kind} is not UTF-8 text (byte 0x{raw[exc.start]:02x})") from None


def read_json(path: str | Path, kind: str) -> Any:
    """Parse a JSON input file safely: size limit, UTF-8, nesting depth, number length.

    Every failure is one :class:`ValidationError` line naming the file (and the line)."""
    text = read_input_text(path, kind)
    depth = _max_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise ValidationError(f"{path}: {kind} is nested {depth} levels deep; allowed: at most {MAX_JSON_DEPTH}")
    try:
        return json.loads(text, parse_constant=_no_constant)
    except json.JSONDecodeError as exc:
        raise ValidationError(f"{path}:{exc.lineno}: invalid JSON in {kind} ({exc.msg})") from None
    except ValueError as exc:  # too many digits, NaN/Infinity
        reason = "a number with too many digits" if "digits" in str(exc) else one_line(str(exc), 120)
        raise ValidationError(f"{path}: invalid JSON in {kind} ({reason})") from None


def read_toml(path: str | Path, kind: str) -> dict[str, Any]:
    """Parse a TOML input file safely: size limit, UTF-8 (the bad byte's line), syntax (line
    and column); every failure is one :class:`ValidationError` line naming the file."""
    text = read_input_text(path, kind)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValidationError(f"{path}: invalid TOML in {kind} ({one_line(str(exc), 160)})") from None
    except RecursionError:
        raise ValidationError(f"{path}: {kind} is nested too deeply") from None


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number")


def _max_depth(text: str) -> int:
    """Deepest ``[``/``{`` nesting outside strings (cheap, no recursion)."""
    depth = deepest = 0
    in_str = escaped = False
    for ch in text:
        if in_str:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def file_sha256(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes, read in 1 MiB chunks (which VAE a bank or a latent
    map belongs to, what data a prepared set was made from)."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
