"""Where every save dialog starts, and the check that a chosen file can be written.

A clip often comes from a folder the user cannot write in (a shared, read-only data
folder), so a save dialog does not simply start beside it. :func:`save_folder` picks,
in order:

1. the folder the user last saved into (one memory for every save dialog of the studio
   and the pose window, QSettings ``files/save_folder``), while it exists and is writable;
2. the source's folder (the open clip, the opened scene) when it is writable and not
   the studio's own ``assets/`` (the bundled example is no place for the user's files);
3. the home folder.

:func:`ask_save_path` is the save dialog itself (the name each caller suggests, in that
folder) and remembers the folder of the answer; :func:`remember_save_folder` is for a
file written without a dialog. :func:`check_writable` refuses a file whose folder cannot
be written, naming the folder, before long work (a re-solve, a render) starts.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from PyQt6.QtCore import QSettings
from PyQt6.QtWidgets import QFileDialog

from engine.errors import UserError

#: The studio's bundled files (the example clip): save dialogs do not offer this folder.
APP_ASSETS = Path(__file__).resolve().parents[1] / "assets"
#: QSettings key of the folder last saved into.
KEY = "files/save_folder"


def writable_folder(folder: str | Path) -> bool:
    """Whether ``folder`` is an existing folder the user may create files in."""
    return os.path.isdir(folder) and os.access(folder, os.W_OK | os.X_OK)


def save_folder(settings: QSettings | None, source: str | Path | None = None) -> Path:
    """The folder a save dialog starts in (see the module doc); ``source`` is the file
    (or folder) the saved thing comes from, None when there is none."""
    remembered = settings.value(KEY, "") if settings is not None else ""
    if remembered and writable_folder(str(remembered)):
        return Path(str(remembered))
    if source:
        folder = Path(source).resolve()
        folder = folder if folder.is_dir() else folder.parent
        if writable_folder(folder) and not folder.is_relative_to(APP_ASSETS):
            return folder
    return Path.home()


def remember_save_folder(settings: QSettings | None, path: str | Path) -> None:
    """Remember the folder of ``path`` (a file just chosen or written) for the next dialog."""
    if settings is not None and path:
        settings.setValue(KEY, str(Path(path).resolve().parent))


def ask_save_path(
    parent: Any, title: str, suggested: str | Path, filters: str, settings: QSettings | None
) -> tuple[str, str]:
    """The save dialog: ``(path, chosen filter)``, ``("", ...)`` when cancelled.
    ``suggested`` is the file offered (its folder from :func:`save_folder`); the folder
    of the answer is remembered in ``settings``."""
    path, chosen = QFileDialog.getSaveFileName(parent, title, str(suggested), filters)
    if path:
        remember_save_folder(settings, path)
    return path, chosen


def check_writable(path: str | Path) -> None:
    """Refuse ``path`` before any long work when its folder cannot be written.

    Raises
    ------
    UserError
        Naming the folder (not writable, missing, or a write there fails).
    """
    from engine.validation import check_output_path

    folder = Path(path).resolve().parent
    if folder.is_dir() and not os.access(folder, os.W_OK | os.X_OK):
        raise UserError(f"cannot write in {folder}: the folder is not writable; choose another folder")
    check_output_path(path, "cannot save")  # the sure test: a file made there (read-only mounts, root)
