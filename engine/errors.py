"""Error types shown to users: the message names the file, line or field at fault."""

from __future__ import annotations

import re
from pathlib import Path

#: Longest run of non-blank characters kept in a message (long enough for file paths);
#: longer user tokens are cut.
MAX_WORD = 256


def shorten_words(message: str, limit: int = MAX_WORD) -> str:
    """``message`` with every word longer than ``limit`` cut to ``limit`` characters plus
    an ellipsis, so a bad multi-megabyte token never reaches the terminal whole."""
    if len(message) <= limit:
        return message
    return re.sub(r"\S{%d,}" % (limit + 1), lambda m: m.group(0)[:limit] + "...", message)


class UserError(Exception):
    """A problem with the user's input or files; the CLI prints it without a traceback.

    Over-long words in the message (echoed user tokens) are cut (:func:`shorten_words`)."""

    def __init__(self, *args: object):
        if len(args) == 1 and isinstance(args[0], str):
            args = (shorten_words(args[0]),)
        super().__init__(*args)


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


class OutputError(UserError, OSError):
    """An output that cannot be written (disk full, read-only folder); also an
    :class:`OSError`, so callers that catch those keep working."""
