"""The tracker networks (engine/solver/tracker_net.py, engine/training/tracker_net.py): the
window a live frame gives is the window training took, the file, training, the command and
DragPoser taking the network's latent as the tracker prior's."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.cli.main import main
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods.dragposer import DragPoserMethod
from engine.solver.tracker_history import TrackerHistory
from engine.solver.tracker_net import HISTORY, WINDOW, TrackerNet, TrackerNets, default_tracker_nets, window_features
from engine.solver.tracker_prior import BANK_JOINTS, LAG, PoseBank, features
from engine.tracking import simulate
from engine.training.tracker_net import Takes, latent_mse, samples, train_net
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder

JOINTS = ("root", "upperneck", "lwrist", "rwrist")


def _take(rng, frames: int) -> Takes:
    pos = np.cumsum(rng.normal(scale=0.01, size=(frames, len(BANK_JOINTS), 3)), axis=0)
    rot = Q.normalize(rng.normal(size=(frames, len(BANK_JOINTS), 4)))
    return Takes([pos], [rot], [rng.normal(size=(frames, 4)).astype(np.float32)])


def test_window_features_read_the_frames_lag_apart_with_the_displacement_before_each():
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(2, WINDOW, 4, 3))
    rot = Q.normalize(rng.normal(size=(2, WINDOW, 4, 4)))
    x = window_features(pos, rot, JOINTS)
    d = x.shape[1] // HISTORY
    for h in range(HISTORY):
        t = WINDOW - 1 - LAG * h
        expect = features(pos[:, t], rot[:, t], 0, pos[:, t - LAG, 0])
        np.testing.assert_array_equal(x[:, h * d : (h + 1) * d], expect)


def test_a_live_window_is_the_window_training_took_from_the_take():
    """Frames pushed one at a time into the solver's history give, at every frame of a take,
    the inputs :func:`samples` built for that frame (the take's start padded alike)."""
    rng = np.random.default_rng(1)
    take = _take(rng, 50)
    x, z = samples(take, JOINTS)
    history = TrackerHistory(WINDOW)
    cols = [BANK_JOINTS.index(j) for j in JOINTS]
    for t in range(50):
        history.push({j: (take.positions[0][t, c], take.rotations[0][t, c]) for j, c in zip(JOINTS, cols)})
        joints, pos, rot = history.arrays()
        assert joints == JOINTS
        np.testing.assert_allclose(window_features(pos[None], rot[None], joints)[0], x[t], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(z, take.latents[0])


def test_history_takes_the_combination_from_the_last_frames_and_fills_a_late_joint_back():
    h = TrackerHistory(WINDOW)
    r = (np.zeros(3), np.array([1.0, 0, 0, 0]))
    for i in range(10):
        h.push({"root": (np.full(3, float(i)), r[1]), "lwrist": r, **({"rwrist": r} if i >= 10 - LAG - 1 else {})})
    joints, pos, rot = h.arrays()
    assert joints == ("root", "lwrist", "rwrist") and pos.shape == (WINDOW, 3, 3)
    # the hips' readings in order, the first one before the history's start
    np.testing.assert_array_equal(pos[-10:, 0, 0], np.arange(10.0))
    np.testing.assert_array_equal(pos[: WINDOW - 10, 0, 0], 0.0)
    h.push({"root": r, "lwrist": r})  # the right hand gone this frame: not in the combination
    assert h.arrays()[0] == ("root", "lwrist")


def test_the_default_history_keeps_the_banks_window():
    h = TrackerHistory()
    r = (np.zeros(3), np.array([1.0, 0, 0, 0]))
    for _ in range(WINDOW):
        h.push({"root": r, "lwrist": r})
    assert h.arrays()[1].shape == (LAG + 1, 2, 3)


def test_training_fits_a_latent_the_readings_determine():
    rng = np.random.default_rng(2)
    take = _take(rng, 600)
    x, _ = samples(take, JOINTS)
    w = rng.normal(size=(x.shape[1], 3)) / np.sqrt(x.shape[1])
    z = np.tanh(x @ w).astype(np.float32)  # a latent that is a function of the window
    spread = float(z.var(0).mean())  # the error of always answering the mean latent
    net = train_net(JOINTS, x, z, hidden=64, epochs=300)
    assert latent_mse(net, x, z) < 0.1 * spread


def test_the_file_round_trips_and_a_wrong_file_is_named(tmp_path):
    rng = np.random.default_rng(3)
    net = TrackerNet(
        JOINTS,
        rng.normal(size=5),
        np.ones(5),
        (rng.normal(size=(5, 7)).astype(np.float32), rng.normal(size=(7, 2)).astype(np.float32)),
        (np.zeros(7, np.float32), np.ones(2, np.float32)),
    )
    path = tmp_path / "nets.npz"
    TrackerNets({JOINTS: net}, "abc").save(path)
    back = TrackerNets.load(path)
    assert back.vae_sha256 == "abc" and back.get(JOINTS) is not None and back.get(("root", "lwrist")) is None
    x = rng.normal(size=(3, 5))
    np.testing.assert_allclose(back.get(JOINTS).forward(x), net.forward(x), rtol=1e-6)
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(UserError, match="other.npz: not a tracker network file"):
        TrackerNets.load(tmp_path / "other.npz")


class _Constant(TrackerNet):
    """A network that answers 0.25 in every latent dimension (a bias-only last layer)."""

    def __init__(self, joints, dim: int = 24) -> None:
        super().__init__(
            joints, np.zeros(1), np.ones(1), (np.zeros((1, dim), np.float32),), (np.full(dim, 0.25, np.float32),)
        )

    def latents(self, pos, rot):
        return np.full((len(pos), 24), 0.25, np.float32)


def _bank(rng) -> PoseBank:
    n = 64
    pos = rng.normal(size=(n, len(BANK_JOINTS), 3))
    rot = Q.normalize(rng.normal(size=(n, len(BANK_JOINTS), 4)))
    return PoseBank(pos, rot, pos[:, :2] + 0.01, np.full((n, 24), -0.5, np.float32), k=4)


@pytest.mark.parametrize("setting,expected", [("network", 0.25), ("neighbours", -0.5), ("both", -0.125)])
def test_dragposer_takes_the_networks_latent_for_its_combination(setting, expected):
    from engine.motion.clip import Motion

    f = 12
    t = np.arange(f) / 60.0
    clip = Motion(np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (f, 22, 1)), np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))
    nets = TrackerNets({JOINTS: _Constant(JOINTS)})
    torch.manual_seed(0)
    m = DragPoserMethod(
        MLPDecoder(),
        CountingPredictor(),
        iterations=2,
        bank=_bank(np.random.default_rng(4)),
        nets=nets,
        tracker_prior=setting,
    )
    seen = []
    solve = m.optimizer.solve

    def spy(start, terms, ctx, settings=None):
        seen.append(float(ctx.prediction.mean()))
        return solve(start, terms, ctx, settings)

    m.reset(clip.skeleton)
    m.optimizer.solve = spy
    tr = simulate(clip, "4")
    for i in range(4):
        m.step(tr.frame(i))
    assert seen[-1] == pytest.approx(expected)
    assert m.priors.from_bank  # the bank still gives the distance the standing legs read
    seen.clear()
    tr = simulate(clip, "3-head-hands")  # no network for this combination: the bank's
    m.reset(clip.skeleton)
    m.optimizer.solve = spy
    for i in range(4):
        m.step(tr.frame(i))
    assert seen[-1] == pytest.approx(-0.5)


def test_the_shipped_networks_belong_to_the_shipped_vae_and_cover_the_presets(tmp_path):
    from engine.methods.dragposer import preset_combinations

    nets = default_tracker_nets()
    if nets is None:
        pytest.skip("no shipped tracker networks (assets/models/tracker_nets.npz)")
    for joints in (("root", "upperneck", "lwrist", "rwrist"), ("upperneck", "lwrist", "rwrist")):
        assert joints in preset_combinations() and nets.get(joints) is not None
    other = tmp_path / "vae.pt"
    other.write_bytes(b"another VAE")
    assert default_tracker_nets(other) is None


def _prepared(root, frames: int = 120) -> None:
    """Two short takes (train and val) of a body walking forward."""
    shards = root / "shards"
    shards.mkdir(parents=True)
    files = []
    for i, split in enumerate(("train", "val")):
        t = np.arange(frames) / sk.FPS
        rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (frames, 22, 1))
        root_pos = np.stack([0.02 * np.sin(3 * t + i), 1.2 * t, np.full(frames, 0.95)], axis=-1)
        name = f"shards/walk{i}.npz"
        np.savez(root / name, local_rot=rot, root_pos=root_pos, offsets=sk.REST_OFFSETS)
        files.append({"split": split, "mirrored": False, "shard": name})
    (root / "manifest.json").write_text(json.dumps({"fps": sk.FPS, "files": files}))


def test_train_tracker_net_writes_the_presets_networks_for_the_shipped_vae(tmp_path, capsys):
    _prepared(tmp_path / "prepared")
    out = tmp_path / "nets.npz"
    args = ["train", "tracker-net", "--data", str(tmp_path / "prepared"), "--out", str(out)]
    assert main([*args, "--presets", "4,3-head-hands", "--hidden", "8", "--epochs", "2", "--stride", "8"]) == 0
    said = capsys.readouterr().out
    assert "root+upperneck+lwrist+rwrist: 15 samples, validation latent MSE" in said
    nets = TrackerNets.load(out)
    assert set(nets.nets) == {("root", "upperneck", "lwrist", "rwrist"), ("upperneck", "lwrist", "rwrist")}
    assert main([*args, "--presets", "6x3dof"]) != 0
    assert "--presets: '6x3dof' has no hips or head" in capsys.readouterr().err


def test_a_window_with_gaps_takes_each_frames_reading_else_the_next_one():
    rng = np.random.default_rng(5)
    h = TrackerHistory(WINDOW)
    pushed = []
    for _ in range(WINDOW - 3):  # fewer frames than the window: the start is repeated
        rd = {j: (rng.normal(size=3), rng.normal(size=4)) for j in BANK_JOINTS if rng.random() < 0.7}
        rd.update({j: (rng.normal(size=3), rng.normal(size=4)) for j in ("root", "lwrist")})
        pushed.append(rd)
        h.push(rd)
    joints, pos, rot = h.arrays()
    pad = WINDOW - len(pushed)
    for s, j in enumerate(joints):
        for t in range(len(pushed)):
            src = next(f for f in pushed[t:] if j in f)  # this frame's reading, else the next one's
            np.testing.assert_array_equal(pos[pad + t, s], src[j][0])
            np.testing.assert_array_equal(rot[pad + t, s], src[j][1])
        np.testing.assert_array_equal(pos[:pad, s], np.repeat(pos[pad : pad + 1, s], pad, axis=0))
