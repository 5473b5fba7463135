"""DragPoserMethod end to end with stand-in models, its editing API, scenes, registry."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import LookAtConstraint, PinConstraint
from engine.errors import UserError
from engine.methods.dragposer import DragPoserMethod
from engine.motion.clip import Motion
from engine.scene import load_scene, save_scene
from engine.sensors import Sensor, SensorFrame
from engine.solver import OptimizerSettings
from engine.tracking import simulate
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder


@pytest.fixture
def clip() -> Motion:
    f = 24
    t = np.arange(f) / 60.0
    rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (f, 22, 1))
    return Motion(rot, np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))


def make(**kw) -> DragPoserMethod:
    torch.manual_seed(0)
    kw.setdefault("iterations", 3)
    kw.setdefault("max_iterations", 20)
    return DragPoserMethod(MLPDecoder(), CountingPredictor(), **kw)


def test_runs_a_clip_and_fills_every_frame_result(clip):
    m = make()
    tr = simulate(clip, "6")
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(len(clip))]
    for r in out:
        assert r.local_rot.shape == (22, 4) and r.positions.shape == (22, 3) and r.latent.shape == (24,)
        assert np.isfinite(r.positions).all() and r.ms > 0 and not r.warnings
        assert len(r.losses) == r.iterations + 1 and "sensor:lwrist" in r.losses[0]
    assert [r.iterations for r in out[1:]] == [3] * (len(clip) - 1)
    # the hip sensor dictates the root
    assert np.allclose(out[5].root_pos, tr.positions[5, tr.joints.index("root")], atol=1e-5)
    assert np.allclose(out[5].positions[0], out[5].root_pos)
    assert m.predictor.calls and "temporal_prior" in out[-1].losses[-1]


def test_nan_reading_warns_and_the_next_frame_recovers(clip):
    m = make()
    tr = simulate(clip, "6")
    m.reset(clip.skeleton)
    for i in range(4):
        m.step(tr.frame(i))
    bad = tr.frame(4)
    readings = dict(bad.readings)
    readings["lwrist"] = Sensor("lwrist", np.full(3, np.nan), np.array([1.0, 0, 0, 0]))
    readings["root"] = Sensor("root", np.array([np.inf, 0, 1.0]), np.array([1.0, 0, 0, 0]))
    r = m.step(SensorFrame(4, readings))
    assert len(r.warnings) == 2 and np.isfinite(r.positions).all() and np.isfinite(r.latent).all()
    nxt = m.step(tr.frame(5))
    assert not nxt.warnings and np.isfinite(nxt.positions).all()
    assert np.allclose(nxt.root_pos, tr.positions[5, 0], atol=1e-5)


def test_disconnected_sensors_are_disabled_and_the_root_is_integrated(clip):
    m = make()
    tr = simulate(clip, "6")
    tr.connected[:, tr.joints.index("root")] = False
    m.reset(clip.skeleton)
    r = [m.step(tr.frame(i)) for i in range(6)]
    assert not m.sensors["root"].enabled and m.sensors["lwrist"].enabled
    assert "sensor:root" not in r[-1].losses[0] or r[-1].losses[0]["sensor:root"] == 0
    assert np.isfinite(r[-1].root_pos).all()


def test_without_hip_the_head_tracker_places_the_body_unless_told_otherwise(clip):
    tr = simulate(clip, "3-head-hands")
    head = tr.joints.index("upperneck")
    anchored, free = make(), make(root_anchor="none")
    for m in (anchored, free):
        m.reset(clip.skeleton)
    ra = [anchored.step(tr.frame(i)) for i in range(len(clip))]
    rf = [free.step(tr.frame(i)) for i in range(len(clip))]
    target = tr.positions[:, head]
    err_a = np.linalg.norm(np.array([r.positions[sk.JOINT_INDEX["upperneck"]] for r in ra]) - target, axis=-1)
    err_f = np.linalg.norm(np.array([r.positions[sk.JOINT_INDEX["upperneck"]] for r in rf]) - target, axis=-1)
    assert err_a.max() < 1e-4, "anchored: the head sits on its tracker every frame"
    assert err_f.max() > 10 * err_a.max(), "integrated: the head only approaches its tracker"


def test_constraint_editing_between_frames(clip):
    m = make()
    tr = simulate(clip, "4")
    m.reset(clip.skeleton)
    m.add_constraint(LookAtConstraint(name="look"))
    with pytest.raises(UserError, match="look"):
        m.add_constraint(LookAtConstraint(name="look"))
    m.step(tr.frame(0))
    m.set_weight("look", 3.0)
    m.set_enabled("look", False)
    assert m.get_constraint("look").weight == 3.0
    assert "look" not in m.step(tr.frame(1)).losses[0]
    m.set_enabled("look", True)
    assert "look" in m.step(tr.frame(2)).losses[0]
    m.remove_constraint("look")
    with pytest.raises(UserError):
        m.get_constraint("look")
    m.set_constraints([PinConstraint(name="p1"), PinConstraint(name="p2", joint="rankle")])
    assert {"p1", "p2"} <= set(m.step(tr.frame(3)).losses[0])
    m.set_sensor_weight("lwrist", 0.0)
    assert "sensor:lwrist" not in m.step(tr.frame(4)).losses[0]


def test_published_constraints_are_never_changed_and_an_unset_pin_keeps_its_capture(clip):
    """The studio hands its constraint objects to the engine thread: solving and editing
    work on copies. An unset pin holds the first solved position from then on, also
    when the same list is sent again."""
    m = make()
    tr = simulate(clip, "4")
    m.reset(clip.skeleton)
    look, pin = LookAtConstraint(name="look"), PinConstraint(name="pin", joint="rankle")
    published = [look, pin]
    m.set_constraints(published)
    first = m.step(tr.frame(0)).positions[sk.JOINT_INDEX["rankle"]]
    m.step(tr.frame(1))
    m.set_weight("look", 3.0)
    m.set_enabled("look", False)
    assert look.weight == 1.0 and look.enabled and not np.isfinite(pin.position).any()
    held = m.get_constraint("pin")
    assert held is not pin and np.allclose(held.position, first)
    m.set_constraints(published)  # e.g. the studio edited another constraint
    m.step(tr.frame(2))
    assert np.allclose(m.get_constraint("pin").position, first)
    m.set_constraints([PinConstraint(name="pin", joint="rankle")])  # a new pin captures afresh
    m.step(tr.frame(3))
    assert not np.allclose(m.get_constraint("pin").position, first)


def test_settings_apply_from_the_next_frame_and_unknown_names_fail(clip):
    m = make()
    tr = simulate(clip, "6")
    m.reset(clip.skeleton)
    m.step(tr.frame(0))
    m.configure(iterations=5)
    assert m.step(tr.frame(1)).iterations == 5
    m.configure(mode="offline", max_iterations=2)
    assert m.step(tr.frame(2)).iterations <= 2
    with pytest.raises(UserError, match="warp"):
        m.configure(warp=9)
    with pytest.raises(UserError, match="lr"):
        m.configure(lr=-1)


def test_decode_latent_gives_world_positions():
    m = make()
    assert m.decode_latent(np.zeros(24)).shape == (22, 3)


def test_scene_round_trip_and_errors(tmp_path):
    path = tmp_path / "scene.json"
    cons = [LookAtConstraint(name="look", target=np.array([1.0, -2.0, 1.5])), PinConstraint(name="pin")]
    save_scene(path, cons, OptimizerSettings(mode="offline", lr=0.02))
    back, settings = load_scene(path)
    assert [c.to_dict() for c in back] == [c.to_dict() for c in cons]
    assert settings.mode == "offline" and settings.lr == 0.02
    assert not list(tmp_path.glob(".*tmp"))

    def fails(doc, match):
        path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
        with pytest.raises(UserError, match=match):
            load_scene(path)

    fails("{bad", r"scene.json:1")
    fails({"settings": {"speed": 2}}, "speed")
    fails({"settings": {"lr": "fast"}}, "lr")
    fails({"constraints": [{"kind": "pin", "joint": "tail"}]}, r"constraints\[0\].*joint")
    fails({"constraints": [{"kind": "pin", "name": "a"}, {"kind": "pin", "name": "a"}]}, "duplicate")
    with pytest.raises(UserError, match="cannot read"):
        load_scene(tmp_path / "missing.json")


def test_registry_knows_dragposer():
    from engine.methods import available_methods

    assert "dragposer" in available_methods()


def test_runs_with_the_real_model_classes(clip):
    """Untrained PoseVAE and TemporalPredictor: the interfaces fit (weights do not matter)."""
    vae = pytest.importorskip("engine.models.vae")
    pred = pytest.importorskip("engine.models.predictor")
    torch.manual_seed(0)
    m = DragPoserMethod(vae.PoseVAE(), pred.TemporalPredictor(), iterations=2, max_iterations=5)
    tr = simulate(clip, "4")
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(10)]
    assert all(np.isfinite(r.positions).all() and not r.warnings for r in out)
    assert "temporal_prior" in out[-1].losses[0]


def test_smoothing_extrapolates_only_between_realtime_frames(clip):
    """Frame 0 is solved offline, so the step from it to frame 1 is no velocity: the smooth
    term starts at frame 3, from the two frames before it."""
    m = make(smooth_weight=5.0)
    tr = simulate(clip, "3-head-hands")
    m.reset(clip.skeleton)
    seen = []
    solve = m.optimizer.solve

    def spy(start, terms, ctx, settings=None):
        seen.append((m.smooth.active, m.smooth.target.copy()))
        return solve(start, terms, ctx, settings)

    m.optimizer.solve = spy
    poses = [m.step(tr.frame(i)).positions for i in range(5)]
    assert [a for a, _ in seen] == [False, False, False, True, True]
    np.testing.assert_allclose(seen[3][1], 2.0 * poses[2] - poses[1], atol=1e-6)
    np.testing.assert_allclose(seen[4][1], 2.0 * poses[3] - poses[2], atol=1e-6)
