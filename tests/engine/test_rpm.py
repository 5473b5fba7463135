"""RPM: PCAF, heading frames, tracking-loss augmentation, a tiny training run, the method."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.config import load_config
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods.rpm import RPMMethod
from engine.models.loading import load_rpm
from engine.models.rpm import POSE_DIM, RPM, RPMConfig, to_frame, yaw_matrix
from engine.tracking import simulate
from engine.training.data import load_split
from engine.training.rpm import Frames, RPMTrainConfig, free_run, gap_flags, pose_losses, train_rpm
from tests.engine.test_training import tiny_data  # noqa: F401  (fixture: a tiny prepared folder)

TINY = [
    "past_inputs=3",
    "past_poses=3",
    "window=4",
    "hidden=32",
    "blocks=1",
    "free_run=4",
    "batch_size=4",
    "steps_per_epoch=3",
    "val_segments=2",
    "val_frames=70",
    "minutes=0.0",
]


def _tiny_model() -> RPM:
    torch.manual_seed(0)
    return RPM(RPMConfig(past_inputs=3, past_poses=3, window=4, hidden=32, blocks=1))


def test_pcaf_bounds_the_correction_by_the_uncertainty():
    m = _tiny_model()
    prev = torch.randn(2, 4, POSE_DIM)
    assert torch.equal(m.pcaf(prev, prev), prev)
    step = m.pcaf(prev, prev + 100.0) - prev
    assert torch.allclose(step, m.u[None, :, None].expand_as(step), atol=1e-5)
    # the paper's cosine (supp. Eq. B): small near the present, 1 at the far end
    assert m.u[-1] == pytest.approx(1.0) and bool((m.u[1:] > m.u[:-1]).all())
    assert 0.0 < float(m.u[0]) < 0.2


def test_weights_files_with_the_stored_inverted_uncertainty_load_the_papers():
    m = _tiny_model()
    sd = m.state_dict()
    assert "u" not in sd  # structure, rebuilt from the config
    sd["u"] = torch.flip(m.u, [0])  # what those files hold
    other = _tiny_model()
    other.load_state_dict(sd)
    assert torch.equal(other.u, m.u)


def test_yaw_matrix_agrees_with_heading_and_frames_round_trip():
    rng = np.random.default_rng(0)
    q = Q.normalize(rng.normal(size=(5, 4)))
    h = yaw_matrix(torch.as_tensor(q, dtype=torch.float32))
    expected = Q.to_matrix(Q.heading(q))
    np.testing.assert_allclose(h.numpy(), expected, atol=1e-5)
    pose = torch.randn(5, 2, 22, 3, 2)
    back = to_frame(to_frame(pose, h), h, inverse=False)
    assert torch.allclose(back, pose, atol=1e-5)


def test_fk_root_space_places_each_joint_from_its_parent_with_the_root_at_the_origin():
    import pymotion.rotations.ortho6d_torch as o6

    from engine.models.rpm import fk_root_space

    g = torch.Generator().manual_seed(0)
    q = torch.nn.functional.normalize(torch.randn(2, 3, sk.NUM_JOINTS, 4, generator=g, dtype=torch.float64), dim=-1)
    mats = Q.to_matrix(q)
    pose6 = mats[..., :2]  # the 6D form: the matrix's first two columns
    offsets = torch.randn(2, 1, sk.NUM_JOINTS, 3, generator=g, dtype=torch.float64)
    assert torch.allclose(o6.to_matrix(pose6), mats)
    world, pos = [mats[..., 0, :, :]], [torch.zeros(2, 3, 3, dtype=torch.float64)]
    for j in range(1, sk.NUM_JOINTS):  # joint by joint, every parent before its child
        p = sk.PARENTS[j]
        world.append(world[p] @ mats[..., j, :, :])
        pos.append(pos[p] + (world[p] @ offsets[..., j, :, None])[..., 0])
    assert torch.allclose(fk_root_space(pose6, offsets), torch.stack(pos, dim=-2), atol=1e-12)


def test_gap_flags_only_drop_hands_for_half_to_two_seconds():
    flags = gap_flags(200, 300, 1.0, torch.Generator().manual_seed(0))
    assert flags[:, :, 0].all()
    lost = (~flags[:, :, 1:]).sum(1)
    assert lost.max() <= 120 and (lost > 0).float().mean() > 0.5


def test_losses_decrease_on_a_fixed_batch(tiny_data):  # noqa: F811
    cfg = load_config(RPMTrainConfig, None, TINY)
    fr = Frames(load_split(tiny_data, "train"))
    m = _tiny_model()
    t = fr.anchors(3, 8)[:8]
    flags = torch.ones(len(t), 8, 3, dtype=torch.bool)
    cold = torch.zeros(len(t), dtype=torch.bool)
    opt = torch.optim.Adam(m.parameters(), lr=3e-3)
    first = None
    for _ in range(30):
        P, tau = free_run(m, fr, t, 2, flags, cold, cfg)
        loss = sum(pose_losses(P, fr.pose6[tau[:, None] + torch.arange(4)], fr.h[tau], fr.offsets[tau]).values())
        opt.zero_grad()
        loss.backward()
        opt.step()
        first = first if first is not None else loss.item()
    assert loss.item() < 0.7 * first


def test_training_writes_weights_that_load(tiny_data, tmp_path):  # noqa: F811
    cfg = load_config(RPMTrainConfig, None, TINY, epochs=2)
    meta = train_rpm(tiny_data, tmp_path / "run", cfg, progress=False)
    assert meta["finished"] and meta["epochs"] == 2 and np.isfinite(meta["val_pos_cm"])
    model, _ = load_rpm(tmp_path / "run" / "rpm.pt")
    assert model.config.window == 4 and float(model.pose_std.min()) > 0
    frozen = dict(epochs=1, lr=0.0, lr_final=0.0, weight_decay=0.0, seed=7)
    train_rpm(
        tiny_data,
        tmp_path / "ft",
        load_config(RPMTrainConfig, None, TINY, init=str(tmp_path / "run" / "rpm.pt"), **frozen),
        progress=False,
    )
    tuned, _ = load_rpm(tmp_path / "ft" / "rpm.pt")
    a, b = model.state_dict(), tuned.state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a), "init with no learning gives the init weights back"
    with pytest.raises(UserError, match="init .*architecture"):
        train_rpm(
            tiny_data,
            tmp_path / "x",
            load_config(RPMTrainConfig, None, TINY, init=str(tmp_path / "run" / "rpm.pt"), hidden=8, **frozen),
            progress=False,
        )


def test_method_puts_the_head_on_its_tracker_through_a_gap(synthetic_motion):
    method = RPMMethod(model=_tiny_model())
    tracking = simulate(synthetic_motion, "3-head-hands")
    tracking.connected[40:70, 1] = False  # left hand lost for half a second
    method.reset(synthetic_motion.skeleton, tracking.fps)
    head = sk.JOINT_INDEX["upperneck"]
    for i in range(80):
        res = method.step(tracking.frame(i))
        assert np.isfinite(res.positions).all()
        np.testing.assert_allclose(res.positions[head], tracking.positions[i, 0], atol=1e-5)
    method.reset(synthetic_motion.skeleton)
    with pytest.raises(UserError, match="3-head-hands"):
        method.step(simulate(synthetic_motion.slice(0, 5), "6").frame(0))
