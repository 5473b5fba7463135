"""Write files atomically: to a temporary file beside the target, then rename.

A crash or an exception mid-write leaves the previous file (or none), never a half
written one. Temporary files are named ``.<name>.tmp-<pid>-<random><suffix>`` beside
the target, so they are recognisable:

* an exception, Ctrl-C (SIGINT), SIGTERM or SIGHUP during a write removes the temporary
  file (a handler is installed for SIGTERM/SIGHUP while a write is in progress, when the
  program has not set its own);
* a run killed with SIGKILL cannot clean up; the next write to the same output removes
  the temporary files of writers that are no longer running: their pid (in the name) is
  not a process here *and* the file is not locked. Every writer holds an exclusive
  ``flock`` on its temporary file until it is renamed, which the kernel releases when
  the writer dies however it dies; the lock keeps the files of writers this process
  cannot see (another pid namespace, another host on a shared folder) from being taken
  for stale.

An output that is a symlink is written through: the temporary file is made beside the
link's final target and renamed over it, so the link stays and the target changes (as
editors do). A dangling link creates its target when the target's folder exists; a
link into a missing folder, a symlink loop and a target that is not a regular file (a
FIFO, a device) are errors.

The new file gets the permissions of the file it replaces; a new output gets those a
plain ``open(path, "w")`` would give (``mkstemp`` creates files readable by the owner
only).
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import stat
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from engine.errors import OutputError

try:
    import fcntl
except ImportError:  # Windows: no flock; the pid in the name alone tells stale files
    fcntl = None  # type: ignore[assignment]

#: Temporary files being written by this process (removed on SIGTERM/SIGHUP).
_LIVE: set[Path] = set()
_LOCK = threading.Lock()
_HANDLED = (signal.SIGTERM, signal.SIGHUP)
_previous: dict[int, object] = {}


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def temp_prefix(path: Path) -> str:
    """Start of the name of every temporary file written for ``path``."""
    return f".{path.name}.tmp-"


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


def _locked(path: str) -> bool:
    """Whether a writer holds the ``flock`` of the temporary file ``path``."""
    if fcntl is None:
        return False
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return True  # unreadable: not ours to judge
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)  # releases the probe's lock
    return False


def remove_stale(path: str | Path) -> list[Path]:
    """Remove temporary files left beside ``path`` by writers that died (SIGKILL, power
    loss); returns what was removed. Files of running writers are kept: a pid that is
    alive here, or a file that is locked."""
    path = Path(path)
    prefix = temp_prefix(path)
    pattern = re.compile(re.escape(prefix) + r"(\d+)-")
    removed: list[Path] = []
    try:
        entries = list(os.scandir(path.parent if str(path.parent) else "."))
    except OSError:
        return removed
    for entry in entries:
        m = pattern.match(entry.name)
        if m and entry.is_file(follow_symlinks=False) and not _pid_alive(int(m.group(1))) and not _locked(entry.path):
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


def write_target(path: str | Path) -> Path:
    """The file a write to ``path`` replaces: ``path``, or its final target if it is a
    symlink (any depth, relative or absolute).

    Raises
    ------
    OutputError
        For a symlink loop, a link whose target folder does not exist, and an existing
        target that is not a regular file (a FIFO, a device, a folder).
    """
    path = Path(path)
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    if target.is_symlink():  # realpath gives up on a loop
        raise OutputError(f"{path}: cannot write: symlink loop")
    if target != path and not target.parent.is_dir():
        raise OutputError(f"{path}: cannot write: it links to {target}, whose folder does not exist")
    try:
        mode = os.stat(target).st_mode
    except OSError:
        return target
    if not stat.S_ISREG(mode):
        where = f"it links to {target}, which" if target != path else "it"
        raise OutputError(f"{path}: cannot write: {where} is not a regular file")
    return target


def _cleanup_live() -> None:
    with _LOCK:
        live = list(_LIVE)
    for tmp in live:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _on_signal(signum: int, frame: object) -> None:
    _cleanup_live()
    prev = _previous.get(signum, signal.SIG_DFL)
    if callable(prev):
        prev(signum, frame)
        return
    signal.signal(signum, signal.SIG_DFL)  # die of the same signal, as without us
    os.kill(os.getpid(), signum)


def _install_handlers() -> None:
    """Clean temporary files on SIGTERM/SIGHUP (main thread only; keeps a handler the
    program set itself by calling it afterwards)."""
    if threading.current_thread() is not threading.main_thread():
        return
    for sig in _HANDLED:
        try:
            current = signal.getsignal(sig)
            if current is _on_signal or current == signal.SIG_IGN:
                continue
            _previous[sig] = current
            signal.signal(sig, _on_signal)
        except (ValueError, OSError):  # not the main interpreter thread
            continue


@contextlib.contextmanager
def atomic_path(path: str | Path, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``path`` (the final target
    of ``path`` when it is a symlink: :func:`write_target`).

    ``suffix`` lets writers that insist on an extension (``np.savez`` adds ``.npz``)
    get one: pass the target's suffix."""
    given = Path(path)
    lock = -1
    try:
        given.parent.mkdir(parents=True, exist_ok=True)
        path = write_target(given)
        remove_stale(path)
        try:
            mode = os.stat(path).st_mode & 0o7777
        except OSError:
            mode = 0o666 & ~_umask()
        _install_handlers()
        lock, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"{temp_prefix(path)}{os.getpid()}-", suffix=suffix)
        if fcntl is not None:
            fcntl.flock(lock, fcntl.LOCK_EX)  # held until the rename: the file is not stale
    except OutputError:
        raise
    except OSError as exc:
        if lock >= 0:
            os.close(lock)
        raise OutputError(f"{given}: cannot write ({exc.strerror or exc})") from None
    tmp_path = Path(tmp)
    with _LOCK:
        _LIVE.add(tmp_path)
    try:
        try:
            yield tmp_path
            os.chmod(tmp_path, mode)
            os.replace(tmp_path, path)
        except OSError as exc:  # disk full, folder removed or made read-only meanwhile
            raise OutputError(f"{given}: cannot write ({exc.strerror or exc})") from exc
    finally:
        with _LOCK:
            _LIVE.discard(tmp_path)
        tmp_path.unlink(missing_ok=True)
        os.close(lock)


def write_bytes(path: str | Path, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | Path, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))
