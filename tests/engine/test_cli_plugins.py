"""The command line: the engine's subcommands plus those other packages register."""

from __future__ import annotations

import subprocess
import sys
from importlib.metadata import entry_points

from engine.cli.main import PLUGIN_GROUP, build_parser


def test_gui_comes_from_the_app_through_the_entry_point_group():
    eps = {ep.name: ep.value for ep in entry_points(group=PLUGIN_GROUP)}
    assert eps.get("gui") == "app.cli", "reinstall the project (make) to register app.cli"
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert "gui" in sub.choices


def test_the_engine_command_line_does_not_import_the_app():
    code = "import sys, engine.cli.main; print(any(m == 'app' or m.startswith('app.') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
