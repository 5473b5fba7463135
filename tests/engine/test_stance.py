"""The stance classifier (engine/models/stance.py, engine/training/stance.py): its features
are the same for one window and for a batch and do not depend on where the walker is or
which way it goes; it learns which foot stands from a sway the arms do not show; the file
round-trips; ``train stance`` writes a model; the gait planner takes its confident answer."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine import skeleton as sk
from engine.cli.main import main
from engine.errors import UserError
from engine.kinematics import quat_np
from engine.models.stance import N_FEATURES, StanceModel, stance_features, window_frames
from engine.solver.gait import GaitPlanner
from engine.training.stance import ANKLES, HANDS, HEAD, accuracy, clip_samples, load_samples, train_stance

FPS = 60.0


def swaying_walk(frames: int = 600, phase: float = 0.0) -> np.ndarray:
    """Joint positions ``(F, 22, 3)`` of a walker along +Y at 1 m/s whose head sways 3 cm
    towards the standing foot (one step per half second) and whose hands hang still beside it:
    the left foot stands (still) while the sway is positive, the right one swings ahead."""
    t = np.arange(frames) / FPS
    s = np.sin(2.0 * np.pi * t + phase)
    pos = np.zeros((frames, 22, 3))
    pos[:, HEAD] = np.stack([0.03 * s, t, np.full(frames, 1.6)], axis=-1)
    pos[:, HANDS[0]] = pos[:, HEAD] + [0.2, 0.0, -0.6]
    pos[:, HANDS[1]] = pos[:, HEAD] + [-0.2, 0.0, -0.6]
    for k, standing in ((0, s > 0), (1, s <= 0)):
        step = np.where(standing, 0.0, 2.0 / FPS)  # a swinging foot moves at 2 m/s
        pos[:, ANKLES[k], 1] = np.cumsum(step)
        pos[:, ANKLES[k], 0] = 0.1 if k == 0 else -0.1
    return pos


def _windows(pos: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
    k = window_frames(FPS)
    return pos[t - k + 1 : t + 1, HEAD], pos[t - k + 1 : t + 1][:, list(HANDS)]


def test_one_window_gives_the_batch_row_and_the_place_and_heading_do_not_matter():
    pos = swaying_walk(200)
    head, hands = _windows(pos, 120)
    one = stance_features(head, hands, FPS)
    assert one is not None and one.shape == (N_FEATURES,)
    k = window_frames(FPS)
    heads = np.stack([_windows(pos, t)[0] for t in range(k - 1, 200)])
    handss = np.stack([_windows(pos, t)[1] for t in range(k - 1, 200)])
    batch = stance_features(heads, handss, FPS)
    assert batch is not None and batch.shape == (200 - k + 1, N_FEATURES)
    np.testing.assert_allclose(batch[120 - (k - 1)], one, atol=1e-12)
    # the same window moved 5 m away and turned 70 degrees about the vertical
    q = quat_np.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.array(np.radians(70.0)))
    moved = stance_features(
        quat_np.rotate(q, head) + [5.0, -2.0, 0.0], quat_np.rotate(q, hands) + [5.0, -2.0, 0.0], FPS
    )
    np.testing.assert_allclose(moved, one, atol=1e-9)


def test_a_head_that_does_not_travel_has_no_features():
    pos = swaying_walk(100)
    pos[:, HEAD, :2] = 0.0
    head, hands = _windows(pos, 80)
    assert stance_features(head, hands, FPS) is None


def test_it_learns_the_standing_foot_from_a_sway_the_arms_do_not_show():
    train = clip_samples(swaying_walk(900), FPS)
    test = clip_samples(swaying_walk(600, phase=1.0), FPS)
    assert len(train.y) > 500 and 0.3 < train.y.mean() < 0.7
    model = train_stance(train, hidden=16, epochs=40)
    a = accuracy(model, test)
    assert a["model"] > 0.9
    assert a["arms_coverage"] == 0.0  # hands hanging still: the arm rule cannot tell


def test_the_model_file_round_trips_and_a_wrong_file_is_named(tmp_path):
    model = train_stance(clip_samples(swaying_walk(300), FPS), hidden=8, epochs=2)
    path = tmp_path / "stance.npz"
    model.save(path)
    assert not list(tmp_path.glob("*.tmp*"))
    back = StanceModel.load(path)
    x = clip_samples(swaying_walk(200, phase=0.5), FPS).x
    np.testing.assert_allclose(back.left_stance(x), model.left_stance(x), atol=1e-5)
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(2))
    with pytest.raises(UserError, match="other.npz: not a stance model"):
        StanceModel.load(other)


def _fixed(p_left: float) -> StanceModel:
    """A model that answers ``p_left`` whatever it reads."""
    logit = np.log(p_left / (1.0 - p_left))
    return StanceModel(np.zeros(N_FEATURES), np.ones(N_FEATURES), (np.zeros((N_FEATURES, 1)),), (np.array([logit]),))


@pytest.mark.parametrize(("p_left", "expected"), [(0.9, 0), (0.1, 1), (0.6, None)])
def test_the_planner_takes_a_confident_answer_only(p_left, expected):
    pos = swaying_walk(120)
    planner = GaitPlanner(FPS, stance=_fixed(p_left))
    for f in range(60):
        planner.update(pos[f, HEAD], pos[f], pos[f, list(HANDS)], pos[f, HEAD])
    assert planner.learned_stance() == expected
    if expected is not None:
        assert planner.update(pos[60, HEAD], pos[60], pos[60, list(HANDS)], pos[60, HEAD]).stance == expected
    # without the head the classifier cannot read and says nothing
    planner.update(pos[61, HEAD], pos[61], pos[61, list(HANDS)], None)
    assert planner.learned_stance() is None


def _prepared(root, frames: int = 400) -> None:
    """A prepared folder of two swaying walks (train and val): hips swinging the legs
    fore and aft, the root swaying towards the standing leg."""
    shards = root / "shards"
    shards.mkdir(parents=True)
    files = []
    for i, split in enumerate(("train", "val")):
        t = np.arange(frames) / FPS
        s = np.sin(2.0 * np.pi * t + i)
        rot = np.zeros((frames, 22, 4))
        rot[..., 0] = 1.0
        x = np.array([1.0, 0.0, 0.0])
        rot[:, sk.JOINT_INDEX["lhip"]] = quat_np.from_axis_angle(x, 0.4 * s)
        rot[:, sk.JOINT_INDEX["rhip"]] = quat_np.from_axis_angle(x, -0.4 * s)
        root_pos = np.stack([0.03 * s, 1.2 * t, np.full(frames, 0.95)], axis=-1)
        name = f"shards/walk{i}.npz"
        np.savez(root / name, local_rot=rot, root_pos=root_pos, offsets=sk.REST_OFFSETS)
        files.append({"split": split, "mirrored": False, "shard": name})
    (root / "manifest.json").write_text(json.dumps({"fps": FPS, "files": files}))


def test_train_stance_writes_a_model_and_reports_against_the_arm_rule(tmp_path, capsys):
    _prepared(tmp_path / "prepared")
    out = tmp_path / "runs" / "stance.npz"
    code = main(
        ["train", "stance", "--data", str(tmp_path / "prepared"), "--out", str(out), "--hidden", "8", "--epochs", "3"]
    )
    assert code == 0
    said = capsys.readouterr().out
    assert "validation" in said and "arm-swing rule" in said
    StanceModel.load(out)


def test_train_stance_names_a_folder_without_prepared_data(tmp_path):
    with pytest.raises(UserError, match="manifest.json not found"):
        load_samples(tmp_path, "train")
