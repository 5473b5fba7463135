"""What the studio's start-up does not pay for: torch while the command line is read
(the engine process starts before it), the compiler stack while the models load, and
an engine process started ahead of the window is the one the session uses."""

from __future__ import annotations

import subprocess
import sys

from engine.studio.session import Session
from tests.conftest import REPO


def _modules_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running ``code`` in the repository."""
    out = subprocess.run(
        [sys.executable, "-c", f"{code}\nimport sys\nprint(' '.join(sys.modules))"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    return set(out.stdout.split())


def test_building_the_command_line_does_not_import_torch():
    mods = _modules_after("from engine.cli.main import build_parser\nbuild_parser()")
    assert "engine.cli.bench" in mods and "engine.solver.settings" in mods
    assert "torch" not in mods


def test_loading_the_models_does_not_import_the_compiler_stack():
    mods = _modules_after("from engine.models import load_default_models\nload_default_models()")
    assert "engine.models.predictor" in mods
    assert "torch._dynamo" not in mods  # 2 s of a meta-device weight initialiser, unused


def test_the_solver_package_gives_its_names_on_first_use():
    import engine.solver as solver
    from engine.solver.optimizer import PoseOptimizer

    assert solver.PoseOptimizer is PoseOptimizer
    try:
        solver.NoSuchName  # noqa: B018
    except AttributeError as exc:
        assert "NoSuchName" in str(exc)
    else:
        raise AssertionError("an unknown name must raise AttributeError")


class _Started:
    """An engine that is already running: the session must take it, not start another."""

    def __init__(self) -> None:
        self.commands: list = []
        self.starts = 0

    def start(self) -> None:
        self.starts += 1

    def submit(self, command) -> None:
        self.commands.append(command)


def test_a_started_engine_process_is_adopted_with_the_whole_session(synthetic_motion):
    session = Session(method="dragposer")
    session.set_motion(synthetic_motion)
    started = _Started()
    assert session.start_engine(process=True, started=started) is started
    assert started.starts == 0 and session.engine is started
    kinds = [type(c).__name__ for c in started.commands]
    assert kinds[0] == "SetMethod" and "SetMotion" in kinds and "SetSensors" in kinds
