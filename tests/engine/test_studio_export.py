"""The session builds the studio's engine work: export jobs and tracker sources."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import UserError
from engine.motion.bvh import load_bvh, save_motion_bvh
from engine.motion.retarget import load_motion
from engine.studio.export import ExportJob
from engine.studio.session import Session
from engine.tracker_io.recording import write_recording
from engine.tracker_io.sender import plan_stream
from engine.tracker_io.trackers import TrackerSample
from tests.stand_ins import RestPoseMethod


@pytest.fixture
def opened(synthetic_motion, tmp_path):
    path = tmp_path / "walk.bvh"
    save_motion_bvh(path, synthetic_motion.slice(0, 20))
    session = Session(method="rest")
    session.open(path)
    return session, tmp_path


def test_an_export_job_solves_the_session_clip_and_writes_it(opened):
    session, tmp = opened
    job = ExportJob.of_session(session, tmp / "out.bvh")
    session.set_method("ik")  # a later edit does not reach the job
    solved = []
    rec = job.run(lambda name: RestPoseMethod(), progress=solved.append)
    assert job.method == "rest" and solved == list(range(20)) and len(rec) == 20
    back = load_motion(tmp / "out.bvh")
    assert len(back) == 20 and np.allclose(back.root_pos[:, :2], rec.root_pos[:, :2], atol=1e-4)  # load grounds it


def test_a_cancelled_job_writes_nothing(opened):
    session, tmp = opened
    job = ExportJob.of_session(session, tmp / "never.bvh")
    solved = []
    assert job.run(lambda name: RestPoseMethod(), solved.append, cancelled=lambda: len(solved) >= 3) is None
    assert solved == [0, 1, 2] and not list(tmp.glob("*never*"))


def test_on_the_source_rig_the_job_writes_the_opened_file_hierarchy(opened):
    session, tmp = opened
    job = ExportJob.of_session(session, tmp / "rig.bvh", on_source_rig=True)
    assert job.source == session.path
    job.run(lambda name: RestPoseMethod())
    assert load_bvh(tmp / "rig.bvh").names == load_bvh(session.path).names


def test_an_export_needs_a_clip(synthetic_motion, tmp_path):
    session = Session()
    with pytest.raises(UserError, match="open a motion"):
        ExportJob.of_session(session, tmp_path / "o.bvh")
    session.set_motion(synthetic_motion)  # not from a file
    with pytest.raises(UserError, match="not opened from a BVH file"):
        ExportJob.of_session(session, tmp_path / "o.bvh", on_source_rig=True)


def test_the_session_opens_a_recording_and_saving_then_says_why_not(synthetic_motion, tmp_path):
    plan = plan_stream(synthetic_motion.slice(0, 10), "6")
    samples = [TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan)) for n, p, r in plan.frame(i)]
    write_recording(tmp_path / "rec.jsonl", samples, 60.0)
    session = Session()
    src = session.open_recording(tmp_path / "rec.jsonl")
    assert session.source is src and src.num_frames == 10 and session.live_source is None
    with pytest.raises(UserError, match="tracker input"):
        ExportJob.of_session(session, tmp_path / "o.bvh")
    with pytest.raises(UserError):
        session.open_recording(tmp_path / "missing.jsonl")
    assert session.source is src  # a failed open leaves the session as it was


def test_the_session_connects_a_live_source_and_closes_it(synthetic_motion):
    session = Session()
    src = session.connect_live("127.0.0.1", 0)
    try:
        assert session.live_source is src and src.receiver.running
    finally:
        session.set_motion(synthetic_motion)  # replacing the source closes it
    assert session.live_source is None and not src.receiver.running
