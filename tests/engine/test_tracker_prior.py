"""The tracker prior (engine/solver/tracker_prior.py): features, the bank lookup, its file,
and DragPoser taking its latent as the temporal prior's for sparse sets."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods.dragposer import DragPoserMethod
from engine.solver.tracker_history import TrackerHistory
from engine.solver.tracker_prior import ANCHORS, BANK_JOINTS, LAG, PoseBank, default_bank, features
from engine.tracking import simulate
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder


def _yaw(deg: float) -> np.ndarray:
    return np.array([np.cos(np.radians(deg) / 2), 0.0, 0.0, np.sin(np.radians(deg) / 2)])


def _random_readings(rng, f: int, s: int):
    pos = rng.normal(size=(f, s, 3))
    rot = Q.normalize(rng.normal(size=(f, s, 4)))
    return pos, rot


def test_features_ignore_where_the_wearer_stands_and_faces_but_see_the_pose():
    rng = np.random.default_rng(0)
    pos, rot = _random_readings(rng, 5, 4)
    prev = pos[:, 0] - rng.normal(scale=0.05, size=(5, 3))
    x = features(pos, rot, 0, prev)
    assert x.shape == (5, 3 * 3 + 1 + 6 * 4 + 3)
    turn = np.broadcast_to(_yaw(73.0), (5, 4, 4))
    shift = np.array([2.0, -1.0, 0.0])  # horizontal only: the anchor's height is a feature
    moved = features(Q.rotate(turn, pos) + shift, Q.mul(turn, rot), 0, Q.rotate(turn[:, 0], prev) + shift)
    np.testing.assert_allclose(moved, x, atol=1e-9)
    lifted = pos.copy()
    lifted[:, 2] += 0.1  # a hand moved: the features change
    assert np.abs(features(lifted, rot, 0, prev) - x).max() > 0.05


def _bank(rng, n: int = 200, k: int = 3) -> PoseBank:
    pos, rot = _random_readings(rng, n, len(BANK_JOINTS))
    prev = pos[:, [BANK_JOINTS.index(a) for a in ANCHORS]] - 0.01
    return PoseBank(pos, rot, prev, rng.normal(size=(n, 24)).astype(np.float32), "abc", k)


def test_the_latent_is_the_mean_latent_of_the_nearest_training_frames():
    rng = np.random.default_rng(1)
    bank = _bank(rng)
    joints = ("root", "lwrist", "rwrist")
    cols = [BANK_JOINTS.index(j) for j in joints]
    i = 57  # readings of training frame 57 (its anchor LAG frames back as the bank has it)
    pos = np.repeat(bank.positions[i : i + 1, cols], LAG + 1, 0)
    rot = np.repeat(bank.rotations[i : i + 1, cols], LAG + 1, 0)
    pos[0, 0] = bank.prev_anchor[i, 0]
    z = bank.latent(joints, pos, rot)
    # brute force, independently: standardised distances over the whole bank
    x = features(bank.positions[:, cols], bank.rotations[:, cols], 0, bank.prev_anchor[:, 0])
    mu, sd = x.mean(0), x.std(0) + 1e-6
    d = (((x - mu) / sd - (x[i] - mu) / sd) ** 2).sum(1)
    near = np.argsort(d)[:3]
    assert near[0] == i
    np.testing.assert_allclose(z.numpy(), bank.latents[near].mean(0), atol=1e-5)
    # the lookup's distance: the neighbours' mean standardised distance to the readings
    z2, far = bank.lookup(joints, pos, rot)
    assert torch.equal(z2, z)
    assert far == pytest.approx(np.sqrt(d[near]).mean(), rel=1e-5) and far > 0.0
    pos[:, 1] += 5.0  # a left hand where no training frame had it is farther from the bank
    assert bank.lookup(joints, pos, rot)[1] > 2.0 * far


def test_a_bank_survives_its_file_and_a_broken_file_is_a_user_error(tmp_path):
    bank = _bank(np.random.default_rng(2))
    bank.save(tmp_path / "b.npz")
    back = PoseBank.load(tmp_path / "b.npz")
    assert back.vae_sha256 == "abc" and back.k == 3 and len(back) == len(bank)
    np.testing.assert_allclose(back.latents, bank.latents, atol=2e-3)  # stored as float16
    (tmp_path / "bad.npz").write_bytes(b"not a bank")
    with pytest.raises(UserError, match="bad.npz"):
        PoseBank.load(tmp_path / "bad.npz")


def test_history_keeps_joints_connected_throughout_and_needs_an_anchor():
    h = TrackerHistory()
    r = (np.zeros(3), np.array([1.0, 0, 0, 0]))
    assert h.arrays() is None
    h.push({"lwrist": r, "rwrist": r, "lelbow": r})
    assert h.arrays() is None  # no hips or head
    h.push({"root": r, "lwrist": r, "rwrist": r})
    assert h.arrays() is None  # the hips were not there the frame before
    for _ in range(LAG + 1):
        h.push({"root": r, "lwrist": r, "rwrist": r})
    joints, pos, rot = h.arrays()
    assert joints == ("root", "lwrist", "rwrist") and pos.shape == (LAG + 1, 3, 3) and rot.shape == (LAG + 1, 3, 4)


def test_dragposer_takes_the_bank_latent_when_6dof_trackers_give_one_and_else_runs_the_predictor(clip):
    rng = np.random.default_rng(3)
    bank = _bank(rng, k=1)
    bank.latents[:] = 0.5  # every neighbour answers 0.5 in every dimension
    bank._latents = torch.as_tensor(bank.latents)
    seen = []

    def run(preset: str, **kw):
        torch.manual_seed(0)
        m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=2, bank=bank, **kw)
        tr = simulate(clip, preset)
        m.reset(clip.skeleton)
        solve = m.optimizer.solve

        def spy(start, terms, ctx, settings=None):
            pred = ctx.prediction
            seen.append((m.prior.weight, None if pred is None else float(pred.mean())))
            return solve(start, terms, ctx, settings)

        m.optimizer.solve = spy
        for i in range(6):
            m.step(tr.frame(i))
            m.between_frames()
        return m

    m = run("4")
    assert seen[-1] == (1.0, pytest.approx(0.5))  # profile hip: trackers, weight tracker_prior_weight
    assert m.predictor.calls == []  # its latents would be thrown away: it does not run
    seen.clear()
    m = run("4", prior="predictor")  # explicitly the paper's
    assert seen[-1][0] == 0.01 and seen[-1][1] != pytest.approx(0.5)
    assert m.predictor.calls
    seen.clear()
    m = run("6")  # full profile: trackers too, lighter
    assert seen[-1] == (0.05, pytest.approx(0.5)) and m.predictor.calls == []
    seen.clear()
    m = run("6x3dof")  # no 6-DoF tracker to look the bank up with: the predictor
    assert seen[-1][0] == 0.03 and seen[-1][1] != pytest.approx(0.5)
    assert m.predictor.calls


@pytest.fixture
def clip():
    from engine.motion.clip import Motion

    f = 24
    t = np.arange(f) / 60.0
    rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (f, 22, 1))
    return Motion(rot, np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))


def test_the_neighbour_count_can_be_chosen_per_lookup():
    rng = np.random.default_rng(4)
    bank = _bank(rng, k=3)
    joints = ("upperneck", "lwrist")
    cols = [BANK_JOINTS.index(j) for j in joints]
    pos = np.repeat(bank.positions[10:11, cols], LAG + 1, 0)
    rot = np.repeat(bank.rotations[10:11, cols], LAG + 1, 0)
    one, all_ = bank.latent(joints, pos, rot, k=1), bank.latent(joints, pos, rot, k=10_000)
    assert torch.allclose(all_, torch.as_tensor(bank.latents).mean(0), atol=1e-5)  # capped at the bank's size
    assert not torch.allclose(one, bank.latent(joints, pos, rot))  # 0 / default: the bank's k = 3


@pytest.mark.parametrize(
    "joints",
    [
        ("root", "upperneck", "lwrist", "rwrist"),
        ("upperneck", "lwrist", "rankle"),
        ("rwrist", "root", "lankle"),
        BANK_JOINTS,
    ],
)
def test_a_combination_looks_up_what_a_table_of_its_own_features_finds(joints):
    rng = np.random.default_rng(5)
    bank = _bank(rng, n=300, k=4)
    cols = [BANK_JOINTS.index(j) for j in joints]
    a = next(joints.index(x) for x in ANCHORS if x in joints)
    prev = bank.prev_anchor[:, ANCHORS.index(joints[a])]
    x = features(bank.positions[:, cols], bank.rotations[:, cols], a, prev)
    mu, sd = x.mean(0), x.std(0) + 1e-6
    for i in (3, 150, 299):
        pos = np.repeat(bank.positions[i : i + 1, cols], LAG + 1, 0)
        pos += rng.normal(scale=0.05, size=pos.shape)
        rot = np.repeat(bank.rotations[i : i + 1, cols], LAG + 1, 0)
        q = features(pos[-1:], rot[-1:], a, pos[:1, a])[0]
        near = np.argsort((((x - mu) / sd - (q - mu) / sd) ** 2).sum(1))[:4]
        np.testing.assert_allclose(bank.latent(joints, pos, rot).numpy(), bank.latents[near].mean(0), atol=1e-6)


def test_the_first_frame_of_every_preset_finds_its_bank_index_built_when_the_models_load():
    from engine.methods import get_method
    from engine.motion.clip import Motion
    from engine.tracking.presets import PRESET_SENSORS

    m = get_method("dragposer")
    if m.bank is None:
        pytest.skip("the shipped pose bank is not installed")
    built = m.bank.index_builds
    assert built >= len(ANCHORS)  # both anchor tables were built at load
    f = 8
    t = np.arange(f) / 60.0
    clip = Motion(np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (f, 22, 1)), np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))
    looked_up = []
    lookup = m.bank.lookup
    m.bank.lookup = lambda *a, **kw: looked_up.append(a[0]) or lookup(*a, **kw)
    for preset in PRESET_SENSORS:
        m.reset(clip.skeleton)
        m.step(simulate(clip, preset).frame(0))
    assert len(looked_up) == len([p for p, s in PRESET_SENSORS.items() if sum(x.dof == 6 for x in s) >= 2])
    assert m.bank.index_builds == built  # no frame built or derived an index


def _windows(bank: PoseBank, joints: tuple[str, ...], starts: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
    """Each start's ``LAG + 1``-frame window of the bank's own readings of ``joints``, moved a little."""
    cols = [BANK_JOINTS.index(j) for j in joints]
    pos = np.stack([bank.positions[i : i + LAG + 1, cols] for i in starts])
    pos += rng.normal(scale=0.03, size=pos.shape)
    return pos, np.stack([bank.rotations[i : i + LAG + 1, cols] for i in starts])


def test_many_frames_at_once_find_what_one_frame_at_a_time_finds():
    rng = np.random.default_rng(6)
    bank = _bank(rng, n=400, k=5)
    joints = ("root", "upperneck", "lwrist", "rwrist")
    pos, rot = _windows(bank, joints, rng.integers(0, 390, 70), rng)
    many = bank.latent_frames(joints, pos, rot)
    one = torch.stack([bank.latent(joints, p, r) for p, r in zip(pos, rot)])
    assert many.shape == (70, 24) and torch.equal(many, one)
    assert bank.latent_frames(joints, pos[:0], rot[:0]).shape == (0, 24)


@pytest.mark.parametrize(
    "joints", [BANK_JOINTS, ("root", "upperneck", "lwrist", "rwrist"), ("upperneck", "lwrist", "rwrist")]
)
def test_the_shipped_bank_finds_for_a_run_of_frames_the_bits_one_frame_at_a_time_finds(joints):
    bank = default_bank()
    if bank is None:
        pytest.skip("the shipped pose bank is not installed")
    rng = np.random.default_rng(7)
    # a run of consecutive frames (each bounded by the last one's neighbours), then a jump
    starts = np.concatenate((np.arange(3000, 3060), rng.integers(0, len(bank) - LAG - 1, 10)))
    pos, rot = _windows(bank, joints, starts, rng)
    bank.latent(joints, pos[-1], rot[-1])
    hint = bank._hints[tuple(joints)]
    many = bank.latent_frames(joints, pos, rot, k=6)
    assert bank._hints[tuple(joints)] is hint  # the run left the realtime lookup's hint alone
    one = torch.stack([bank.latent(joints, p, r, k=6) for p, r in zip(pos, rot)])
    assert torch.equal(many, one)


def test_a_bank_left_for_later_builds_the_first_frames_lookup_then_the_rest_after_it(clip):
    """``prepare_bank_later`` (the studio's DragPoser): the first frame builds only its
    anchor's table and its combination, ``between_frames`` the rest once, and the priors
    equal those of a bank prepared before the first frame."""
    from engine.methods.dragposer import preset_combinations

    combos = preset_combinations()
    later, ahead = _bank(np.random.default_rng(5), k=2), _bank(np.random.default_rng(5), k=2)
    ahead.prepare(combos)
    priors = {}
    for name, bank in (("later", later), ("ahead", ahead)):
        torch.manual_seed(0)
        m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=2, bank=bank)
        if bank is later:
            m.prepare_bank_later(combos)
        lookup, seen = bank.lookup, priors.setdefault(name, [])
        bank.lookup = lambda *a, _lookup=lookup, _seen=seen, **kw: (
            _seen.append(_lookup(*a, **kw)[0]) or (_seen[-1], 0.0)
        )
        tr = simulate(clip, "6")
        m.reset(clip.skeleton)
        for i in range(3):
            m.step(tr.frame(i))
            if bank is later and i == 0:
                assert later.index_builds == 2  # the hips' table and the six trackers' combination
            m.between_frames()
            if bank is later and i == 0:
                assert later.index_builds == len(ANCHORS) + len(combos)
    assert later.index_builds == ahead.index_builds
    assert len(priors["later"]) == 3 and all(torch.equal(a, b) for a, b in zip(priors["later"], priors["ahead"]))


def test_the_studio_builds_dragposer_with_the_bank_left_for_after_its_first_frame(monkeypatch):
    import engine.studio.method_edits as edits

    asked = []
    monkeypatch.setattr(edits, "get_method", lambda name, **kw: asked.append((name, kw)))
    edits.make_method("dragposer")
    edits.make_method("ik")
    assert asked == [("dragposer", {"prepare_bank": False}), ("ik", {})]


def test_a_copy_of_the_shipped_vae_keeps_the_bank_and_another_vae_goes_without(tmp_path):
    """A predictor retrained on the shipped VAE is evaluated with ``--vae`` pointing at that
    VAE: the bank holds its latents, so the prior must stay; any other VAE's latents differ."""
    import shutil

    from engine.methods.dragposer import create
    from engine.models.loading import DEFAULT_PREDICTOR, DEFAULT_VAE

    copy = tmp_path / "vae.pt"
    shutil.copyfile(DEFAULT_VAE, copy)
    assert default_bank(copy) is not None
    other = tmp_path / "other.pt"
    data = bytearray(DEFAULT_VAE.read_bytes())
    data[-1] ^= 1
    other.write_bytes(bytes(data))
    assert default_bank(other) is None
    method = create(vae_path=copy, predictor_path=DEFAULT_PREDICTOR, prepare_bank=False)
    assert method.bank is not None
