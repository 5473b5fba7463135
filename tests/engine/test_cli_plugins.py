"""The command line: the engine's subcommands plus those other packages register."""

from __future__ import annotations

import subprocess
import sys
from importlib.metadata import entry_points

import pytest

from engine.cli import main as cli_main
from engine.cli.main import PLUGIN_GROUP, SubcommandImportError, build_parser


def test_gui_comes_from_the_app_through_the_entry_point_group():
    eps = {ep.name: ep.value for ep in entry_points(group=PLUGIN_GROUP)}
    assert eps.get("gui") == "app.cli", "reinstall the project (make) to register app.cli"
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert "gui" in sub.choices


def test_the_engine_command_line_does_not_import_the_app():
    code = "import sys, engine.cli.main; print(any(m == 'app' or m.startswith('app.') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    "body, message",
    [
        (None, "No module named 'cli_broken_sub'"),  # the module is missing
        ("import no_such_dependency_xyz\n", "no_such_dependency_xyz"),  # it imports something missing
        ("raise ValueError('bad constant')\n", "ValueError: bad constant"),  # it raises on import
    ],
)
def test_a_subcommand_that_fails_to_import_is_an_error_not_a_gap(monkeypatch, tmp_path, capsys, body, message):
    if body is not None:
        (tmp_path / "cli_broken_sub.py").write_text(body)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(cli_main, "SUBCOMMANDS", ("engine.cli.info", "cli_broken_sub"))
    with pytest.raises(SubcommandImportError, match="cli_broken_sub"):
        build_parser()
    assert cli_main.main(["info", "--help"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: subcommand module cli_broken_sub cannot be imported") and message in err


def test_an_entry_point_whose_module_is_missing_is_an_error_that_says_how_to_fix_it(monkeypatch, capsys):
    from importlib.metadata import EntryPoint

    stale = EntryPoint(name="ghost", value="app.no_such_subcommand", group=cli_main.PLUGIN_GROUP)
    monkeypatch.setattr(cli_main, "entry_points", lambda group: [stale])
    with pytest.raises(SubcommandImportError, match="app.no_such_subcommand"):
        build_parser()
    assert cli_main.main(["info", "--help"]) == 1
    err = capsys.readouterr().err
    assert "reinstall with pip install -e ." in err and len(err.strip().splitlines()) == 1
