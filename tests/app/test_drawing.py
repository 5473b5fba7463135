"""The display scheduler's status bar: solver timing figures, labels set only on change."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any


def status_window(bar: Any, **extra: Any) -> SimpleNamespace:
    """A stand-in for the studio window with the parts the draw scheduler's status update
    reads: the status bar ``bar``, three status labels and plot views that take nothing."""
    from PyQt6.QtWidgets import QLabel

    return SimpleNamespace(
        plots=SimpleNamespace(update_iterations=None, update_cost=None, update_history=None),
        latent=SimpleNamespace(update_snapshot=None),
        method_errors=SimpleNamespace(update_snapshot=None),
        ghost_status=SimpleNamespace(on_snapshot=lambda snap: None, is_ghost_problem=lambda m: False),
        optimizer_panel=SimpleNamespace(set_settings_apply=lambda on, method: None),
        statusBar=lambda: bar,
        **{n: QLabel() for n in ("status_engine", "status_gui", "status_warnings")},
        **extra,
    )


def test_status_shows_the_solver_breakdown_and_leaves_unchanged_labels_alone(qtbot):
    from PyQt6.QtWidgets import QStatusBar

    from app.drawing import DrawScheduler
    from tests.widgets.conftest import FakeSnapshot

    bar = QStatusBar()
    qtbot.addWidget(bar)
    window = status_window(bar)
    d = DrawScheduler(window)
    snap = FakeSnapshot()
    snap.timing = {
        "ms_per_frame": 12.0,
        "ms_per_iteration": 1.2,
        "decoder": 0.3,
        "fk_losses": 0.6,
        "backward": 0.2,
        "step": 0.1,
    }
    snap.frames_skipped, snap.pace, snap.recent_errors = 0, "every_frame", ("ik ignores constraints",)
    d._update_status(snap)
    text, tip = window.status_engine.text(), window.status_engine.toolTip()
    assert "1.20 ms/it" in text and "decoder" not in text  # short enough for the bar
    assert "decoder 0.30 ms" in tip and "fk+loss 0.60 ms" in tip  # the breakdown is in the tooltip
    assert "skipped" not in text  # counted in real-time mode only
    assert window.status_warnings.toolTip() == "ik ignores constraints"
    changed = []
    window.status_engine.setText = lambda t: changed.append(t)  # type: ignore[method-assign]
    d._update_status(snap)
    assert changed == [], "an unchanged label must not be set again"


def test_a_snapshot_solved_before_a_seek_does_not_move_the_paused_frame_back(studio, qtbot):
    """Paused and seeked to frame 20, a snapshot of frame 0 that the engine solved before
    the seek (drawn after it) leaves the timeline at 20; while playing it follows the engine."""
    from dataclasses import replace

    s = studio.session
    qtbot.waitUntil(lambda: s.latest is not None, timeout=30000)
    s.pause()
    s.seek(20)
    stale = replace(s.latest, frame=0, playing=False, seq=s.latest.seq + 1000)
    for panel in studio.drawing.panels:
        if panel.name == "timeline":
            panel.update(stale)
    assert s.frame == 20
    s.play()
    for panel in studio.drawing.panels:
        if panel.name == "timeline":
            panel.update(replace(stale, frame=33, playing=True, plays=s.plays))
    assert s.frame == 33


def test_a_stopped_solvers_last_snapshot_does_not_replace_the_line_that_says_why(qtbot):
    """The solver died for good (no restart): its last snapshot, whose error a status panel
    had not shown yet, is drawn after the death; the status bar keeps the reason."""
    from PyQt6.QtWidgets import QStatusBar

    from app.drawing import DrawScheduler
    from engine.studio.restarts import RestartPolicy
    from tests.widgets.conftest import FakeSnapshot

    bar = QStatusBar()
    qtbot.addWidget(bar)
    errors: list[str] = []
    window = status_window(
        bar,
        session=SimpleNamespace(engine=SimpleNamespace(failure="the engine process stopped unexpectedly")),
        show_error=lambda title, text: errors.append(title),
    )
    d = DrawScheduler(window)
    d.engine_watch.policy = RestartPolicy(limit=1)  # this death is the one not restarted
    d.engine_watch.check()
    assert errors == ["The engine stopped"]
    snap = FakeSnapshot(error="ik ignores constraints")
    snap.timing, snap.frames_skipped, snap.pace, snap.recent_errors = {}, 0, "every_frame", ()
    d._update_status(snap)
    assert bar.currentMessage().endswith("so it is not restarted again")
    assert d.engine_watch.stopped
    window.session.engine = SimpleNamespace(failure="")  # a new engine: its errors show again
    assert not d.engine_watch.stopped
    d._update_status(snap)
    assert bar.currentMessage() == "ik ignores constraints"
