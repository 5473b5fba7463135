"""The kill test (scripts/kill_test.py, docs/reliability.md) in short: a studio and pose
window session driven by real input, killed with SIGKILL twice and recovered at each next
start (then quit cleanly), and one session whose solver process is killed and replaced.
The full run (10 kills of each) is the script's default."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import REPO

pytestmark = [pytest.mark.gui, pytest.mark.slow, pytest.mark.soak]


def kill_test(tmp_path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(REPO / "scripts" / "kill_test.py"), *args, "--work", str(tmp_path), "--seed", "7"],
        cwd=REPO,
        timeout=600,
        capture_output=True,
        text=True,
    )


def test_killed_studios_are_recovered_and_a_killed_solver_is_replaced(tmp_path):
    studio = kill_test(
        tmp_path / "studio", "studio", "--kills", "2", "--engine", "thread", "--min-edit", "4", "--max-edit", "7"
    )
    log = (tmp_path / "studio" / "sessions.log").read_text()[-3000:]
    assert studio.returncode == 0, studio.stdout + log
    assert "kill-test studio kills=2 passed=2" in studio.stdout and "clean quit: ok" in studio.stdout
    engine = kill_test(tmp_path / "engine", "engine", "--kills", "1", "--max-edit", "4")
    log = (tmp_path / "engine" / "sessions.log").read_text()[-3000:]
    assert engine.returncode == 0, engine.stdout + log
    assert "kill-test engine kills=1 passed=1" in engine.stdout
