"""Writing a canonical motion back onto the source's own rig (``--on-source-rig``).

* the trajectory goes on whichever joint carries it in the source: a static ``joint_Root``
  above a 6-channel ``Hips`` (every joint with 6 channels) keeps its channels, the hips travel;
* the source's frame rate is kept unless another is asked for;
* a clip read and written back reproduces the source's mapped joints within 1 cm over the
  whole clip (here on the synthetic rig; on each shared rig family in
  ``test_retarget_shared.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from engine.kinematics.fk import fk
from engine.motion.retarget_strategy import CURRENT
from tests.engine.test_retarget_body import canonical_walk, write_rig


def _world(raw, skip=0):
    """World positions (F, J, 3) of a parsed file, every position channel applied."""
    pos = raw.positions[skip:]
    moving = np.array([len(c) == 6 for c in raw.channels])
    local = np.where(moving[None, :, None], pos, raw.offsets[None])
    return fk(raw.local_quaternions()[skip:], pos[:, 0], local, list(raw.parents))[0]


@pytest.fixture
def hub_rig(tmp_path):
    from engine.motion.bvh import load_bvh

    local, root = canonical_walk(90)
    return load_bvh(write_rig(tmp_path / "hub.bvh", local[::2], root[::2], hub=True, fps=30.0))


def test_a_static_root_above_moving_hips_is_read_with_its_trajectory(hub_rig):
    from engine.motion.retarget import retarget

    assert np.ptp(hub_rig.positions[:, 0], axis=0).max() == 0.0, "joint_Root never moves"
    motion, rep = retarget(hub_rig, strategy=CURRENT)
    hips = _world(hub_rig)[:, 1]
    travel = np.ptp(hips, axis=0)
    assert travel.max() > 0.5
    assert np.allclose(np.ptp(motion.root_pos, axis=0), travel, atol=0.01), (np.ptp(motion.root_pos, axis=0), travel)


def test_written_back_the_hips_carry_the_trajectory_at_the_source_rate(hub_rig, tmp_path):
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget
    from engine.motion.write_back import save_on_source_rig

    motion, rep = retarget(hub_rig, strategy=CURRENT)
    save_on_source_rig(tmp_path / "back.bvh", motion, hub_rig, rep)
    back = load_bvh(tmp_path / "back.bvh")
    assert abs(back.fps - 30.0) < 0.01 and back.frames == hub_rig.frames
    assert np.allclose(back.positions[:, 0], hub_rig.positions[:, 0]), "the static root stays where it was"
    idx = [hub_rig.names.index(s) for s in rep.profile.joints.values()]
    err = np.linalg.norm(_world(back)[:, idx] - _world(hub_rig)[:, idx], axis=-1)
    assert err.max() < 0.01, f"{100 * err.max():.2f} cm"
    others = [k for k in range(2, len(hub_rig.names))]  # position channels of the other joints, as the source has them
    assert np.allclose(back.positions[:, others], hub_rig.positions[:, others], atol=1e-5)


def test_fps_asked_for_resamples_the_written_file(hub_rig, tmp_path):
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget
    from engine.motion.write_back import save_on_source_rig

    motion, rep = retarget(hub_rig, strategy=CURRENT)
    save_on_source_rig(tmp_path / "back60.bvh", motion, hub_rig, rep, fps=60.0)
    back = load_bvh(tmp_path / "back60.bvh")
    assert abs(back.fps - 60.0) < 0.01 and back.frames == 2 * hub_rig.frames - 1
    idx = [hub_rig.names.index(s) for s in rep.profile.joints.values()]
    err = np.linalg.norm(_world(back)[::2, idx] - _world(hub_rig)[:, idx], axis=-1)
    assert err.max() < 0.01, f"{100 * err.max():.2f} cm"
