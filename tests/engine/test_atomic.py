"""Atomic writes leave the old file or the new one, never half of one."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from engine.atomic import atomic_path, write_text


def test_success_replaces_and_uses_normal_permissions(tmp_path):
    target = tmp_path / "out.txt"
    write_text(target, "hello")
    assert target.read_text() == "hello"
    mode = stat.S_IMODE(os.stat(target).st_mode)
    assert mode & 0o044, "file must be readable by others like a normal write (umask permitting)"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_failure_keeps_the_old_file_and_leaves_no_temp(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("crash mid-write")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_suffix_for_numpy(tmp_path):
    target = tmp_path / "a.npz"
    with atomic_path(target, suffix=".npz") as tmp:
        np.savez(tmp, x=np.arange(3))
    assert np.load(target)["x"].tolist() == [0, 1, 2]


def test_existing_permissions_are_kept(tmp_path):
    target = tmp_path / "secret.txt"
    target.write_text("old")
    os.chmod(target, 0o600)
    write_text(target, "new")
    assert target.read_text() == "new"
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o600


def _dead_pid() -> int:
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_stale_temp_files_of_dead_writers_are_removed_by_the_next_write(tmp_path):
    from engine.atomic import remove_stale, temp_prefix

    target = tmp_path / "out.bvh"
    stale = tmp_path / f"{temp_prefix(target)}{_dead_pid()}-abc.tmp"
    stale.write_bytes(b"x" * 1000)
    live = tmp_path / f"{temp_prefix(target)}{os.getpid()}-def.tmp"  # a writer still running
    live.write_bytes(b"y")
    other = tmp_path / ".other.bvh.tmp-1-abc.tmp"
    other.write_bytes(b"z")
    write_text(target, "new")
    assert not stale.exists(), "a dead writer's temp file is removed"
    assert live.exists() and other.exists(), "running writers' and other outputs' files are kept"
    assert remove_stale(target) == []


def test_sigterm_and_sigint_during_a_write_leave_no_temp_file(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    # The child sets Python's own Ctrl-C handler first: a suite started in the background by
    # a non-interactive shell (`cmd &`, as a CI runner may do) passes SIGINT on as ignored,
    # and Python then keeps it ignored, which would test the launcher rather than our code.
    script = (
        "import signal, sys, time\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from engine.atomic import atomic_path\n"
        "with atomic_path(sys.argv[1]) as tmp:\n"
        "    tmp.write_bytes(b'x' * 100000)\n"
        "    print('writing', flush=True)\n"
        "    time.sleep(60)\n"
    )
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    for sig in (signal.SIGTERM, signal.SIGINT):
        target = tmp_path / f"out{int(sig)}.bvh"
        proc = subprocess.Popen([sys.executable, "-c", script, str(target)], stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": repo})  # fmt: skip
        assert proc.stdout.readline().strip() == b"writing"
        assert any(p.name.startswith(f".{target.name}.tmp-") for p in tmp_path.iterdir())
        t0 = time.monotonic()
        proc.send_signal(sig)
        proc.wait(timeout=30)
        assert time.monotonic() - t0 < 30
        assert proc.returncode != 0
        assert list(tmp_path.iterdir()) == [], f"signal {sig!r} left {list(tmp_path.iterdir())}"
