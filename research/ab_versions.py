"""Two versions of the ``engine`` package in one process, for interleaved A/B timing.

``EngineVersion(root)`` imports ``engine`` from ``root`` under its own module objects;
``with version:`` makes it the one that ``import engine...`` resolves to (the code's
lazy imports inside functions included), so calls into either version run that
version's code throughout. ``checkout(rev, into)`` writes ``engine/`` and
``assets/models`` of a git revision into a folder (``git archive``).
"""

from __future__ import annotations

import importlib
import subprocess
import sys
import tarfile
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _engine_modules() -> dict:
    return {k: v for k, v in sys.modules.items() if k == "engine" or k.startswith("engine.")}


def checkout(rev: str, into: Path) -> Path:
    """``engine/`` and ``assets/models`` of git revision ``rev`` under ``into``."""
    data = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev, "engine", "assets/models"], check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(into, filter="data")
    return into


class EngineVersion:
    """The ``engine`` package found under ``root`` (module doc)."""

    def __init__(self, root: Path, label: str) -> None:
        self.root, self.label = Path(root), label
        self.modules: dict = {}
        self._saved: dict = {}

    def __enter__(self) -> "EngineVersion":
        self._saved = _engine_modules()
        for name in self._saved:
            del sys.modules[name]
        sys.modules.update(self.modules)
        sys.path.insert(0, str(self.root))
        importlib.invalidate_caches()
        return self

    def __exit__(self, *exc) -> None:
        self.modules = _engine_modules()  # keeps what was imported meanwhile
        sys.path.remove(str(self.root))
        for name in self.modules:
            del sys.modules[name]
        sys.modules.update(self._saved)

    def module(self, name: str):
        """Import ``name`` (e.g. ``engine.methods``) from this version."""
        with self:
            return importlib.import_module(name)
