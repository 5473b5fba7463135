"""The save dialog of motion files: every format a writer knows (BVH, glTF binary, glTF
JSON; :data:`engine.motion.formats.MOTION_FORMATS`), one filter each, and a name typed
without an extension gets the chosen filter's."""

from __future__ import annotations

from pathlib import Path

from PyQt6.QtWidgets import QFileDialog, QWidget

from engine.motion.formats import MOTION_FORMATS

#: The dialog's filters, BVH first: ``"BVH motion (*.bvh);;glTF 2.0 binary (*.glb);;..."``.
MOTION_FILTERS = ";;".join(f"{what} (*{ext})" for ext, what in MOTION_FORMATS.items())


def with_filter_suffix(path: str, chosen: str) -> str:
    """``path``, with the extension of the ``chosen`` filter when it has none."""
    if Path(path).suffix:
        return path
    ext = next((e for e, what in MOTION_FORMATS.items() if chosen.startswith(what)), ".bvh")
    return path + ext


def ask_motion_path(parent: QWidget, title: str, suggested: str) -> str | None:
    """A motion file name from the save dialog, or None when cancelled. The format is the
    extension's (an unknown one is refused when writing, listing the known ones)."""
    path, chosen = QFileDialog.getSaveFileName(parent, title, suggested, MOTION_FILTERS)
    return with_filter_suffix(path, chosen) if path else None
