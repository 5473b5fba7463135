"""GUI test helpers: fake snapshots and a shown viewport (the display handling lives in
tests/conftest.py)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from engine import skeleton as sk


@dataclass(frozen=True)
class FakeRecord:
    """The fields widgets read from ``engine.studio.snapshot.HistoryEntry``."""

    frame: int
    iterations: int
    ms: float
    losses: dict
    latent: np.ndarray | None = None


@dataclass
class FakeSnapshot:
    """Just the fields widgets read from ``engine.studio.snapshot.Snapshot`` (no torch needed)."""

    seq: int = 1
    frame: int = 0
    num_frames: int = 100
    positions: np.ndarray = field(default_factory=lambda: sk.Skeleton.canonical().rest_positions() + [0, 0, 1.0])
    ground_truth: np.ndarray = field(default_factory=lambda: sk.Skeleton.canonical().rest_positions() + [0.3, 0, 1.0])
    ghosts: dict = field(default_factory=dict)
    target_joints: tuple = ("root", "lwrist")
    target_positions: np.ndarray = field(default_factory=lambda: np.array([[0, 0, 1.0], [0.7, 0, 1.4]]))
    target_rotations: np.ndarray = field(default_factory=lambda: np.tile([1.0, 0, 0, 0], (2, 1)))
    target_connected: np.ndarray = field(default_factory=lambda: np.array([True, False]))
    gizmos: tuple = ()
    losses: tuple = ({"total": 1.0, "pos:root": 0.5}, {"total": 0.1, "pos:root": 0.05})
    latent: np.ndarray | None = None
    iterations: int = 2
    ms: float = 3.0
    warnings: int = 0
    messages: tuple = ()
    error: str = ""
    engine_fps: float = 60.0
    playing: bool = False
    method: str = "fake"
    can_decode: bool = False
    configurable: bool = True
    decoded: np.ndarray | None = None
    history: tuple | None = None  # None: just this frame's record
    history_run: int = 0
    plays: int = 0

    def __post_init__(self) -> None:
        if self.history is None:
            last = self.losses[-1] if self.losses else {}
            self.history = (FakeRecord(self.frame, self.iterations, self.ms, dict(last), self.latent),)


@pytest.fixture
def fake_snapshot():
    return FakeSnapshot


def shown(qtbot, widget, width: int, height: int):
    """``widget`` at ``width`` x ``height`` px, shown and exposed; closed after the test."""
    qtbot.addWidget(widget)
    widget.resize(width, height)
    widget.show()
    qtbot.waitExposed(widget)
    return widget


@pytest.fixture
def viewport(qtbot):
    """A shown 640 x 480 :class:`widgets.viewport.Viewport`, closed after the test."""
    from widgets.viewport import Viewport

    v = Viewport()
    v.resize(640, 480)
    v.show()
    qtbot.waitExposed(v)
    yield v
    v.close()
