"""Settings dataclasses from TOML files and ``--set key=value`` overrides (no torch)."""

from __future__ import annotations

import re
import tomllib
import typing
from pathlib import Path
from typing import Any

from engine.errors import UserError


def load_config(cls: type, path: Path | None = None, overrides: list[str] | None = None, **direct: Any):
    """Build dataclass ``cls`` from defaults, then a TOML file, then ``key=value`` overrides,
    then ``direct`` keyword values that are not None. Errors name the file and field."""
    values: dict[str, Any] = {}
    if path is not None:
        from engine.input_files import read_input_bytes

        raw = read_input_bytes(Path(path), "config")
        try:
            values.update(tomllib.loads(raw.decode("utf-8")))
        except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise UserError(f"{path}: cannot read config: {exc}") from exc
    hints = typing.get_type_hints(cls)
    values.update(parse_overrides(cls, overrides))
    values.update({k: v for k, v in direct.items() if v is not None})
    unknown = set(values) - set(hints)
    if unknown:
        raise UserError(f"{path or 'config'}: unknown settings {sorted(unknown)}")
    for key, val in values.items():
        if isinstance(val, list):
            values[key] = tuple(val)
    return cls(**values)


_INT = re.compile(r"[+-]?[0-9]+")
_FLOAT = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|[+-]?(inf|nan)", re.IGNORECASE)


def parse_overrides(cls: type, overrides: list[str] | None) -> dict[str, Any]:
    """``["key=value", ...]`` -> ``{key: value}`` typed by the fields of dataclass ``cls``;
    an unknown key or a value of the wrong type raises :class:`UserError` naming it."""
    hints = typing.get_type_hints(cls)
    values: dict[str, Any] = {}
    for item in overrides or []:
        if "=" not in item:
            raise UserError(f"--set {item!r}: expected key=value")
        key, raw = item.split("=", 1)
        key = key.strip()
        if key not in hints:
            raise UserError(f"--set {key}: unknown setting; known: {', '.join(sorted(hints))}")
        values[key] = parse_typed(key, raw.strip(), hints[key])
    return values


def parse_typed(key: str, raw: str, hint: Any) -> Any:
    """``raw`` (the text of ``--set key=raw``) as a value of type ``hint``: bool, str,
    int and float strictly, anything else as a TOML value; a :class:`UserError` names
    ``key`` when it is not one."""
    try:
        if hint is bool:
            if raw.lower() not in ("true", "false", "1", "0"):
                raise ValueError(raw)
            return raw.lower() in ("true", "1")
        if hint is str:
            return raw
        if hint in (int, float):
            # int()/float() also take Unicode digits and underscores ("٣", "1_0"): a typo
            # there should be an error, not a silently different number.
            if not (_INT if hint is int else _FLOAT).fullmatch(raw):
                raise ValueError(raw)
            return hint(raw)
        return tomllib.loads(f"v = {raw}")["v"]
    except (ValueError, tomllib.TOMLDecodeError) as exc:
        raise UserError(f"--set {key}={raw}: not a valid {getattr(hint, '__name__', hint)}") from exc
