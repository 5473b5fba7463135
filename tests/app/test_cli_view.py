"""``gui --view`` and ``--ghosts`` reach the window's run()."""

from __future__ import annotations

import argparse


def test_view_and_ghost_options_are_passed_to_the_window(monkeypatch):
    from app import cli

    seen = {}
    monkeypatch.setattr("app.main.run", lambda *a: seen.setdefault("args", a) and 0)
    parser = argparse.ArgumentParser()
    cli.register(parser.add_subparsers())
    args = parser.parse_args(["gui", "--view", "body", "--ghosts", "ik,autoencoder", "--method", "ik"])
    args.func(args)
    assert seen["args"][-2:] == (("ik", "autoencoder"), "body")
