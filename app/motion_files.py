"""The save dialog of motion files: every format a writer knows (BVH, glTF binary, glTF
JSON; :data:`engine.motion.formats.MOTION_FORMATS`), one filter each, and a name typed
without an extension gets the chosen filter's."""

from __future__ import annotations

from pathlib import Path

from PyQt6.QtCore import QSettings
from PyQt6.QtWidgets import QWidget

from app.save_folder import ask_save_path
from engine.motion.formats import MOTION_FORMATS

#: The dialog's filters, BVH first: ``"BVH motion (*.bvh);;glTF 2.0 binary (*.glb);;..."``.
MOTION_FILTERS = ";;".join(f"{what} (*{ext})" for ext, what in MOTION_FORMATS.items())


def with_filter_suffix(path: str, chosen: str) -> str:
    """``path``, with the extension of the ``chosen`` filter when it has none."""
    if Path(path).suffix:
        return path
    ext = next((e for e, what in MOTION_FORMATS.items() if chosen.startswith(what)), ".bvh")
    return path + ext


def ask_motion_path(parent: QWidget, title: str, suggested: str, settings: QSettings | None) -> str | None:
    """A motion file name from the save dialog (:func:`app.save_folder.ask_save_path`,
    whose folder is remembered in ``settings``), or None when cancelled. The format is the
    extension's (an unknown one is refused when writing, listing the known ones)."""
    path, chosen = ask_save_path(parent, title, suggested, MOTION_FILTERS, settings)
    return with_filter_suffix(path, chosen) if path else None
