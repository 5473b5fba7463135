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
    assert seen["args"][8:12] == (("ik", "autoencoder"), "body", None, "process")  # ..., rig map, engine


def test_rig_map_option_reaches_the_window(monkeypatch, tmp_path):
    import pytest

    from app import cli
    from engine.errors import UserError

    seen = {}
    monkeypatch.setattr("app.main.run", lambda *a: seen.setdefault("args", a) and 0)
    parser = argparse.ArgumentParser()
    cli.register(parser.add_subparsers())
    rig_map = tmp_path / "map.toml"
    rig_map.write_text("[joints]\n")
    args = parser.parse_args(["gui", "clip.bvh", "--rig-map", str(rig_map)])
    args.func(args)
    assert seen["args"][0] == "clip.bvh" and seen["args"][10] == rig_map  # then the engine, the scene
    args = parser.parse_args(["gui", "clip.bvh", "--rig-map", str(tmp_path / "missing.toml")])
    with pytest.raises(UserError, match="--rig-map: no such file"):
        args.func(args)


def test_pace_reaches_the_window_and_the_old_mode_flag_still_works(monkeypatch, capsys):
    from app import cli

    seen = []
    monkeypatch.setattr("app.main.run", lambda *a: seen.append(a) and 0)
    parser = argparse.ArgumentParser()
    cli.register(parser.add_subparsers())
    for argv in (["gui", "--pace", "real_time"], ["gui", "--mode", "real_time"], ["gui"]):
        args = parser.parse_args(argv)
        args.func(args)
    assert [a[7] for a in seen] == ["real_time", "real_time", None]  # the pace argument of app.main.run
    assert "--mode is deprecated, use --pace" in capsys.readouterr().err
