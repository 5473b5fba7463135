"""Import contracts: engine/ never loads Qt or VTK; widgets/ never loads torch."""

from __future__ import annotations

import subprocess
import sys

WIDGET_MODULES = (
    "widgets.viewport",
    "widgets.timeline",
    "widgets.sensor_panel",
    "widgets.constraint_panel",
    "widgets.plots",
    "widgets.latent_inspector",
    "widgets.optimizer_panel",
    "widgets.live_panel",
)


def _loaded_after(imports: tuple[str, ...], banned: tuple[str, ...]) -> list[str]:
    code = (
        "import sys\n"
        + "".join(f"import {m}\n" for m in imports)
        + f"print(','.join(b for b in {banned!r} if b in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return [b for b in out.stdout.strip().split(",") if b]


def test_widgets_do_not_import_torch():
    assert _loaded_after(WIDGET_MODULES, ("torch",)) == []


def test_engine_studio_core_does_not_import_qt():
    banned = ("PyQt6", "pyvista", "pyvistaqt", "pyqtgraph", "superqt", "vtk")
    assert _loaded_after(("engine.studio.session", "engine.studio.thread", "engine.cli.main", "app.cli"), banned) == []
