"""SparsePoser: network shapes, tail decoding, a tiny training run, save/load, the method."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine.config import load_config
from engine.errors import UserError
from engine.kinematics.features import encoder_input, pose_from_motion
from engine.kinematics.fk import fk
from engine.methods.sparseposer import SparsePoserMethod
from engine.models.loading import load_sparseposer
from engine.models.sparseposer import SparsePoser, SparsePoserConfig
from engine.tracking import simulate
from engine.training.sparseposer import SparsePoserTrainConfig, gen_loss, ik_losses, train_sparseposer
from tests.engine.test_training import tiny_data  # noqa: F401  (fixture: a tiny prepared folder)

TINY = [
    "window=16",
    "channels=[4, 6, 8]",
    "ik_hidden=16",
    "batch_size=4",
    "steps_per_epoch=3",
    "loss_frames=8",
    "ik_frames=2",
    "val_windows=8",
    "minutes=0.0",
]


def _tiny_model(window: int = 16) -> SparsePoser:
    torch.manual_seed(0)
    return SparsePoser(SparsePoserConfig(window=window, channels=(4, 6, 8), ik_hidden=16))


def _windows(motion, window: int):
    rot, disp = pose_from_motion(torch.as_tensor(motion.local_rot), torch.as_tensor(motion.root_pos))
    off = torch.as_tensor(motion.skeleton.offsets)
    dq = encoder_input(rot, disp, off.expand(rot.shape[0], -1, -1)).float()
    idx = torch.arange(0, len(motion) - window, 7)[:, None] + torch.arange(window)
    return dq[idx], off.float().expand(idx.shape[0], -1, -1)


def test_shapes_and_tail_decoding_match_the_full_decode(synthetic_motion):
    m = _tiny_model().eval()
    dq, off = _windows(synthetic_motion, 16)
    with torch.no_grad():
        full = m.generate(dq, off)
        tail = m.generate(dq, off, tail=8)
        local_ik, local_gen = m(dq, off, tail=8)
    assert full.shape == dq.shape and tail.shape == (dq.shape[0], 8, 22, 8)
    assert torch.allclose(full[:, -1], tail[:, -1], atol=1e-5)
    assert local_ik.shape == local_gen.shape == (dq.shape[0], 22, 4)
    assert torch.allclose(local_ik.norm(dim=-1), torch.ones(dq.shape[0], 22), atol=1e-5)
    # the IK's last layer starts at zero: before training it returns the generator's pose
    assert torch.allclose(local_ik, local_gen, atol=1e-6)


def test_generator_and_ik_losses_decrease_on_a_fixed_batch(synthetic_motion):
    m = _tiny_model()
    dq, off = _windows(synthetic_motion, 16)
    opt = torch.optim.Adam(m.parameters(), lr=3e-3)
    first_g = first_s = None
    for _ in range(40):
        lg, out = gen_loss(m, dq, off, 1.0, 8)
        ls, lr = ik_losses(m, out[:, -1].detach(), dq[:, -1], off)
        loss = lg + ls + 0.1 * lr
        opt.zero_grad()
        loss.backward()
        opt.step()
        first_g = first_g if first_g is not None else lg.item()
        first_s = first_s if first_s is not None else ls.item()
    assert lg.item() < 0.7 * first_g and ls.item() < 0.7 * first_s


def test_training_writes_weights_that_load_and_resume_continues(tiny_data, tmp_path):  # noqa: F811
    cfg = load_config(SparsePoserTrainConfig, None, TINY, epochs=1)
    meta = train_sparseposer(tiny_data, tmp_path / "run", cfg, progress=False)
    assert meta["finished"] and meta["epochs"] == 1 and np.isfinite(meta["val_pos_cm"])
    for name in ("sparseposer.pt", "best.pt", "last.pt", "losses.csv", "losses.png"):
        assert (tmp_path / "run" / name).is_file(), name
    model, loaded_meta = load_sparseposer(tmp_path / "run" / "sparseposer.pt")
    assert model.config.channels == (4, 6, 8) and loaded_meta["data_hash"]
    cfg2 = load_config(SparsePoserTrainConfig, None, TINY, epochs=2)
    meta2 = train_sparseposer(tiny_data, tmp_path / "run", cfg2, resume=True, progress=False)
    assert meta2["epochs"] == 2
    assert len((tmp_path / "run" / "losses.csv").read_text().strip().splitlines()) == 3  # header + 2 epochs


def test_budget_ends_the_run_cleanly(tiny_data, tmp_path):  # noqa: F811
    cfg = load_config(SparsePoserTrainConfig, None, TINY, epochs=50, minutes=1e-4)
    meta = train_sparseposer(tiny_data, tmp_path / "run", cfg, progress=False)
    assert meta["finished"] and meta["epochs"] == 1 and (tmp_path / "run" / "sparseposer.pt").is_file()
    assert meta["steps"] == 1, "the budget ends the first epoch after its first step (3 per epoch)"


def test_method_follows_the_hip_tracker_and_rejects_other_presets(synthetic_motion):
    method = SparsePoserMethod(model=_tiny_model())
    tracking = simulate(synthetic_motion.slice(0, 30), "6")
    method.reset(synthetic_motion.skeleton, tracking.fps)
    for i in range(len(tracking)):
        res = method.step(tracking.frame(i))
    true_pos, _ = synthetic_motion.fk()
    assert res.positions.shape == (22, 3) and np.isfinite(res.positions).all()
    np.testing.assert_allclose(res.root_pos, synthetic_motion.root_pos[29], atol=1e-9)
    np.testing.assert_allclose(res.positions[0], true_pos[29, 0], atol=1e-9)
    method.reset(synthetic_motion.skeleton)
    with pytest.raises(UserError, match="preset '6'"):
        method.step(simulate(synthetic_motion.slice(0, 5), "3-head-hands").frame(0))


def _reference_poses(model: SparsePoser, motion, frames: int) -> np.ndarray:
    """The method's pipeline written out plainly: the whole window (first frame
    repeated at the start), full decode, the four limb networks one by one."""
    feats = SparsePoserMethod(model=model)
    feats.reset(motion.skeleton, motion.fps)
    tracking = simulate(motion.slice(0, frames), "6")
    off = torch.as_tensor(np.asarray(motion.skeleton.offsets), dtype=torch.float32)[None]
    window, out = [], []
    for i in range(frames):
        window.append(feats.features(tracking.frame(i)))
        win = window[-model.config.window :]
        win = [win[0]] * (model.config.window - len(win)) + win
        with torch.no_grad():
            local_ik, _ = model(torch.as_tensor(np.stack(win), dtype=torch.float32)[None], off)
        out.append(local_ik[0].numpy())
    return np.stack(out)


def test_realtime_step_matches_the_plain_full_window_pipeline_with_the_shipped_weights():
    from engine.motion.retarget import load_motion
    from tests.engine.test_hardening_cli import EX

    model, _ = load_sparseposer()  # trained limb networks: the stacked IK really changes poses
    motion = load_motion(EX).slice(100, 190)
    ref = _reference_poses(model, motion, 90)
    method = SparsePoserMethod(model=model)
    assert method.context < model.config.window  # the step reads a shorter window
    method.reset(motion.skeleton, motion.fps)
    tracking = simulate(motion.slice(0, 90), "6")
    res = [method.step(tracking.frame(i)) for i in range(90)]
    got = np.stack([r.local_rot for r in res])
    np.testing.assert_allclose(got[:, 1:], ref[:, 1:], atol=1e-5)
    # the whole pose: the root from the hip tracker, the joints placed by FK
    hip = tracking.joints.index("root")
    ref[:, 0] = tracking.rotations[:, hip]
    want, _ = fk(ref, tracking.positions[:, hip], np.asarray(motion.skeleton.offsets))
    np.testing.assert_allclose(got[:, 0], ref[:, 0], atol=1e-9)
    np.testing.assert_allclose(np.stack([r.positions for r in res]), want, atol=1e-5)


def test_context_covers_the_receptive_field_of_the_last_frame():
    from engine.models.sparseposer_infer import context_frames, receptive_field

    m = SparsePoser(SparsePoserConfig(window=64)).eval()
    rf = receptive_field(m)
    assert 8 < rf < 64 and context_frames(m) == 32
    dq = torch.randn(2, 64, 22, 8)
    off = 0.1 * torch.randn(2, 22, 3)
    with torch.no_grad():
        full = m.generate(dq, off)[:, -1]
        short = m.generate(dq[:, -context_frames(m) :], off, tail=8)[:, -1]
        dq[:, : 64 - rf] += 5.0  # frames before the receptive field do not matter
        moved = m.generate(dq, off)[:, -1]
    torch.testing.assert_close(short, full, atol=1e-6, rtol=0)
    torch.testing.assert_close(moved, full, atol=1e-6, rtol=0)
    assert context_frames(_tiny_model(16)) == 16  # never more than the trained window
