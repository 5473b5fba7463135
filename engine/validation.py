"""One declarative validation layer for everything that enters the program from outside.

Every input kind has one *schema* here: a mapping from field name to a spec
(:class:`Num`, :class:`Choice`, :class:`Flag`). Commands, loaders and the studio call the ``check_*``
functions at their edges, before any work starts; a failure is a
:class:`ValidationError` (a :class:`~engine.errors.UserError`, so the CLI prints one
line and exits with status 2) that names the file or flag, the field, the value (cut
short) and the allowed range.

Schemas
-------
``CLI``        command-line numbers (``--iterations``, ``--fps``, ``--seed``...)
``MANIFEST``   one entry of a ``manifest.json`` beside a clip
``BVH_HEADER`` ``Frames:`` / ``Frame Time:`` of a BVH file
``SKELETON``   plausibility of a retargeted subject (height, root travel)

The optimizer settings' schema (``--set KEY=VALUE``, a scene's ``settings``, the
studio's panel) is generated from the metadata of the settings' own fields:
:data:`engine.solver.settings.SETTINGS`.

The ``config`` of a weights file is checked by :mod:`engine.models.weights_check`.

Files
-----
:func:`check_input_file` accepts only regular files (no FIFO, device, directory or
symlink loop) below a size limit per kind (:data:`MAX_BYTES`), checked before a byte
is read; :func:`check_output_path` refuses an output that is a folder or cannot be
written, before the solve. Reading a checked file (bounded bytes, UTF-8 text, safe
JSON and TOML) is :mod:`engine.input_files`. See ``docs/limits.md`` for the
user-facing table.
"""

from __future__ import annotations

import difflib
import math
import os
import stat
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from engine.atomic import write_target
from engine.errors import OutputError, UserError

#: Longest piece of user input quoted back in an error message (characters).
MAX_SHOWN = 40
#: Largest file read per kind, bytes (checked with ``stat`` before reading).
MAX_BYTES = {
    "BVH file": 1 << 30,
    "AMC file": 1 << 30,
    "ASF file": 16 << 20,
    "scene": 16 << 20,
    "manifest": 16 << 20,
    "weights file": 1 << 30,
    "checkpoint": 4 << 30,
    "config": 1 << 20,
    "tracker recording": 1 << 30,
    "tracker mapping": 1 << 20,
    "rig mapping": 1 << 20,
    "rig profile": 1 << 20,
}
#: Longest line of a line-based text input (a tracker recording), bytes.
MAX_LINE_BYTES = 1 << 16


class ValidationError(UserError):
    """An input outside its schema; ``str()`` is one line naming where, field and range."""


def shown(value: Any, limit: int = MAX_SHOWN) -> str:
    """``repr`` of a user value cut to ``limit`` characters (a 5 MB token stays short)."""
    try:
        text = repr(value)
    except ValueError:  # an int too long for repr (Python's digit limit)
        text = "<a very long number>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_known_fields(value: Mapping[str, Any], known: Iterable[str], where: str) -> None:
    """Refuse any key of ``value`` outside ``known``: a misspelt key would otherwise be
    read as absent and its default used without a word (``keyz`` would bake a clip with no
    keys). The message names each unknown key and the nearest known one.

    Raises
    ------
    UserError
        ``<where>: unknown field 'keyz' (did you mean 'keys'?); known: ...``.
    """
    known = sorted(known)
    unknown = sorted((k for k in value if k not in known), key=str)
    if not unknown:
        return
    parts = []
    for key in unknown:
        near = difflib.get_close_matches(str(key), known, n=1, cutoff=0.6)
        parts.append(f"{shown(key)} (did you mean {near[0]!r}?)" if near else shown(key))
    noun = "field" if len(unknown) == 1 else "fields"
    raise UserError(f"{where}: unknown {noun} {', '.join(parts)}; known: {', '.join(known)}")


def one_line(message: str, limit: int = 500) -> str:
    """A message on one line of at most ``limit`` characters."""
    text = " ".join(part.strip() for part in str(message).splitlines() if part.strip())
    return text if len(text) <= limit else text[: limit - 3] + "..."


@dataclass(frozen=True)
class Num:
    """A finite number in ``[lo, hi]`` (``lo`` excluded when ``open_lo``).

    ``integer`` requires a whole number (a float like 6.5 is refused, 6.0 is taken
    as 6); ``unit`` is shown in the message."""

    lo: float
    hi: float
    integer: bool = False
    unit: str = ""
    open_lo: bool = False

    def describe(self) -> str:
        kind = "a whole number" if self.integer else "a number"
        left = "(" if self.open_lo else "["
        unit = f" {self.unit}" if self.unit else ""
        fmt = "{:d}" if self.integer else "{:g}"
        lo, hi = (int(self.lo), int(self.hi)) if self.integer else (self.lo, self.hi)
        return f"{kind} in {left}{fmt.format(lo)}, {fmt.format(hi)}]{unit}"

    def check(self, value: Any) -> int | float:
        """The value, converted; ``ValueError`` with the reason otherwise."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            if type(value).__module__ == "numpy" and hasattr(value, "item"):
                return self.check(value.item())
            raise ValueError("not a number")
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError("not finite")
        if self.integer:
            if isinstance(value, float) and not value.is_integer():
                raise ValueError("not a whole number")
        ok_lo = value > self.lo if self.open_lo else value >= self.lo
        if not (ok_lo and value <= self.hi):
            raise ValueError("out of range")
        return int(value) if self.integer else float(value)


@dataclass(frozen=True)
class Choice:
    """One of a fixed set of strings (``summary`` replaces the list in messages when
    the set is long, e.g. "a joint name or 'none'")."""

    options: tuple[str, ...]
    summary: str = ""

    def describe(self) -> str:
        return self.summary or "one of " + ", ".join(self.options)

    def check(self, value: Any) -> str:
        if not isinstance(value, str) or value not in self.options:
            raise ValueError("not allowed")
        return value


@dataclass(frozen=True)
class Flag:
    """``true`` or ``false`` (a bool; numbers and strings are refused)."""

    def describe(self) -> str:
        return "true or false"

    def check(self, value: Any) -> bool:
        if type(value).__module__ == "numpy" and hasattr(value, "item"):
            value = value.item()
        if not isinstance(value, bool):
            raise ValueError("not a boolean")
        return value


Spec = Num | Choice | Flag
Schema = Mapping[str, Spec]

#: Command-line numbers, by argparse ``dest``.
CLI: Schema = {
    "iterations": Num(1, 10_000, integer=True),
    "max_frames": Num(1, 10_000_000, integer=True),
    "lr": Num(0, 10, open_lo=True),
    "faulty": Num(0, 1),
    "noise_pos": Num(0, 1, unit="m"),
    "noise_rot": Num(0, 180, unit="degrees"),
    "seed": Num(0, 2**32 - 1, integer=True),
    "fps": Num(1, 1000, unit="frames/s"),
    "epochs": Num(1, 100_000, integer=True),
    "batch_size": Num(1, 1 << 20, integer=True),
    "minutes": Num(0, 100_000, open_lo=True, unit="min"),
    "repeats": Num(1, 100_000, integer=True),
    "frames": Num(1, 10_000_000, integer=True),
    "warmup": Num(0, 100_000, integer=True),
}

#: One entry of ``manifest.json`` (``{"files": [{"path": ..., "fps": ...}, ...]}``).
MANIFEST: Schema = {"fps": Num(1, 1000, unit="frames/s")}

#: Values of a BVH header.
BVH_HEADER: Schema = {
    "Frames": Num(1, 10_000_000, integer=True),
    "Frame Time": Num(0.001, 1.0, unit="s (1 to 1000 frames/s)"),
}

#: A retargeted subject: standing height and how far the root may travel.
SKELETON: Schema = {
    "height": Num(0.5, 3.0, unit="m"),
    "root position": Num(-10_000, 10_000, unit="m"),
    "canonical frames": Num(1, 10_000_000, integer=True),
}


def check_value(spec: Spec, value: Any, where: str, field: str) -> Any:
    """``value`` converted by ``spec``; a :class:`ValidationError` naming ``where``/``field``
    and the allowed range otherwise."""
    try:
        return spec.check(value)
    except ValueError as exc:
        raise ValidationError(f"{where}: {field} = {shown(value)} is {exc}; allowed: {spec.describe()}") from None


def check_fields(schema: Schema, values: Mapping[str, Any], where: str) -> dict[str, Any]:
    """Check every key of ``values`` that ``schema`` knows; return them converted.

    Keys the schema does not list are returned unchanged (their owner checks them)."""
    out = dict(values)
    for key, value in values.items():
        spec = schema.get(key)
        if spec is not None and value is not None:
            out[key] = check_value(spec, value, where, key)
    return out


def check_args(args: Any, names: tuple[str, ...] | None = None) -> None:
    """Check the parsed command-line numbers of ``args`` (an ``argparse.Namespace``)
    against :data:`CLI`; the message names the flag (``--max-frames``)."""
    for name in names or tuple(CLI):
        value = getattr(args, name, None)
        if value is not None and name in CLI:
            setattr(args, name, check_value(CLI[name], value, "--" + name.replace("_", "-"), "value"))


# ---------------------------------------------------------------- files


def check_input_file(path: str | Path, kind: str = "BVH file", max_bytes: int | None = None) -> Path:
    """``path`` if it is a regular file no larger than the limit of ``kind``.

    Refuses, before reading a byte: missing files, folders, FIFOs, devices (a symlink to
    ``/dev/zero``), sockets, symlink loops and files above :data:`MAX_BYTES` ``[kind]``."""
    path = Path(path)
    limit = MAX_BYTES.get(kind, 1 << 30) if max_bytes is None else max_bytes
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ValidationError(f"{path}: cannot read {kind}: not found") from None
    except OSError as exc:  # ELOOP, EACCES, ENAMETOOLONG...
        raise ValidationError(f"{path}: cannot read {kind}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValidationError(f"{path}: cannot read {kind}: is a folder")
    if not stat.S_ISREG(st.st_mode):
        raise ValidationError(f"{path}: cannot read {kind}: not a regular file (a pipe, device or socket)")
    if st.st_size > limit:
        raise ValidationError(
            f"{path}: cannot read {kind}: {st.st_size:,} bytes is larger than the limit of {limit:,} bytes"
        )
    if not os.access(path, os.R_OK):
        raise ValidationError(f"{path}: cannot read {kind}: permission denied")
    return path


def check_output_path(path: str | Path, flag: str = "--out") -> Path:
    """``path`` if a file can be written there; checked before any work starts.

    Refuses a folder, a special file, an existing file without write permission and a
    parent that cannot be created or written. Missing parent folders are allowed (the
    writers create them) when the nearest existing ancestor is writable. A symlink is
    checked as its target, which is what the writers replace (:func:`engine.atomic.write_target`)."""
    path = Path(path)
    if path.is_dir():
        raise ValidationError(f"{flag} {path}: is a folder, expected a file name")
    if path.exists():
        if not path.is_file():
            raise ValidationError(f"{flag} {path}: exists and is not a regular file")
        if not os.access(path, os.W_OK):
            raise ValidationError(f"{flag} {path}: exists and is not writable (permission denied)")
    try:
        real = write_target(path)
    except OutputError as exc:
        raise ValidationError(f"{flag} {exc}") from None
    parent = real.parent if str(real.parent) else Path(".")
    ancestor = parent
    while not ancestor.exists():
        if ancestor.parent == ancestor:
            break
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise ValidationError(f"{flag} {path}: {ancestor} is not a folder")
    try:  # the only sure test (read-only mounts, /proc, root's access()): create a file there
        fd, probe = tempfile.mkstemp(dir=ancestor, prefix=f".{path.name[:40]}.probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ValidationError(f"{flag} {path}: cannot write in {ancestor} ({exc.strerror or exc})") from None
    return path


def check_output_dir(path: str | Path, flag: str = "--out") -> Path:
    """``path`` if it is (or can become) a writable folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValidationError(f"{flag} {path}: exists and is not a folder")
    check_output_path(path / "probe", flag)
    return path


# ---------------------------------------------------------------- documents


def check_manifest(doc: Any, where: str) -> list[dict]:
    """The ``files`` (BVH) and ``amc`` (ASF/AMC motions) entries of a manifest document,
    each with a checked ``fps``."""
    if not isinstance(doc, dict):
        raise ValidationError(f"{where}: a manifest is a JSON object with a 'files' list, got {type(doc).__name__}")
    out = []
    for key in ("files", "amc"):
        files = doc.get(key, [])
        if not isinstance(files, list):
            raise ValidationError(f"{where}: field '{key}' must be a list, got {type(files).__name__}")
        for i, entry in enumerate(files):
            if not isinstance(entry, dict):
                raise ValidationError(f"{where}: {key}[{i}] must be an object, got {type(entry).__name__}")
            for name in ("path", "skeleton"):
                if not isinstance(entry.get(name, ""), str):
                    raise ValidationError(f"{where}: {key}[{i}].{name} must be a string")
            out.append(check_fields(MANIFEST, entry, f"{where}: {key}[{i}]"))
    return out
