"""The heading network (engine/models/heading.py, engine/training/heading.py): its features do
not depend on where the body is or which way it faces; it learns the pelvis heading where the
feet-and-hands facing is off; the file round-trips and a wrong file is named; ``train
heading`` writes a model; DragPoser's trackers use it only with a 3-DoF hip and all six of
its trackers, and restart its window when one is lost."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from engine import skeleton as sk
from engine.cli.main import main
from engine.errors import UserError
from engine.kinematics import quat_np
from engine.methods.dragposer_parts import TrackerTerms
from engine.models.heading import JOINTS, N_FEATURES, HeadingModel, heading_features, rough_yaw, window_frames
from engine.sensors import Sensor, SensorFrame
from engine.solver import OptimizerSettings
from engine.training.heading import angle_error_deg, clip_samples, load_samples, pelvis_yaw, train_heading

FPS = 60.0
#: The body-frame positions (left +X, forward -Y, z up) of the six joints: the hands held
#: turned 50 degrees from the body's left-right line (carrying something), so the facing of
#: the feet and hands is :data:`_ROUGH` degrees off the pelvis's.
_HANDS_TURN = math.radians(50.0)
_BODY = np.array(
    [
        [0.0, 0.0, 0.95],
        [0.0, 0.0, 1.6],
        [0.3 * math.cos(_HANDS_TURN), 0.3 * math.sin(_HANDS_TURN), 1.0],
        [-0.3 * math.cos(_HANDS_TURN), -0.3 * math.sin(_HANDS_TURN), 1.0],
        [0.1, 0.0, 0.05],
        [-0.1, 0.0, 0.05],
    ]
)

_ROUGH = math.degrees(math.atan2(0.6 * math.sin(_HANDS_TURN), 0.2 + 0.6 * math.cos(_HANDS_TURN)))  # 38.1


def _about_z(yaw: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=-1)


def turning_walk(frames: int = 900, rate: float = 0.7, phase: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions ``(F, 22, 3)`` and root rotations ``(F, 4)`` of a body walking forward
    at 1 m/s while turning at ``rate`` rad/s, the six tracked joints at :data:`_BODY`."""
    t = np.arange(frames) / FPS
    yaw = phase + rate * t
    rot = _about_z(yaw)
    fwd = np.stack([np.sin(yaw), -np.cos(yaw)], axis=-1)  # -Y turned by yaw
    ground = np.concatenate([np.cumsum(fwd, axis=0) / FPS, np.zeros((frames, 1))], axis=-1)
    pos = np.zeros((frames, 22, 3))
    for k, j in enumerate(JOINTS):
        pos[:, sk.JOINT_INDEX[j]] = ground + quat_np.rotate(rot, np.broadcast_to(_BODY[k], (frames, 3)))
    return pos, rot


def test_pelvis_yaw_is_the_heading_of_the_root_rotation():
    q = quat_np.normalize(np.random.default_rng(0).normal(size=(20, 4)))
    h = quat_np.heading(q)
    assert np.allclose(np.angle(np.exp(1j * (2 * np.arctan2(h[:, 3], h[:, 0]) - pelvis_yaw(q)))), 0.0, atol=1e-9)


def test_features_do_not_depend_on_place_or_facing():
    pos, _ = turning_walk(200)
    window = pos[-window_frames(FPS) :][:, [sk.JOINT_INDEX[j] for j in JOINTS]]
    x, rough = heading_features(window)
    assert x.shape == (N_FEATURES,)
    turn = 1.3
    moved = quat_np.rotate(_about_z(np.array(turn)), window) + np.array([5.0, -2.0, 0.0])
    x2, rough2 = heading_features(moved)
    assert np.allclose(x, x2, atol=1e-9)
    assert math.remainder(rough2 - rough - turn, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    # a batch of windows gives the rows of the single ones
    xb, _ = heading_features(np.stack([window, moved]))
    assert np.allclose(xb[1], x2)
    # the rough facing reads feet and hands alike (the hands' 0.6 m line outweighs the feet's 0.2)
    assert math.degrees(rough_yaw(_BODY)) == pytest.approx(_ROUGH, abs=1e-9)


def test_it_learns_the_heading_where_the_feet_and_hands_facing_is_off():
    # walks turning at nine rates from -0.8 to 0.8 rad/s; judged on one at a rate between them
    train = [clip_samples(*turning_walk(600, rate, 3 * rate), FPS, stride=2) for rate in np.linspace(-0.8, 0.8, 9)]
    samples = type(train[0])(*(np.concatenate([getattr(s, f) for s in train]) for f in ("x", "rough", "truth")))
    model = train_heading(samples, hidden=64, epochs=30)
    val = clip_samples(*turning_walk(600, 0.3, 4.0), FPS)
    rough, learned = angle_error_deg(None, val).mean(), angle_error_deg(model, val).mean()
    assert rough == pytest.approx(_ROUGH, abs=0.5)
    assert learned < 3.0
    # the model's own answer on a window is the same
    pos, _ = turning_walk(600, 0.3, 4.0)
    window = pos[100 - window_frames(FPS) + 1 : 101][:, [sk.JOINT_INDEX[j] for j in JOINTS]]
    err = math.remainder(float(model.yaw(window)) - float(val.truth[100]), 2 * math.pi)
    assert abs(math.degrees(err)) < 5.0


def test_the_model_file_round_trips_and_a_wrong_file_is_named(tmp_path):
    rng = np.random.default_rng(1)
    model = HeadingModel(
        rng.normal(size=N_FEATURES),
        rng.uniform(0.5, 2.0, size=N_FEATURES),
        (rng.normal(size=(N_FEATURES, 4)), rng.normal(size=(4, 2))),
        (rng.normal(size=4), rng.normal(size=2)),
    )
    path = tmp_path / "h.npz"
    model.save(path)
    again = HeadingModel.load(path)
    x = rng.normal(size=(5, N_FEATURES))
    assert np.allclose(again.correction(x), model.correction(x), atol=1e-4)
    np.savez(tmp_path / "other.npz", mean=np.zeros(3))
    with pytest.raises(UserError, match="other.npz: not a heading model"):
        HeadingModel.load(tmp_path / "other.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(UserError, match="junk.npz: not a heading model"):
        HeadingModel.load(tmp_path / "junk.npz")


def _prepared(root) -> None:
    (root / "shards").mkdir(parents=True)
    files = []
    for i, split in enumerate(("train", "val")):
        pos, rot = turning_walk(300, 0.6 - i, float(i))
        local = np.zeros((len(pos), 22, 4))
        local[..., 0] = 1.0
        local[:, 0] = rot
        name = f"shards/w{i}.npz"
        # a rest skeleton turned and carried along: the shard's own FK gives its positions
        np.savez(root / name, local_rot=local, root_pos=pos[:, 0], offsets=sk.REST_OFFSETS)
        files.append({"split": split, "mirrored": False, "shard": name})
    (root / "manifest.json").write_text(json.dumps({"fps": FPS, "files": files}))


def test_train_heading_writes_a_model_and_reports_against_the_facing(tmp_path, capsys):
    _prepared(tmp_path / "prepared")
    out = tmp_path / "runs" / "heading.npz"
    args = ["train", "heading", "--data", str(tmp_path / "prepared"), "--out", str(out), "--hidden", "8"]
    assert main([*args, "--epochs", "2"]) == 0
    said = capsys.readouterr().out
    assert "mean heading error" in said and "feet-and-hands facing" in said
    HeadingModel.load(out)
    assert main([*args, "--stride", "0"]) != 0
    assert "--stride: 0 is not a whole number from 1 to 1000" in capsys.readouterr().err
    with pytest.raises(UserError, match="manifest.json not found"):
        load_samples(tmp_path, "train")


class _Fixed(HeadingModel):
    """A model whose correction is a fixed angle, whatever it reads."""

    def __init__(self, angle: float) -> None:
        super().__init__(np.zeros(N_FEATURES), np.ones(N_FEATURES), (), ())
        object.__setattr__(self, "angle", angle)

    def correction(self, features: np.ndarray) -> np.ndarray:
        return np.full(np.shape(features)[:-1], self.angle)  # type: ignore[attr-defined]


def _frame(dof: int, drop: str | None = None) -> SensorFrame:
    readings = {}
    for k, j in enumerate(JOINTS):
        if j != drop:
            d = dof if j == "root" else 3
            rot = np.array([1.0, 0.0, 0.0, 0.0]) if d == 6 else None
            readings[j] = Sensor(j, position=_BODY[k].copy(), rotation=rot, dof=d, connected=True)
    return SensorFrame(0, readings)


def _yaw_deg(q: np.ndarray) -> float:
    return math.degrees(2 * math.atan2(q[3], q[0]))


def test_dragposer_trackers_use_the_network_with_a_3dof_hip_and_all_six_trackers():
    s = OptimizerSettings()
    terms = TrackerTerms(heading=_Fixed(math.radians(-_ROUGH)))
    terms.update(_frame(3), s, FPS, None)
    assert _yaw_deg(terms.facing) == pytest.approx(0.0, abs=1e-6)  # the rough facing corrected
    assert terms.learned_facing
    assert len(terms._heading_window) == window_frames(FPS)
    # switched off: the feet's and hands' lines
    terms.update(_frame(3), OptimizerSettings(heading_network=False), FPS, None)
    assert _yaw_deg(terms.facing) == pytest.approx(_ROUGH, abs=1e-6)
    assert terms._heading_window == [] and not terms.learned_facing
    # a hand lost: the lines of what is left (the feet), and the window restarts
    terms.update(_frame(3), s, FPS, None)
    terms.update(_frame(3, drop="lwrist"), s, FPS, None)
    assert _yaw_deg(terms.facing) == pytest.approx(0.0, abs=1e-6)
    assert terms._heading_window == []
    # a 6-DoF hip gives its own heading: the lines (unused by the root rule)
    terms.update(_frame(6), s, FPS, None)
    assert _yaw_deg(terms.facing) == pytest.approx(_ROUGH, abs=1e-6)
    # without a network the lines as well
    plain = TrackerTerms()
    plain.update(_frame(3), s, FPS, None)
    assert _yaw_deg(plain.facing) == pytest.approx(_ROUGH, abs=1e-6)
