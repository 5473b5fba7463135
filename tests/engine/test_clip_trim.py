"""Trimming a clip to a frame range: the motion, the scene's frame ranges, the write-back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.constraints import FloorConstraint, PinConstraint
from engine.errors import UserError
from engine.sensors import Sensor
from engine.studio.clip_trim import trim_clip, trim_failures


def test_trim_keeps_frames_first_to_last_inclusive_as_copies_and_counts_its_start(synthetic_motion):
    m = synthetic_motion
    cut = m.trim(89, 110)
    assert len(cut) == 22 and cut.start == 89 and cut.fps == m.fps and cut.skeleton is m.skeleton
    assert np.array_equal(cut.local_rot, m.local_rot[89:111]) and np.array_equal(cut.root_pos, m.root_pos[89:111])
    cut.local_rot[0] = 0.0
    assert not np.array_equal(m.local_rot[89], cut.local_rot[0])  # a copy: the original is untouched
    again = cut.trim(1, 5)  # trimmed twice: still counted from the clip as loaded
    assert again.start == 90 and np.array_equal(again.root_pos, m.root_pos[90:95])
    assert len(m.trim(0, len(m) - 1)) == len(m) and len(m.trim(7, 7)) == 1


@pytest.mark.parametrize("first,last", [(-1, 5), (5, 4), (0, 120), (200, 210)])
def test_trim_refuses_a_range_outside_the_clip(synthetic_motion, first, last):
    with pytest.raises(UserError, match="frames 0-119"):
        synthetic_motion.trim(first, last)


def test_constraint_ranges_move_with_the_frames_and_one_outside_is_turned_off(synthetic_motion):
    inside = PinConstraint(name="inside", joint="lwrist", frames=(40, 50), blend_in=3)
    partly = PinConstraint(name="partly", joint="rwrist", frames=(10, 35))
    over = PinConstraint(name="over", joint="lankle", frames=(90, 119), blend_out=4)
    before = PinConstraint(name="before", joint="rankle", frames=(0, 20))
    every = FloorConstraint(name="floor")
    scene = [inside, partly, over, before, every]
    out = trim_clip(synthetic_motion, scene, [], 30, 100)
    got = {c.name: c for c in out.constraints}
    assert [c.name for c in out.constraints] == [c.name for c in scene]  # same order
    assert got["inside"].frames == (10, 20) and got["inside"].blend_in == 3 and got["inside"].enabled
    assert got["partly"].frames == (0, 5) and got["partly"].enabled  # cut at the start: clamped
    assert got["over"].frames == (60, 70) and got["over"].blend_out == 4  # cut at the end
    assert got["before"].frames == (0, 0) and not got["before"].enabled  # wholly outside: off
    assert got["floor"] is every  # every frame: unchanged
    assert out.turned_off == ("before",)
    # the weights at the kept frames are those they had
    for name in ("inside", "partly", "over"):
        old = next(c for c in scene if c.name == name)
        assert [got[name].activity(f - 30) for f in range(30, 101)] == [old.activity(f) for f in range(30, 101)]
    assert inside.frames == (40, 50) and before.enabled  # the inputs are not changed


def test_tracker_failures_move_with_the_frames_and_ones_outside_are_dropped(synthetic_motion):
    assert trim_failures(((5, 10), (25, 40), (60, 80), (95, 110)), 30, 100) == ((0, 10), (30, 50), (65, 71))
    lost = Sensor("lwrist", failures=((50, 60),))
    plain = Sensor("rwrist")
    out = trim_clip(synthetic_motion, [], [lost, plain], 40, 80)
    assert out.sensors[0].failures == ((10, 20),) and out.sensors[1] is plain
    assert out.sensors[0].lost_at(10) and not out.sensors[0].lost_at(20)


def _with_rest_frame(path: Path) -> Path:
    """``path`` with a rest pose (rotations 0) put before its first frame, as cgspeed
    conversions start: retargeting skips it (``report.skip`` = 1)."""
    lines = path.read_text().splitlines()
    i = lines.index("MOTION")
    first = lines[i + 3].split()
    lines.insert(i + 3, " ".join(first[:3] + ["0"] * (len(first) - 3)))
    lines[i + 1] = f"Frames: {int(lines[i + 1].split()[1]) + 1}"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_trimmed_clip_is_written_onto_the_source_rig_as_the_source_frames_it_holds(tmp_path):
    """A source at 120 fps with a skipped rest frame: frame 0 of the clip trimmed at clip
    frame 10 (60 fps) is source frame 1 + 20; the trimmed file is those frames of the
    whole clip's file."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget
    from engine.motion.write_back import save_on_source_rig
    from tests.engine.rig_fixtures import write_family_bvh

    src = _with_rest_frame(write_family_bvh(tmp_path / "mixamo.bvh", "mixamo", frames=120, fps=120.0))
    raw = load_bvh(src)
    motion, rep = retarget(raw)
    assert rep.skip == 1 and rep.source_fps == 120.0 and motion.fps == 60.0
    save_on_source_rig(tmp_path / "whole.bvh", motion, raw, rep)
    save_on_source_rig(tmp_path / "cut.bvh", motion.trim(10, 39), raw, rep)
    whole, cut = load_bvh(tmp_path / "whole.bvh"), load_bvh(tmp_path / "cut.bvh")
    assert cut.frames >= 58 and cut.names == whole.names
    n = cut.frames - 2  # the last source frames are resampled from the cut's end
    assert np.allclose(cut.positions[:n], whole.positions[20 : 20 + n], atol=1e-4)
    rot = np.abs(((cut.rotations_deg[:n] - whole.rotations_deg[20 : 20 + n]) + 180.0) % 360.0 - 180.0)
    assert rot.max() < 1e-3
    # and not the first source frames: the trim is not ignored
    assert not np.allclose(cut.positions[:n], whole.positions[:n], atol=1e-4)
