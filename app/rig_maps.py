"""Joint mapping files (``--rig-map MAP.toml``) in the studio.

When a BVH's rig cannot be mapped onto the canonical skeleton automatically, the Open
dialog asks the user to pick a mapping file or to have one suggested
(``dragposer-studio rig suggest``, written beside the BVH). A mapping that opened a file
is remembered for that file (in the studio's settings), so reopening it, loading a scene
on it or saving onto its rig uses the same mapping. docs/skeleton.md describes the format.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from PyQt6.QtCore import QSettings, QStandardPaths
from PyQt6.QtWidgets import QFileDialog, QMessageBox, QWidget

SETTINGS_KEY = "rig_maps"


class RigMaps:
    """BVH file -> its mapping file, stored as one JSON object under ``rig_maps``."""

    def __init__(self, settings: QSettings) -> None:
        self.settings = settings

    def _all(self) -> dict[str, str]:
        try:
            value = json.loads(str(self.settings.value(SETTINGS_KEY, "{}")))
        except ValueError:  # a hand-edited settings file: start again rather than fail
            return {}
        return {str(k): str(v) for k, v in value.items()} if isinstance(value, dict) else {}

    def get(self, bvh: str | Path) -> Path | None:
        """The mapping remembered for ``bvh`` if that file still exists."""
        found = self._all().get(str(Path(bvh).resolve()))
        return Path(found) if found and Path(found).is_file() else None

    def remember(self, bvh: str | Path, rig_map: str | Path) -> None:
        items = self._all()
        items[str(Path(bvh).resolve())] = str(Path(rig_map).resolve())
        self.settings.setValue(SETTINGS_KEY, json.dumps(items))


def suggestion_path(bvh: str | Path) -> Path:
    """Where a suggested mapping for ``bvh`` goes: ``NAME.rigmap.toml`` beside it (or in the
    studio's data folder when that folder is read-only), never over an existing file."""
    bvh = Path(bvh)
    folder = bvh.parent
    if not os.access(folder, os.W_OK):
        data = QStandardPaths.writableLocation(QStandardPaths.StandardLocation.AppDataLocation)
        folder = Path(data or Path.home()) / "rig-maps"
        folder.mkdir(parents=True, exist_ok=True)
    out, n = folder / f"{bvh.stem}.rigmap.toml", 2
    while out.exists():
        out, n = folder / f"{bvh.stem}.rigmap-{n}.toml", n + 1
    return out


def ask_unmapped(parent: QWidget, path: str, message: str) -> str:
    """Ask what to do with a file whose rig is not recognised: ``"pick"`` a mapping file,
    ``"suggest"`` one, or ``""`` (cancel)."""
    box = QMessageBox(
        QMessageBox.Icon.Warning,
        "Rig not recognised",
        f"{Path(path).name}: the joints could not be mapped onto the canonical skeleton.",
        QMessageBox.StandardButton.Cancel,
        parent,
    )
    box.setInformativeText(
        "Pick a joint mapping file (MAP.toml), or let the studio write a suggestion "
        "beside the file for you to check and complete."
    )
    box.setDetailedText(message)
    pick = box.addButton("Pick mapping file...", QMessageBox.ButtonRole.AcceptRole)
    suggest = box.addButton("Suggest a mapping", QMessageBox.ButtonRole.ActionRole)
    box.exec()
    clicked = box.clickedButton()
    return "pick" if clicked is pick else "suggest" if clicked is suggest else ""


def pick_rig_map(parent: QWidget, start: str) -> str:
    """A mapping file chosen by the user, or ``""``."""
    path, _ = QFileDialog.getOpenFileName(parent, "Joint mapping for this file", start, "Joint mapping (*.toml)")
    return path


def tell(parent: QWidget, title: str, message: str) -> None:
    QMessageBox.information(parent, title, message)
