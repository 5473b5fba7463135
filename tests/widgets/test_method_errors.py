"""The per-method error plot: one curve per method on screen, in the ghosts' colours."""

from __future__ import annotations

import numpy as np

from widgets import style
from widgets.method_errors import MethodErrorPlot, frame_error_cm


def test_error_is_the_mean_joint_distance_in_cm():
    a = np.zeros((22, 3))
    assert abs(frame_error_cm(a + [0.03, 0.04, 0], a) - 5.0) < 1e-9
    assert np.isnan(frame_error_cm(None, a))


def test_one_curve_per_method_restarting_when_playback_jumps(qtbot, fake_snapshot):
    p = MethodErrorPlot()
    qtbot.addWidget(p)
    base = fake_snapshot()
    gt = base.ground_truth
    for f in range(5):
        ghosts = {"ik": gt + [0.01 * f, 0, 0], "rpm": gt + [0, 0.05, 0]}
        p.update_snapshot(
            fake_snapshot(
                seq=f + 1, frame=f, positions=gt + [0.02, 0, 0], ghosts=ghosts, ground_truth=gt, method="dragposer"
            )
        )
    assert set(p.curves) == {"dragposer", "ik", "rpm"}
    x, y = p.curves["ik"].getData()
    np.testing.assert_allclose(x, range(5))
    np.testing.assert_allclose(y, [0, 1, 2, 3, 4], atol=1e-9)
    assert p.curves["rpm"].opts["pen"].color().name() == style.ghost_color("rpm")
    assert "rpm" in p.legend.text() and "5.0 cm" in p.legend.text()
    p.update_snapshot(fake_snapshot(seq=9, frame=1, positions=gt, ground_truth=gt, method="dragposer"))
    assert set(p.curves) == {"dragposer"} and len(p.curves["dragposer"].getData()[0]) == 1


def test_curves_restart_when_the_engine_history_restarts_unseen(qtbot, fake_snapshot):
    """The window draws only the newest snapshot: after frames 0 and 1 it may miss the
    engine reaching frame 30 and see frame 10 next, a frame later than the last it drew.
    The engine's history_run says the history started again, so the curves do too."""
    p = MethodErrorPlot()
    qtbot.addWidget(p)
    gt = fake_snapshot().ground_truth
    for seq, frame in ((1, 0), (2, 1)):
        p.update_snapshot(
            fake_snapshot(seq=seq, frame=frame, positions=gt, ground_truth=gt, method="dragposer", history_run=1)
        )
    p.update_snapshot(fake_snapshot(seq=5, frame=10, positions=gt, ground_truth=gt, method="dragposer", history_run=2))
    assert sorted(p.data["dragposer"]) == [10]
    p.update_snapshot(fake_snapshot(seq=6, frame=11, positions=gt, ground_truth=gt, method="dragposer", history_run=2))
    assert sorted(p.data["dragposer"]) == [10, 11]


def test_the_frame_axis_ticks_whole_frames(qtbot, fake_snapshot):
    """Over a frame or two the frame axis ticks whole numbers only
    (widgets.plots.CountAxis), never 0.5, 1.5 ..., frames that do not exist."""
    from tests.widgets.conftest import shown

    p = shown(qtbot, MethodErrorPlot(), 900, 220)
    gt = fake_snapshot().ground_truth
    for f in range(2):
        p.update_snapshot(fake_snapshot(seq=f + 1, frame=f, positions=gt + [0.01, 0, 0], ground_truth=gt))
    p.grab()
    axis = p.plot.getAxis("bottom")
    lo, hi = p.plot.getPlotItem().getViewBox().viewRange()[0]
    ticks = [v for _s, values in axis.tickValues(lo, hi, axis.width()) for v in values]
    assert ticks and all(float(v).is_integer() for v in ticks), ticks
