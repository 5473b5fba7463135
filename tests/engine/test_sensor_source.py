"""Every sensor source implements one contract and applies the studio's edits one way."""

from __future__ import annotations

import numpy as np
import pytest

from engine.sensor_source import SensorSource, apply_edits
from engine.sensors import Sensor
from engine.tracker_io.live_source import LiveSource
from engine.tracker_io.recording_source import RecordingSource
from engine.studio.clip_source import ClipSource

SOURCES = (ClipSource, LiveSource, RecordingSource)


@pytest.mark.parametrize("cls", SOURCES, ids=lambda c: c.__name__)
def test_every_source_is_a_sensor_source_with_every_member(cls):
    assert SensorSource in cls.__mro__  # subclassed: the type checker holds it to the contract
    assert not getattr(cls, "__abstractmethods__", ()), "abstract members left"
    for name in ("fps", "num_frames", "frame", "ground_truth", "set_sensors", "arrival", "close"):
        assert hasattr(cls, name), name


def test_clip_source_answers_the_whole_contract(synthetic_motion):
    src = ClipSource(synthetic_motion)
    src.set_sensors((Sensor("root"), Sensor("lwrist")))
    assert src.skeleton is synthetic_motion.skeleton and src.skeleton_version == 0 and not src.live
    assert src.arrival(0) is None and set(src.frame(0).readings) == {"root", "lwrist"}
    src.close()  # nothing to release; must not raise


def _raw() -> dict[str, Sensor]:
    rot = np.array([0.0, 1.0, 0.0, 0.0])
    return {j: Sensor(j).read(np.array([0.1, 0.2, 1.0 + k]), rot) for k, j in enumerate(("root", "lwrist", "rwrist"))}


def test_apply_edits_drops_disabled_offsets_strips_and_fails():
    raw = _raw()
    sensors = (Sensor("root", weight=2.0), Sensor("lwrist", dof=3, offset=(0.0, 0.0, 0.5), failures=((3, 5),)),
               Sensor("rwrist", enabled=False), Sensor("upperneck"))  # fmt: skip
    at2, at4 = apply_edits(raw, sensors, 2), apply_edits(raw, sensors, 4)
    assert set(at2.readings) == {"root", "lwrist"}  # disabled and unread sensors are dropped
    lw = at2.readings["lwrist"]
    np.testing.assert_allclose(lw.position, raw["lwrist"].position + [0, 0, 0.5])
    np.testing.assert_allclose(lw.rotation, [1, 0, 0, 0])  # 3-DoF: no rotation leaks through
    assert lw.dof == 3 and lw.connected and not at4.readings["lwrist"].connected
    assert at2.readings["root"].weight == 2.0 and at2.readings["root"].connected
    assert apply_edits(raw, (), 0).readings == raw  # no studio sensors yet: the stream as it is


def test_a_recording_takes_the_studio_edits_of_a_clip_failures_included(synthetic_motion, tmp_path):
    """A recording of a clip's trackers, with the same edits, reads as the clip does
    (the recording's lost-tracker windows were ignored before both used apply_edits)."""
    from engine.tracker_io.recording import write_recording
    from engine.tracker_io.sender import plan_stream
    from engine.tracker_io.trackers import TrackerSample

    plan = plan_stream(synthetic_motion.slice(0, 6), "6")
    samples = [TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan)) for n, p, r in plan.frame(i)]
    write_recording(tmp_path / "rec.jsonl", samples, 60.0)
    rec = RecordingSource(tmp_path / "rec.jsonl")
    sensors = (Sensor("root"), Sensor("lwrist", dof=3, offset=(0.0, 0.1, 0.0), failures=((1, 3),)),
               Sensor("rwrist", enabled=False))  # fmt: skip
    rec.set_sensors(sensors)
    assert set(rec.frame(0).readings) == {"root", "lwrist"}
    assert [rec.frame(f).readings["lwrist"].connected for f in range(4)] == [True, False, False, True]
    lw = rec.frame(0).readings["lwrist"]
    assert lw.dof == 3 and np.array_equal(lw.rotation, [1.0, 0.0, 0.0, 0.0])
