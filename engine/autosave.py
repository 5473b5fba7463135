"""Autosave files: a window's unsaved document, kept on disk while the program runs so a
crash or a kill loses at most the last few seconds of work.

One running program is one *autosave session* in a per-user folder (the GUI passes it:
:func:`app.crash_report.state_folder`)::

    autosave-<id>.lock          held with ``flock`` while the program runs
    autosave-<id>-<doc>.json    one document per window (``studio``, ``pose1``, ``pose2``...)
    autosave-<id>-<doc>.npz     a document's edited clip, exactly (range re-solves)

Every file is written to a temporary name and renamed (:mod:`engine.atomic`), so a kill
in the middle of a write leaves the previous autosave. A clean quit removes the
session's files. The kernel releases the lock of a program that dies however it dies
(SIGKILL included), so an unlocked session left in the folder is the work of a program
that did not quit cleanly: :func:`left_sessions` finds them and the next start offers to
recover the newest. Without ``flock`` (Windows) a session counts as left when no
process has its pid.

The documents are the windows' own scene dicts (:meth:`engine.studio.session.Session.to_scene`,
:func:`engine.authoring.recovery.document`), so recovery reads them with the scene
readers and their checks; this module adds only the envelope::

    {"format": "dragposer-autosave", "version": 1, "document": "studio", "saved": 1733380000.0,
     "scene": {...}}
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.atomic import atomic_path, write_text
from engine.errors import UserError
from engine.input_files import read_json
from engine.motion.clip import Motion

try:
    import fcntl
except ImportError:  # Windows: the pid alone tells a left session
    fcntl = None  # type: ignore[assignment]

FORMAT = "dragposer-autosave"
VERSION = 1
_PREFIX = "autosave-"


def is_document(name: str) -> bool:
    """Whether ``name`` names a document: ``studio`` (the main window) or ``pose<N>``
    (the N-th pose window)."""
    return name == "studio" or (name.startswith("pose") and name[4:].isdigit())


def _pid_running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


class AutosaveSession:
    """This program's autosave files in ``folder`` (made if missing).

    Raises
    ------
    UserError
        When the folder cannot be made or written, naming it.
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.id = f"{os.getpid()}-{secrets.token_hex(3)}"
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            self._lock = os.open(self.folder / f"{_PREFIX}{self.id}.lock", os.O_WRONLY | os.O_CREAT, 0o600)
        except OSError as exc:
            raise UserError(f"{self.folder}: cannot keep autosave files there ({exc.strerror or exc})") from None
        if fcntl is not None:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # a fresh name: never held
        self._clips: dict[str, Motion] = {}  # the edited clip last written, per document

    def path(self, doc: str, suffix: str = ".json") -> Path:
        """Where document ``doc`` (:func:`is_document`) is kept."""
        if not is_document(doc):
            raise ValueError(f"unknown autosave document {doc!r}")
        return self.folder / f"{_PREFIX}{self.id}-{doc}{suffix}"

    def write(self, doc: str, scene: dict[str, Any], clip: Motion | None = None) -> Path:
        """Keep ``scene`` (plain JSON) as document ``doc``, with ``clip`` (an edited clip
        the scene cannot name by path) beside it; the clip is written only when it is
        another object than the one last written."""
        envelope: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "document": doc,
            "saved": time.time(),
            "scene": scene,
        }
        if clip is not None:
            if self._clips.get(doc) is not clip:
                save_clip(self.path(doc, ".npz"), clip)
                self._clips[doc] = clip
            envelope["edited_clip"] = self.path(doc, ".npz").name
        elif self._clips.pop(doc, None) is not None:
            self.path(doc, ".npz").unlink(missing_ok=True)
        out = self.path(doc)
        write_text(out, json.dumps(envelope, allow_nan=False))
        return out

    def remove(self, doc: str) -> None:
        """Drop document ``doc`` (saved, or its window closed cleanly)."""
        self._clips.pop(doc, None)
        for suffix in (".json", ".npz"):
            self.path(doc, suffix).unlink(missing_ok=True)

    def close(self) -> None:
        """A clean quit: remove every file of the session and release its lock."""
        self._clips.clear()
        for path in self.folder.glob(f"{_PREFIX}{self.id}-*"):
            path.unlink(missing_ok=True)
        self._release(remove_lock=True)

    def abandon(self) -> None:
        """Release the lock and keep the files, as a killed program does (tests)."""
        self._release(remove_lock=False)

    def _release(self, remove_lock: bool) -> None:
        if self._lock < 0:
            return
        if remove_lock:
            (self.folder / f"{_PREFIX}{self.id}.lock").unlink(missing_ok=True)
        os.close(self._lock)  # releases the flock
        self._lock = -1


@dataclass
class LeftSession:
    """The files of a program that did not quit cleanly: ``documents`` maps a document
    name to its JSON file; ``saved`` is the newest document's save time (seconds since
    the epoch)."""

    folder: Path
    id: str
    documents: dict[str, Path] = field(default_factory=dict)
    saved: float = 0.0

    def read(self, doc: str) -> tuple[dict[str, Any], Motion | None]:
        """Document ``doc``'s scene and its edited clip (None when it has none).

        Raises
        ------
        UserError
            An unreadable or malformed file, naming it and the field.
        """
        path = self.documents[doc]
        envelope = read_json(path, "autosave")
        where = str(path)
        if not isinstance(envelope, dict) or envelope.get("format") != FORMAT:
            raise UserError(f"{where}: not an autosave file (field 'format' is not {FORMAT!r})")
        if envelope.get("version") != VERSION:
            raise UserError(f"{where}: field 'version' is {envelope.get('version')!r}; this build reads {VERSION}")
        scene = envelope.get("scene")
        if not isinstance(scene, dict):
            raise UserError(f"{where}: field 'scene' must be an object")
        clip_name = envelope.get("edited_clip")
        if clip_name is None:
            return scene, None
        if not isinstance(clip_name, str) or Path(clip_name).name != clip_name:
            raise UserError(f"{where}: field 'edited_clip' must be a file name beside it")
        return scene, load_clip(self.folder / clip_name)

    def discard(self) -> None:
        """Remove the session's files (recovered, or declined)."""
        for path in [*self.folder.glob(f"{_PREFIX}{self.id}-*"), self.folder / f"{_PREFIX}{self.id}.lock"]:
            with contextlib.suppress(OSError):
                path.unlink()


def _locked(path: Path) -> bool:
    """Whether a running program holds the lock ``path``."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return False  # gone: nobody holds it
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)  # releases the probe's lock
    return False


def left_sessions(folder: str | Path) -> list[LeftSession]:
    """Sessions in ``folder`` whose program no longer runs and that hold a document,
    newest first (see the module doc). The lock of such a program that had nothing
    unsaved is removed on the way."""
    folder = Path(folder)
    found: dict[str, LeftSession] = {}
    if fcntl is not None and folder.is_dir():
        for lock in folder.glob(f"{_PREFIX}*.lock"):
            ident = lock.name[len(_PREFIX) : -len(".lock")]
            if not any(folder.glob(f"{_PREFIX}{ident}-*")) and not _locked(lock):
                lock.unlink(missing_ok=True)
    for path in folder.glob(f"{_PREFIX}*.json") if folder.is_dir() else ():
        stem = path.name[len(_PREFIX) : -len(".json")]
        ident, _, doc = stem.rpartition("-")
        if not is_document(doc) or not ident:
            continue
        lock = folder / f"{_PREFIX}{ident}.lock"
        pid = ident.split("-", 1)[0]
        if fcntl is not None:
            if _locked(lock):
                continue
        elif pid.isdigit() and _pid_running(int(pid)):
            continue
        left = found.setdefault(ident, LeftSession(folder, ident))
        left.documents[doc] = path
        with contextlib.suppress(OSError):
            left.saved = max(left.saved, path.stat().st_mtime)
    return sorted(found.values(), key=lambda s: s.saved, reverse=True)


def save_clip(path: str | Path, motion: Motion) -> None:
    """Write ``motion`` exactly (float64 arrays, offsets, fps, name) as ``.npz``, atomically."""
    with atomic_path(path, suffix=".npz") as tmp:
        np.savez(
            tmp,
            local_rot=motion.local_rot,
            root_pos=motion.root_pos,
            offsets=motion.skeleton.offsets,
            fps=np.float64(motion.fps),
            name=np.array(motion.name),
            start=np.int64(motion.start),
        )


def load_clip(path: str | Path) -> Motion:
    """Read a clip :func:`save_clip` wrote; errors name the file."""
    try:
        with np.load(Path(path), allow_pickle=False) as d:
            return Motion(
                d["local_rot"],
                d["root_pos"],
                sk.Skeleton(offsets=np.array(d["offsets"], float)),
                float(d["fps"]),
                str(d["name"]),
                int(d["start"]) if "start" in d else 0,  # files autosaved before trimming had none
            )
    except (OSError, ValueError, KeyError) as exc:
        raise UserError(f"{path}: cannot read the autosaved clip ({exc})") from None
