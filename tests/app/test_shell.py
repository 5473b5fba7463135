"""The app's helpers take the main window as a typed shell: the window satisfies it, and
the protocol names everything the helpers use of the window."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from app.shell import StudioShell, ViewWindow

APP = Path(__file__).resolve().parents[2] / "app"

#: The helpers typed against :class:`StudioShell`, and the names they call the window by.
HELPERS = (
    "clip_saving.py",
    "clip_trim.py",
    "drawing.py",
    "failures.py",
    "ghost_status.py",
    "latent_views.py",
    "measure.py",
    "range_actions.py",
    "authoring_actions.py",
    "studio_redraw.py",
)
WINDOW_NAMES = {"window", "w"}


def _members(protocol: type) -> set[str]:
    """Attributes and methods a protocol declares (its annotations are strings, unresolved)."""
    return set(protocol.__annotations__) | {
        n for n, v in vars(protocol).items() if callable(v) and not n.startswith("_")
    }


def _window_uses(path: Path) -> set[str]:
    """Attributes read from the window in ``path``: ``window.X``, ``w.X``, ``self.w.X``."""
    used = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Attribute):
            continue
        base = node.value
        if isinstance(base, ast.Name) and base.id in WINDOW_NAMES:
            used.add(node.attr)
        elif (
            isinstance(base, ast.Attribute)
            and base.attr == "w"
            and isinstance(base.value, ast.Name)
            and base.value.id == "self"
        ):
            used.add(node.attr)
    return used


@pytest.mark.parametrize("helper", HELPERS)
def test_the_shell_names_what_each_helper_uses_of_the_window(helper):
    used = _window_uses(APP / helper)
    assert used, f"{helper}: no use of the window found (were its names changed?)"
    missing = used - _members(StudioShell)
    assert not missing, f"{helper} uses {sorted(missing)} of the window, which StudioShell does not name"


def test_the_view_menu_parts_use_only_the_view_window():
    missing = _window_uses(APP / "menu_parts.py") - _members(ViewWindow) - {"help_dialog"}
    assert not missing, f"menu_parts uses {sorted(missing)}, which ViewWindow does not name"


def test_the_main_window_is_a_studio_shell_and_a_view_window(studio):
    assert isinstance(studio, StudioShell)
    assert isinstance(studio, ViewWindow)
    assert studio.hips() is None or studio.hips().shape == (3,)


def test_a_window_lacking_a_member_is_not_a_shell(studio):
    class Partial:
        session = studio.session
        viewport = studio.viewport

    assert not isinstance(Partial(), StudioShell)
