"""Edit ▸ Re-solve range in the studio: the clip's range replaced, undo restores it."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def test_resolving_a_range_replaces_it_and_undo_redo_round_trip(studio, qtbot):
    from app.range_actions import resolve_range

    session = studio.session
    original = session.motion
    before = original.local_rot.copy()
    session.seek(40)
    edit = resolve_range(studio, 30, 50, blend=4)
    assert session.motion is edit.motion and session.frame == 40
    assert np.array_equal(session.motion.local_rot[: edit.first], before[: edit.first])
    assert np.array_equal(session.motion.local_rot[edit.last + 1 :], before[edit.last + 1 :])
    assert not np.array_equal(session.motion.local_rot[30:51], before[30:51])
    assert "resolve_range" in studio.actions_by_name and studio.undo.stack.count() == 1
    studio.undo.stack.undo()
    assert session.motion is original and np.array_equal(session.motion.local_rot, before)
    studio.undo.stack.redo()
    assert session.motion is edit.motion
    qtbot.waitUntil(lambda: session.latest is not None, timeout=10000)
