"""Error types shown to users: the message names the file, line or field at fault."""

from __future__ import annotations

from pathlib import Path


class UserError(Exception):
    """A problem with the user's input or files; the CLI prints it without a traceback."""


class BVHError(UserError):
    """A BVH file that cannot be read. ``str()`` reads ``file:line: message``."""

    def __init__(self, path: str | Path, message: str, line: int | None = None):
        self.path = str(path)
        self.line = line
        self.message = message
        where = f"{self.path}:{line}" if line is not None else self.path
        super().__init__(f"{where}: {message}")


class RigError(UserError):
    """A skeleton that matches no known rig profile."""


class ModelFileError(UserError):
    """A weights file that is missing, corrupt or of the wrong shape/version."""
