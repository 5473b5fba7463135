"""File ▸ Save edited clip: a range-re-solved clip written as it is, onto its source rig or canonical."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk

pytestmark = pytest.mark.gui


def test_a_range_edit_is_written_onto_the_source_rig(studio, qtbot, tmp_path):
    from app.clip_saving import save_clip
    from app.range_actions import resolve_range
    from engine.motion.bvh import load_bvh
    from engine.studio.clips import load_clip
    from tests.engine.rig_fixtures import write_family_bvh

    src = write_family_bvh(tmp_path / "mixamo.bvh", "mixamo", frames=120)
    assert studio.files.open_path(src)
    assert resolve_range(studio, 40, 70, blend=4).wait() is not None
    out = tmp_path / "edited_rig.bvh"
    save_clip(studio, out, on_source_rig=True)
    raw, back = load_bvh(src), load_bvh(out)
    assert back.names == raw.names and back.frames == raw.frames  # the user's own rig and rate
    assert np.allclose(back.offsets, raw.offsets, atol=1e-5)
    before, after = load_clip(src).positions(), load_clip(out).positions()
    moved = np.linalg.norm(after - before, axis=-1).max(axis=1)  # per frame, metres
    assert moved[:36].max() < 0.01 and moved[75:].max() < 0.01  # outside the range and its blends: kept
    assert moved[40:71].max() > 0.01  # inside: the edit, not the original
    canon = tmp_path / "edited.bvh"
    save_clip(studio, canon)
    assert list(load_bvh(canon).names) == list(sk.JOINT_NAMES)
    qtbot.waitUntil(lambda: studio.session.latest is not None, timeout=10000)


def test_a_clip_not_opened_from_a_file_has_no_source_rig_and_nothing_is_written(studio, tmp_path):
    from app.clip_saving import save_clip
    from engine.errors import UserError

    out = tmp_path / "x.bvh"
    with pytest.raises(UserError, match="not opened from a BVH file"):
        save_clip(studio, out, on_source_rig=True)
    assert not out.exists()
