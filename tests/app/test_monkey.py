"""The monkey (:mod:`tests.app.monkey`): seeded random UI events on the studio and the pose
window find no crash, no traceback and no frozen event loop. A run of its own process, so
a crash is an exit status here, not the end of the test session."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.gui, pytest.mark.slow]
REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("seed", [1])
def test_the_monkey_finds_no_crash_traceback_or_frozen_loop(seed):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    run = subprocess.run(
        [sys.executable, "-m", "tests.app.monkey", "--seed", str(seed), "--events", "300", "--step-timeout", "60"],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    last = [line for line in run.stdout.splitlines() if line.startswith("monkey ")]
    assert run.returncode == 0, f"exit {run.returncode}\n{run.stdout[-3000:]}\n{run.stderr[-6000:]}"
    assert last and f"seed={seed} events=300 " in last[-1] and "errors=0" in last[-1]
    assert "Traceback" not in run.stderr and "Fatal Python error" not in run.stderr
