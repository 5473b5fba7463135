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
        proc = subprocess.Popen(
            [sys.executable, "-c", script, str(target)],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env={**os.environ, "PYTHONPATH": repo},
        )
        assert proc.stdout.readline().strip() == b"writing"
        assert any(p.name.startswith(f".{target.name}.tmp-") for p in tmp_path.iterdir())
        t0 = time.monotonic()
        proc.send_signal(sig)
        proc.wait(timeout=30)
        assert time.monotonic() - t0 < 30
        assert proc.returncode != 0
        assert list(tmp_path.iterdir()) == [], f"signal {sig!r} left {list(tmp_path.iterdir())}"


_WRITER = (
    "import sys, time\n"
    "from engine.atomic import atomic_path\n"
    "with atomic_path(sys.argv[1]) as tmp:\n"
    "    tmp.write_bytes(b'x' * 100000)\n"
    "    print('writing', flush=True)\n"
    "    time.sleep(120)\n"
)


def _writer(target):
    """A real process stopped in the middle of writing ``target``."""
    import subprocess
    import sys

    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    proc = subprocess.Popen(
        [sys.executable, "-c", _WRITER, str(target)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "PYTHONPATH": repo},
    )
    assert proc.stdout.readline().strip() == b"writing"
    return proc


def _temps(folder, target):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(f".{target.name}.tmp-"))


def test_the_temp_file_of_a_killed_writer_goes_with_the_next_write_and_a_live_one_stays(tmp_path):
    import signal

    target = tmp_path / "OUT.bvh"
    killed = _writer(target)
    killed_temp = _temps(tmp_path, target)
    live = _writer(target)
    both = _temps(tmp_path, target)
    try:
        killed.send_signal(signal.SIGKILL)
        killed.wait(timeout=30)
        assert _temps(tmp_path, target) == both, "SIGKILL leaves the temp file (nothing can clean it then)"
        write_text(target, "new")
        assert target.read_text() == "new"
        assert _temps(tmp_path, target) == sorted(set(both) - set(killed_temp)), "the live writer's file stays"
    finally:
        live.terminate()
        live.wait(timeout=30)
    assert _temps(tmp_path, target) == []


def test_a_locked_temp_file_is_kept_even_when_its_pid_is_not_visible(tmp_path):
    """A writer in another pid namespace or on another host sharing the folder: its pid
    means nothing here, its lock does."""
    import subprocess
    import sys

    from engine.atomic import temp_prefix

    target = tmp_path / "out.bvh"
    other = tmp_path / f"{temp_prefix(target)}{_dead_pid()}-abc.tmp"
    other.write_bytes(b"y")
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, sys, time\nf = open(sys.argv[1], 'rb')\n"
            "fcntl.flock(f, fcntl.LOCK_EX)\nprint('locked', flush=True)\ntime.sleep(120)\n",
            str(other),
        ],
        stdout=subprocess.PIPE,
    )
    try:
        assert holder.stdout.readline().strip() == b"locked"
        write_text(target, "new")
        assert other.exists(), "a locked temp file belongs to a running writer"
    finally:
        holder.kill()
        holder.wait(timeout=30)
    write_text(target, "newer")
    assert not other.exists(), "once its writer is gone the file is stale"


def test_a_symlinked_output_writes_its_target_and_keeps_the_link(tmp_path):
    real_dir, link_dir = tmp_path / "real", tmp_path / "links"
    real_dir.mkdir()
    link_dir.mkdir()
    target = real_dir / "clip.bvh"
    target.write_text("old")
    os.chmod(target, 0o640)
    link = link_dir / "clip.bvh"
    link.symlink_to(os.path.relpath(target, link_dir))
    chain = link_dir / "latest.bvh"
    chain.symlink_to("clip.bvh")  # a link to the link
    with atomic_path(chain) as tmp:
        assert tmp.parent == real_dir, "the temp file is made beside the target, so the rename is atomic"
        tmp.write_text("new")
    assert chain.is_symlink() and link.is_symlink()
    assert target.read_text() == "new" and not target.is_symlink()
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o640
    assert sorted(p.name for p in real_dir.iterdir()) == ["clip.bvh"]
    assert sorted(p.name for p in link_dir.iterdir()) == ["clip.bvh", "latest.bvh"]


def test_dangling_looping_and_special_links(tmp_path):
    from engine.errors import OutputError

    dangling = tmp_path / "new.bvh"
    dangling.symlink_to(tmp_path / "made" / "here.bvh")
    with pytest.raises(OutputError, match="whose folder does not exist"):
        write_text(dangling, "x")
    assert not (tmp_path / "made").exists(), "no folder is created at the far end of a link"
    (tmp_path / "made").mkdir()
    write_text(dangling, "x")  # like a shell's `>`: the link's target is created
    assert dangling.is_symlink() and (tmp_path / "made" / "here.bvh").read_text() == "x"

    loop_a, loop_b = tmp_path / "a.bvh", tmp_path / "b.bvh"
    loop_a.symlink_to(loop_b)
    loop_b.symlink_to(loop_a)
    with pytest.raises(OutputError, match="symlink loop"):
        write_text(loop_a, "x")
    assert loop_a.is_symlink() and loop_b.is_symlink()

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    to_fifo = tmp_path / "to_pipe.bvh"
    to_fifo.symlink_to(fifo)
    for out in (to_fifo, fifo):
        with pytest.raises(OutputError, match="not a regular file"):
            write_text(out, "x")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and to_fifo.is_symlink()
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


def test_the_cli_checks_a_linked_output_before_the_solve(tmp_path, capsys, monkeypatch):
    import engine.methods
    from engine.cli.main import main

    monkeypatch.setattr(engine.methods, "run_method", lambda *a, **k: pytest.fail("the solve started"))
    link = tmp_path / "o.bvh"
    link.symlink_to(tmp_path / "missing" / "o.bvh")
    clip = os.path.join(os.path.dirname(__file__), "..", "..", "assets", "clips", "example.bvh")
    rc = main(["reconstruct", clip, "--out", str(link)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and err.startswith(f"error: --out {link}: cannot write: it links to"), err
