"""``gui``'s start-up (app/cli.py): no cyclic garbage collection while the window's
modules are imported, collection on again once the window is built, and no torch in the
window process."""

from __future__ import annotations

import os
import sys


def test_gui_collects_no_cycles_while_starting_and_collects_again_after(monkeypatch):
    import argparse
    import gc
    import types

    from app import cli

    seen = {}

    def fake_run(*args):
        seen["during"] = gc.isenabled()
        seen["started"] = args[-1]
        return 0

    monkeypatch.setitem(sys.modules, "app.main", types.SimpleNamespace(run=fake_run))
    args = argparse.Namespace(
        measure=None,
        old_pace=None,
        ghosts="",
        after_frames=1,
        method="ik",
        engine="thread",
        file=None,
        sensors=None,
        screenshot=None,
        json="m.json",
        pace=None,
        view="stick",
        rig_map=None,
        scene=None,
    )
    assert gc.isenabled()
    try:
        assert cli.run(args) == 0
        assert seen == {"during": False, "started": None}  # a thread engine: no process started ahead
        assert gc.isenabled()
    finally:
        gc.enable()


def test_the_window_process_does_not_import_torch():
    """The window never runs torch (the engine process does), and torch costs about a CPU
    second of the launch: the modules the window imports must reach it only inside the
    functions the engine calls (a constraint's loss, tensor kinematics, saving a BVH)."""
    import subprocess

    from tests.conftest import REPO

    code = (
        "import sys\nimport app.main_window, app.main, engine.constraints, engine.motion.bvh\n"
        "print('torch' in sys.modules, 'engine.constraints.look_at' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
        env={**os.environ, "QT_QPA_PLATFORM": "offscreen"},
    )
    assert out.stdout.split() == ["False", "True"], out.stderr[-2000:]
