"""``dragposer-studio`` command line: one module per subcommand.

Each subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` (taking the parsed args, returning an exit code). Packages outside the engine
add subcommands through the ``dragposer_studio.subcommands`` entry-point group (the
studio's ``gui`` comes from ``app.cli`` this way), so the engine never imports them. User-facing failures raise
:class:`engine.errors.UserError`; they are printed without a traceback and exit 2. A
subcommand module that fails to import is an error (exit 1, naming the module), never
a subcommand silently missing.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from importlib.metadata import entry_points
from types import ModuleType
from typing import NoReturn

from engine.errors import UserError, shorten_words
from engine.startup_trace import mark
from engine.validation import one_line

#: Subcommand modules, in the order ``--help`` lists them.
SUBCOMMANDS = (
    "engine.cli.info",
    "engine.cli.convert",
    "engine.cli.rig",
    "engine.cli.data",
    "engine.cli.train",
    "engine.cli.reconstruct",
    "engine.cli.send",
    "engine.cli.live",
    "engine.cli.evaluate",
    "engine.cli.bench",
    "engine.cli.compare",
    "engine.cli.bake",
    "engine.cli.latent",
)
#: Entry-point group of subcommand modules other packages register.
PLUGIN_GROUP = "dragposer_studio.subcommands"


class SubcommandImportError(RuntimeError):
    """A module of :data:`SUBCOMMANDS` failed to import (a broken install or a bug)."""


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: no usage block, bad tokens cut short (subcommand
    parsers inherit the class)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {one_line(shorten_words(message, 60), 400)} (see --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="dragposer-studio",
        description="Full-body motion reconstruction from sparse trackers (DragPoser). "
        "Run a subcommand with --help for its options.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod_name in SUBCOMMANDS:
        _import_subcommand(mod_name).register(sub)
    for ep in sorted(entry_points(group=PLUGIN_GROUP), key=lambda e: e.name):
        _import_subcommand(ep.value, installed=True).register(sub)
    return parser


def _import_subcommand(mod_name: str, installed: bool = False) -> ModuleType:
    """The subcommand module ``mod_name``; :class:`SubcommandImportError` when it fails to
    import, so a broken subcommand says so instead of vanishing from ``--help``."""
    try:
        return importlib.import_module(mod_name)
    except Exception as exc:
        hint = ""
        if installed and isinstance(exc, ModuleNotFoundError) and exc.name == mod_name:
            hint = " (the installed entry points name a module this checkout lacks: reinstall with pip install -e .)"
        raise SubcommandImportError(
            f"subcommand module {mod_name} cannot be imported: {type(exc).__name__}: {exc}{hint}"
        ) from exc


def main(argv: list[str] | None = None) -> int:
    mark("interpreter up")
    try:
        parser = build_parser()
    except SubcommandImportError as exc:
        print(f"error: {one_line(str(exc))}", file=sys.stderr)
        return 1
    mark("command line parsed")
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except UserError as exc:
        print(f"error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except RecursionError:
        print("error: input nested too deeply to process", file=sys.stderr)
        return 2
    except MemoryError:
        print("error: out of memory (input too large for this machine)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
