"""Every sensor source implements one contract and applies the studio's edits one way."""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest

from engine.sensor_source import SensorSource, apply_edits
from engine.sensors import Sensor
from engine.studio.clip_source import ClipSource
from engine.tracker_io.recording_source import RecordingSource

ENGINE = Path(__file__).resolve().parents[2] / "engine"


def _declared_sources() -> list[tuple[str, str]]:
    """``(module, class)`` of every class under engine/ whose bases name SensorSource
    (read from the source text, so a new source is checked without editing this test)."""
    found = []
    for path in sorted(ENGINE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and any(
                getattr(b, "id", getattr(b, "attr", "")) == "SensorSource" for b in node.bases
            ):
                module = ".".join(path.relative_to(ENGINE.parent).with_suffix("").parts)
                found.append((module, node.name))
    return found


SOURCES = _declared_sources()


def test_the_shipped_sources_are_found():
    assert {c for _, c in SOURCES} >= {"ClipSource", "LiveSource", "RecordingSource"}


@pytest.mark.parametrize("module, name", SOURCES, ids=[c for _, c in SOURCES])
def test_every_source_is_a_concrete_sensor_source_with_the_whole_contract(module, name):
    cls = getattr(importlib.import_module(module), name)
    assert SensorSource in cls.__mro__ and not inspect.isabstract(cls), "abstract members left"
    for member in ("fps", "num_frames", "frame", "ground_truth", "set_sensors", "arrival", "close"):
        assert hasattr(cls, member), member
    base = inspect.signature(SensorSource.frame).parameters
    assert list(inspect.signature(cls.frame).parameters) == list(base)


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
    sensors = (
        Sensor("root", weight=2.0),
        Sensor("lwrist", dof=3, offset=(0.0, 0.0, 0.5), failures=((3, 5),)),
        Sensor("rwrist", enabled=False),
        Sensor("upperneck"),
    )
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
    sensors = (
        Sensor("root"),
        Sensor("lwrist", dof=3, offset=(0.0, 0.1, 0.0), failures=((1, 3),)),
        Sensor("rwrist", enabled=False),
    )
    rec.set_sensors(sensors)
    assert set(rec.frame(0).readings) == {"root", "lwrist"}
    assert [rec.frame(f).readings["lwrist"].connected for f in range(4)] == [True, False, False, True]
    lw = rec.frame(0).readings["lwrist"]
    assert lw.dof == 3 and np.array_equal(lw.rotation, [1.0, 0.0, 0.0, 0.0])
