"""Range edits of a loaded clip: the rest untouched bit for bit, a sliding foot stopped."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.range_edit import edit_range
from engine.constraints import EndEffectorConstraint, FloorConstraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.motion.clip import Motion

LTOE, LANKLE, LWRIST = sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["lwrist"]
#: Frames of the bundled clip where the left toe is planted (below 8 cm, 2 mm/frame).
PLANTED = (150, 200)


@pytest.fixture(scope="module")
def sliding_clip():
    """The bundled clip with its planted left foot swung +-6 cm, about 2.4 cm per frame."""
    from engine.motion.retarget import load_motion

    m = load_motion(Path(__file__).resolve().parents[3] / "assets" / "clips" / "example.bvh")
    local = m.local_rot.copy()
    hip = sk.JOINT_INDEX["lhip"]
    for f in range(*PLANTED):
        a = 0.067 * np.sin(2 * np.pi * (f - PLANTED[0]) / 16)
        swing = np.array([np.cos(a / 2), np.sin(a / 2), 0.0, 0.0])  # about world X
        r0 = local[f, 0]
        local[f, hip] = QN.mul(QN.mul(QN.conjugate(r0), QN.mul(swing, r0)), local[f, hip])
    return Motion(local, m.root_pos, m.skeleton, m.fps, "sliding")


def speeds(motion: Motion, joint: int, frames: range) -> np.ndarray:
    p = motion.positions()[:, joint, :2]
    return np.array([np.linalg.norm(p[f] - p[f - 1]) for f in frames])


def test_floor_contact_stops_the_sliding_foot_and_the_rest_is_bit_identical(vae, sliding_clip):
    start, end, blend = PLANTED[0] + 5, PLANTED[1] - 5, 4
    inside = range(start + 1, end + 1)
    assert speeds(sliding_clip, LTOE, inside).max() > 0.02  # it really slides
    edit = edit_range(vae, sliding_clip, start, end, [FloorConstraint(name="floor")], blend=blend)
    assert (edit.first, edit.last) == (start - blend, end + blend)
    out = edit.motion
    pos = out.positions()
    contact = [f for f in inside if pos[f, LTOE, 2] < 0.08 and pos[f - 1, LTOE, 2] < 0.08]
    assert len(contact) > 0.8 * len(inside)
    for j in (LANKLE, LTOE):
        assert speeds(out, j, contact).max() < 0.01, sk.JOINT_NAMES[j]
    assert np.array_equal(out.local_rot[: edit.first], sliding_clip.local_rot[: edit.first])
    assert np.array_equal(out.local_rot[edit.last + 1 :], sliding_clip.local_rot[edit.last + 1 :])
    assert np.array_equal(out.root_pos, sliding_clip.root_pos)
    assert not np.array_equal(out.local_rot[start:end], sliding_clip.local_rot[start:end])
    jump = np.linalg.norm(np.diff(pos[edit.first - 1 : edit.last + 2], axis=0), axis=-1).max()
    assert jump < 0.05  # the blends leave no jump at either end


def test_a_raised_hand_target_is_met_on_the_range(vae, sliding_clip):
    f0, f1 = 67, 73  # the body walks: a fixed point stays within reach for a few frames
    goal = sliding_clip.positions()[70, LWRIST] + [0.0, 0.0, 0.2]
    edit = edit_range(
        vae,
        sliding_clip,
        f0,
        f1,
        [EndEffectorConstraint(name="hand", joint="lwrist", position=goal, weight=10.0)],
        blend=5,
    )
    pos = edit.motion.positions()
    assert np.linalg.norm(pos[f0 : f1 + 1, LWRIST] - goal, axis=-1).max() < 0.01
    assert np.array_equal(edit.motion.local_rot[: f0 - 5], sliding_clip.local_rot[: f0 - 5])


def test_bad_ranges_are_errors(vae, sliding_clip):
    with pytest.raises(UserError, match="range"):
        edit_range(vae, sliding_clip, 10, 5, [])
    with pytest.raises(UserError, match="range"):
        edit_range(vae, sliding_clip, 0, len(sliding_clip), [])


def contact_slide(
    before: Motion, after: Motion, joint: int, frames: range, floor: FloorConstraint
) -> tuple[float, float]:
    """Mean horizontal step (m/frame) of ``joint`` before and after an edit, over the
    steps of ``frames`` where the clip has it down on both frames."""
    a, b = before.positions(), after.positions()
    down = [f for f in frames if max(a[f, joint, 2], a[f - 1, joint, 2]) < floor.floor_height + floor.contact_height]
    if not down:
        return 0.0, 0.0
    step = lambda p: float(np.mean([np.linalg.norm(p[f, joint, :2] - p[f - 1, joint, :2]) for f in down]))  # noqa: E731
    return step(a), step(b)


@pytest.mark.shared_data
@pytest.mark.parametrize("clip, start, end", [("cmu_iclone/005_04.bvh", 300, 360), ("cmu_mb/05_04.bvh", 530, 599)])
def test_a_floor_contact_resolve_of_a_cmu_clip_pops_no_joint_and_slides_no_foot_more(
    vae, shared_mocap, clip, start, end
):
    """A re-solve with floor contact made a joint jump 10-34 cm in a frame where
    the clip moves 5 cm, and planted toes slide 0.2 -> 2.5 cm/frame."""
    from engine.motion.retarget import load_motion

    m = load_motion(shared_mocap / clip)
    floor = FloorConstraint(name="floor")
    edit = edit_range(vae, m, start, end, [floor], blend=8)
    lo, hi = edit.first, edit.last
    a = m.positions()[lo - 1 : hi + 2]
    b = edit.motion.positions()[lo - 1 : hi + 2]
    limit = max(1.5 * np.linalg.norm(np.diff(a, axis=0), axis=-1).max(), 0.03)
    assert np.linalg.norm(np.diff(b, axis=0), axis=-1).max() <= limit
    for name in ("ltoe", "rtoe", "lankle", "rankle"):
        was, now = contact_slide(m, edit.motion, sk.JOINT_INDEX[name], range(lo, min(hi + 2, len(m))), floor)
        assert now <= was + 1e-6, (name, was, now)
