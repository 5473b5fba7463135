"""Write files atomically: to a temporary file beside the target, then rename.

A crash or an exception mid-write leaves the previous file (or none), never a half
written one. Temporary files are named ``.<name>.tmp-<pid>-<random><suffix>`` beside
the target, so they are recognisable:

* an exception, Ctrl-C (SIGINT), SIGTERM or SIGHUP during a write removes the temporary
  file (a handler is installed for SIGTERM/SIGHUP while a write is in progress, when the
  program has not set its own);
* a run killed with SIGKILL cannot clean up; the next write to the same output removes
  the temporary files of writers that are no longer running (their pid is in the name).

The new file gets the permissions of the file it replaces; a new output gets those a
plain ``open(path, "w")`` would give (``mkstemp`` creates files readable by the owner
only).
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from engine.errors import OutputError

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


def remove_stale(path: str | Path) -> list[Path]:
    """Remove temporary files left beside ``path`` by writers that died (SIGKILL, power
    loss); returns what was removed. Files of running writers are kept."""
    path = Path(path)
    prefix = temp_prefix(path)
    pattern = re.compile(re.escape(prefix) + r"(\d+)-")
    removed = []
    try:
        entries = list(os.scandir(path.parent if str(path.parent) else "."))
    except OSError:
        return removed
    for entry in entries:
        m = pattern.match(entry.name)
        if m and entry.is_file(follow_symlinks=False) and not _pid_alive(int(m.group(1))):
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


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
    """Yield a temporary path to write; on success it replaces ``path``.

    ``suffix`` lets writers that insist on an extension (``np.savez`` adds ``.npz``)
    get one: pass the target's suffix."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale(path)
        try:
            mode = os.stat(path).st_mode & 0o7777
        except OSError:
            mode = 0o666 & ~_umask()
        _install_handlers()
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"{temp_prefix(path)}{os.getpid()}-", suffix=suffix)
        os.close(fd)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    tmp_path = Path(tmp)
    with _LOCK:
        _LIVE.add(tmp_path)
    try:
        try:
            yield tmp_path
            os.chmod(tmp_path, mode)
            os.replace(tmp_path, path)
        except OSError as exc:  # disk full, folder removed or made read-only meanwhile
            raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from exc
    finally:
        with _LOCK:
            _LIVE.discard(tmp_path)
        tmp_path.unlink(missing_ok=True)


def write_bytes(path: str | Path, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | Path, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))
