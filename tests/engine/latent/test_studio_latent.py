"""The engine thread's latent views: a view per solved frame, the detail on request, and
the note for a method without a latent (real DragPoser, bundled clip, no Qt)."""

from __future__ import annotations

import pytest

from engine.motion.retarget import load_motion
from engine.studio.session import Session
from tests.engine.latent.conftest import CLIP
from tests.engine.test_studio_thread import newest, wait_for


@pytest.fixture(scope="module")
def clip():
    return load_motion(CLIP).slice(0, 30)


def _engine(clip, method):
    session = Session(method=method)
    session.set_motion(clip)
    worker = session.start_engine()
    return session, worker


def test_views_readouts_and_detail(clip):
    session, worker = _engine(clip, "dragposer")
    try:
        wait_for(lambda: worker.latest is not None and worker.latest.latent_view is not None, timeout=60)
        session.step(3)
        wait_for(
            lambda: (
                worker.latest.frame == 3
                and worker.latest.latent_view is not None
                and worker.latest.latent_view.frame == 3
            ),
            timeout=60,
        )
        snap = worker.latest
        v = snap.latent_view
        assert v.xy.shape == (2,) and v.path_xy is not None and v.path_xy.shape[1] == 2
        assert v.start in ("predictor", "pose bank", "solved frame 0")  # stepped 3 ahead of frame 0
        assert snap.latent_note == ""
        entry = snap.history[-1]
        assert entry.frame == 3 and entry.readouts["nearest"] == pytest.approx(v.nearest)
        assert entry.readouts["x"] == pytest.approx(v.xy[0])
        assert snap.latent_detail is None
        seq = snap.seq
        session.inspect_latent("lwrist")
        wait_for(lambda: worker.latest.seq > seq and worker.latest.latent_detail is not None, timeout=60)
        d = worker.latest.latent_detail
        assert d.frame == 3 and "sensor:lwrist" in d.names
        assert d.forces.shape[1:] == (len(d.names), 24) and d.plane.shape[-1] == 2
        assert d.sweep.shape == (24, 3, 22, 3) and d.influence.shape == (24,) and d.joint == "lwrist"
        assert worker.latest.frame == 3  # inspecting solved nothing again
        seq = worker.latest.seq
        session.step(1)  # a new frame drops the old detail
        wait_for(lambda: worker.latest.seq > seq and worker.latest.frame == 4, timeout=60)
        assert worker.latest.latent_detail is None
    finally:
        worker.stop()


def test_stopping_cancels_an_inspection_in_hand(clip):
    session, worker = _engine(clip, "dragposer")
    try:
        wait_for(lambda: worker.latest is not None and worker.latest.latent_view is not None, timeout=60)
        session.inspect_latent("lwrist")
        wait_for(lambda: worker.doing == "InspectLatent", timeout=60)
    finally:
        worker.stop(timeout=60)
    assert not worker.is_alive()
    # the inspection stopped between two of its steps: no detail made, no error said
    assert worker.latest.latent_detail is None and "inspect latent" not in worker.latest.error


def test_a_method_without_a_latent_says_so(clip):
    session, worker = _engine(clip, "ik")
    try:
        newest(worker)
        wait_for(lambda: worker.latest.latent_note != "", timeout=30)
        assert worker.latest.latent_view is None
        assert "ik has no latent space" in worker.latest.latent_note
        assert worker.latest.history[-1].readouts == {}
        seq = worker.latest.seq
        session.inspect_latent()
        wait_for(lambda: worker.latest.seq > seq, timeout=30)
        assert "no latent space" in worker.latest.error
    finally:
        worker.stop()


def test_the_solve_after_a_seek_says_where_it_started(clip):
    """The map names where the first solve after a seek starts: a seek ahead starts from
    the frame solved before it; one back resets the method, which starts from the zero
    latent."""
    session, worker = _engine(clip, "dragposer")
    try:
        session.set_setting("init_from_prediction", False)  # start from the last latent
        wait_for(lambda: worker.latest is not None and worker.latest.latent_view is not None, timeout=60)
        assert worker.latest.frame == 0
        session.seek(20)
        wait_for(lambda: (v := worker.latest.latent_view) is not None and v.frame == 20, timeout=60)
        assert worker.latest.latent_view.start == "solved frame 0"
        session.step(1)
        wait_for(lambda: (v := worker.latest.latent_view) is not None and v.frame == 21, timeout=60)
        assert worker.latest.latent_view.start == "previous frame"
        session.seek(10)  # back: a jump, the method starts again
        wait_for(lambda: (v := worker.latest.latent_view) is not None and v.frame == 10, timeout=60)
        assert worker.latest.latent_view.start == "zero latent"
    finally:
        worker.stop()
