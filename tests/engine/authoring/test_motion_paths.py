"""Motion paths: a clip's, a bake's over the keyed range, and the preview from the keys
that passes through each key and stays near the bake between them."""

from __future__ import annotations

import copy
import time

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.bake import bake
from engine.authoring.character import Character
from engine.authoring.document import AuthoringScene
from engine.authoring.keys import Animation, Key
from engine.authoring.motion_paths import (
    MotionPaths,
    authored_paths,
    baked_paths,
    clip_paths,
    keyed_paths,
    path_joints,
)
from engine.authoring.pose_mode import PoseMode

LW = sk.JOINT_INDEX["lwrist"]


def test_the_batch_decode_is_the_single_decode(vae):
    c = Character(vae, 1.75)
    rng = np.random.default_rng(3)
    z = (0.7 * rng.normal(size=(4, c.latent_dim))).astype(np.float32)
    xy, headings = rng.normal(size=(4, 2)), rng.uniform(-180, 180, 4)
    local, root, positions = c.decode_many(z, xy, headings)
    for i in range(4):
        one = c.decode(z[i], c.grounded(xy[i], headings[i]))
        assert np.abs(one.positions - positions[i]).max() < 1e-5
        assert np.abs(one.local_rot - local[i]).max() < 1e-5
        assert np.abs(one.root_pos - root[i]).max() < 1e-5


def test_a_clips_paths_are_its_joint_positions_marked_each_second(synthetic_motion):
    m = synthetic_motion  # 120 frames at 60 fps
    paths = clip_paths(m, 10, 100)
    assert (paths.first, paths.last) == (10, 100) and paths.exact
    np.testing.assert_allclose(paths.positions, m.positions()[10:101], atol=1e-9)
    assert paths.marks == (60,)
    assert clip_paths(m).marks == (0, 60) and clip_paths(m).last == 119
    np.testing.assert_allclose(paths.at("lwrist", 50), m.positions()[50, LW], atol=1e-9)
    assert paths.at("lwrist", 101) is None
    with pytest.raises(ValueError, match="motion path positions"):
        MotionPaths(0, np.zeros((3, 5, 3)))


def test_the_joints_drawn_are_the_selected_and_the_feet():
    assert path_joints("lwrist", True) == ("lwrist", "lankle", "rankle")
    assert path_joints("lankle", True) == ("lankle", "rankle")
    assert path_joints(None, False) == () and path_joints("nosuch", False) == ()


@pytest.fixture(scope="module")
def wave(vae):
    """Three keys of the left wrist (frames 0, 12, 24), posed as the pose window keys
    them: the pose's latent, its targets, where it stands."""
    mode = PoseMode(vae, 1.75)
    start = mode.pose.positions[LW].copy()
    keys = []
    for frame, offset in ((0, [0.0, -0.1, 0.1]), (12, [0.15, -0.2, 0.45]), (24, [0.3, -0.1, 0.2])):
        for k in range(1, 6):  # dragged in a few events, as a hand does
            mode.set_target("lwrist", start + np.array(offset) * k / 5)
            mode.solve()
        p = mode.pose
        keys.append(Key(frame, copy.deepcopy(mode.targets), p.latent.copy(), p.root_pos[:2].copy(), mode.heading))
    posing = PoseMode(vae, 1.75)
    exact = {k.frame: posing.pose_key(k).positions.copy() for k in keys}  # as a scrub to the key shows it
    return mode.character, keys, exact


def test_the_preview_passes_through_every_key_and_is_smooth(wave):
    character, keys, exact = wave
    t = time.perf_counter()
    paths = keyed_paths(character, keys, "cubic")
    ms = (time.perf_counter() - t) * 1000
    assert paths is not None and not paths.exact
    assert (paths.first, paths.last, paths.marks) == (0, 24, (0, 12, 24))
    for frame, positions in exact.items():
        assert np.abs(paths.positions[frame] - positions).max() < 1e-5, frame
    line = paths.line("lwrist")
    steps = np.linalg.norm(np.diff(line, axis=0), axis=1)
    assert steps.max() < 3 * np.median(steps) + 0.005, "no jump along the path"
    assert ms < 500, f"the preview took {ms:.0f} ms"


def test_keys_without_a_latent_leave_the_preview(wave):
    character, keys, _ = wave
    bare = [Key(k.frame, k.targets) for k in keys]
    assert keyed_paths(character, bare, "cubic") is None
    some = [keys[0], bare[1], keys[2]]
    paths = keyed_paths(character, some, "linear")
    assert paths is not None and paths.marks == (0, 12, 24)


def test_the_bake_replaces_the_preview_and_stays_near_it(wave, vae):
    character, keys, _ = wave
    scene = AuthoringScene(animation=Animation(fps=30.0, frames=30), keys=keys, height=character.height)
    baked = bake(scene, vae)
    exact = authored_paths(character, keys, "cubic", baked)
    assert exact is not None and exact.exact and (exact.first, exact.last) == (0, 24)
    np.testing.assert_allclose(exact.positions, baked.motion.positions()[:25], atol=1e-9)
    assert baked_paths(baked, []) is None
    preview = keyed_paths(character, keys, "cubic")
    for joint, cm in (("lwrist", 1.0), ("lelbow", 2.0), ("lankle", 2.5), ("root", 2.0)):
        gap = np.linalg.norm(preview.line(joint) - exact.line(joint), axis=1).max() * 100
        assert gap < cm, f"the preview's {joint} is {gap:.1f} cm off the bake"
