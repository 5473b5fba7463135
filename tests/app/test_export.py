"""Save reconstruction as BVH: progress, cancel, and quitting while it runs."""

from __future__ import annotations

import time

import pytest

from tests.stand_ins import RestPoseMethod

pytestmark = pytest.mark.gui


class SlowMethod(RestPoseMethod):
    """The rest-pose stand-in at ~40 ms per frame (a 120-frame clip takes ~5 s)."""

    def step(self, sensors):
        time.sleep(0.04)
        return super().step(sensors)


@pytest.fixture
def slow_export(studio):
    studio.files.export.factory = lambda name: SlowMethod()
    return studio.files.export


def test_cancel_stops_the_export_and_writes_nothing(studio, qtbot, tmp_path, slow_export):
    out = tmp_path / "never.bvh"
    studio.files.save_reconstruction(str(out))
    qtbot.waitUntil(lambda: slow_export.dialog.value() > 0, timeout=10000)
    assert slow_export.dialog.maximum() == studio.session.num_frames
    from PyQt6.QtWidgets import QPushButton

    slow_export.dialog.findChild(QPushButton).click()  # the dialog's Cancel button
    qtbot.waitUntil(lambda: not slow_export.running, timeout=5000)
    assert slow_export.done < studio.session.num_frames
    assert not out.exists() and not list(tmp_path.glob(".never.bvh*"))
    assert "cancelled" in studio.statusBar().currentMessage()


def test_quitting_during_an_export_does_not_hang(studio, qtbot, tmp_path, slow_export):
    """Closing the window during an export quits at once, without waiting for the export thread."""
    out = tmp_path / "quit.bvh"
    studio.files.save_reconstruction(str(out))
    qtbot.waitUntil(lambda: slow_export.done > 0, timeout=10000)
    thread = slow_export.thread
    t0 = time.monotonic()
    studio.close()
    assert time.monotonic() - t0 < 2.0
    assert not thread.is_alive() and not out.exists()
