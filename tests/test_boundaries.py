"""Package boundaries: the engine stays free of GUI toolkits, the widgets free of torch,
and no installed package imports the repository's research or scripts folders.

Every ``.py`` file is parsed with :mod:`ast` (never imported), so a forbidden import is
found wherever it sits: at module level, inside a function, under ``if TYPE_CHECKING``,
or as a string passed to ``importlib.import_module`` / ``__import__``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

GUI_MODULES = frozenset({"PyQt6", "PySide6", "pyvista", "pyvistaqt", "pyqtgraph", "superqt"})
TORCH_MODULES = frozenset({"torch"})

#: Folders of the repository that are not installed (``pyproject.toml`` packages engine,
#: widgets and app): code that imports them works only from a checkout.
REPO_ONLY = frozenset({"research", "scripts"})

#: package folder -> top-level modules it must never import
RULES: dict[str, frozenset[str]] = {
    "engine": GUI_MODULES | REPO_ONLY,
    "widgets": TORCH_MODULES | REPO_ONLY,
    "app": REPO_ONLY,
}


def forbidden_imports(source: str, banned: frozenset[str], filename: str = "<string>") -> list[tuple[int, str]]:
    """Imports of ``banned`` top-level modules in ``source``.

    Parameters
    ----------
    source : str
        Python source text.
    banned : frozenset of str
        Top-level module names (``"PyQt6"`` bans ``PyQt6.QtCore`` too).
    filename : str
        Used in syntax-error messages.

    Returns
    -------
    list of (int, str)
        Line number and full module name of each offending import, in file order.
    """
    hits: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(source, filename=filename)):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            func = node.func
            called = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if called in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                names = [node.args[0].value]
        hits.extend((node.lineno, n) for n in names if n.split(".")[0] in banned)
    return sorted(hits)


def _python_files(package: str) -> list[Path]:
    return sorted(p for p in (REPO / package).rglob("*.py") if "__pycache__" not in p.parts)


@pytest.mark.parametrize("package", list(RULES))
def test_package_respects_its_import_boundary(package):
    files = _python_files(package)
    assert files, f"{package}/ has no Python files: is the test looking in the right place?"
    offences = [
        f"{path.relative_to(REPO)}:{line}: imports {module}"
        for path in files
        for line, module in forbidden_imports(path.read_text(encoding="utf-8"), RULES[package], str(path))
    ]
    assert not offences, f"{package}/ must not import {sorted(RULES[package])}:\n" + "\n".join(offences)


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("import numpy as np\nimport PyQt6.QtCore\n", [(2, "PyQt6.QtCore")]),
        ("from PySide6.QtWidgets import QWidget\n", [(1, "PySide6.QtWidgets")]),
        ("def f():\n    import pyvista as pv\n    return pv\n", [(2, "pyvista")]),
        ("if TYPE_CHECKING:\n    from superqt import QLabeledSlider\n", [(2, "superqt")]),
        ("import os, pyqtgraph\n", [(1, "pyqtgraph")]),
        ("import importlib\nqt = importlib.import_module('pyvistaqt')\n", [(2, "pyvistaqt")]),
        ("from . import pyvista\nimport pyvistax\nfrom engine.pyvista_free import x\n", []),
    ],
)
def test_checker_finds_gui_imports(source, expected):
    assert forbidden_imports(source, GUI_MODULES) == expected


def test_checker_finds_torch_in_widgets_code():
    source = "from torch import nn\nimport numpy\n\n\nclass W:\n    def f(self):\n        import torch.nn\n"
    assert forbidden_imports(source, TORCH_MODULES) == [(1, "torch"), (7, "torch.nn")]
    assert forbidden_imports("import torchvision\nimport numpy\n", TORCH_MODULES) == []


def test_checker_finds_research_imports():
    source = "from research.retarget_versions import VERSIONS\nimport scripts.eval_table\nimport researchers\n"
    assert forbidden_imports(source, REPO_ONLY) == [(1, "research.retarget_versions"), (2, "scripts.eval_table")]
