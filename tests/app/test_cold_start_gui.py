"""``gui``'s start-up (app/cli.py): no cyclic garbage collection while the window's
modules are imported, collection on again once the window is built."""

from __future__ import annotations

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
        measure=None, old_pace=None, ghosts="", after_frames=1, method="ik", engine="thread", file=None,
        sensors=None, screenshot=None, json="m.json", pace=None, view="stick", rig_map=None, scene=None)  # fmt: skip
    assert gc.isenabled()
    try:
        assert cli.run(args) == 0
        assert seen == {"during": False, "started": None}  # a thread engine: no process started ahead
        assert gc.isenabled()
    finally:
        gc.enable()
