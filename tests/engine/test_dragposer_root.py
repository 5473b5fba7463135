"""DragPoser's root rules (engine/methods/dragposer_root.py): the reference heading with
head and hands, and the facing it is bounded by (engine/solver/pose.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from engine.constraints import SensorConstraint
from engine.kinematics import quat_np as QN
from engine.methods.dragposer_root import reference_root
from engine.solver import OptimizerSettings, RootFrame
from engine.solver.pose import HEAD_LATERAL_M, HEADING_LIMIT_DEG, head_hands_facing


def _about_z(deg: float) -> np.ndarray:
    return np.array([math.cos(math.radians(deg) / 2), 0.0, 0.0, math.sin(math.radians(deg) / 2)])


def _yaw(q) -> float:
    f = QN.rotate(np.asarray(q, dtype=np.float64), np.array([0.0, -1.0, 0.0]))
    return math.degrees(math.atan2(f[0], -f[1]))


def _hands(yaw: float, apart: float) -> dict[str, np.ndarray]:
    """Wrists ``apart`` metres apart on the left-right line of a body facing ``yaw``."""
    left = np.array([math.cos(math.radians(yaw)), math.sin(math.radians(yaw)), 0.0])
    centre = np.array([0.3, -0.2, 1.1])
    return {"lwrist": centre + 0.5 * apart * left, "rwrist": centre - 0.5 * apart * left}


def _sensors(head_yaw: float, hands_yaw: float, apart: float = 0.6) -> dict[str, SensorConstraint]:
    out = {}
    head = SensorConstraint(name="sensor:upperneck", joint="upperneck", dof=6)
    # the head pitched down 30 deg as well: its heading is still head_yaw
    head.set_target(
        np.array([0.3, -0.2, 1.6]), QN.mul(_about_z(head_yaw), np.array([math.cos(0.26), math.sin(0.26), 0, 0]))
    )
    out["upperneck"] = head
    for j, p in _hands(hands_yaw, apart).items():
        c = SensorConstraint(name=f"sensor:{j}", joint=j, dof=6)
        c.set_target(p, _about_z(hands_yaw))
        out[j] = c
    for c in out.values():
        c.enabled = True
    return out


def _previous(yaw: float) -> RootFrame:
    return RootFrame(torch.as_tensor(_about_z(yaw), dtype=torch.float32), torch.tensor([0.3, -0.2, 0.95]))


@pytest.mark.parametrize("yaw", [-150.0, 0.0, 40.0, 120.0])
def test_head_hands_facing_reads_head_and_hands(yaw):
    head = QN.mul(_about_z(yaw), np.array([math.cos(0.3), math.sin(0.3), 0, 0]))  # pitched down
    assert _yaw(head_hands_facing(head, {})) == pytest.approx(yaw, abs=1e-6)  # the head alone
    assert _yaw(head_hands_facing(head, _hands(yaw, 0.7))) == pytest.approx(yaw, abs=1e-6)
    # hands turned 60 deg from the head, as far apart as the head counts: halfway
    assert _yaw(head_hands_facing(head, _hands(yaw + 60.0, HEAD_LATERAL_M))) == pytest.approx(yaw + 30.0, abs=1e-6)
    # hands held close together barely move it
    assert abs(_yaw(head_hands_facing(head, _hands(yaw + 60.0, 0.05))) - yaw) < 6.0


def test_reference_heading_stays_with_the_head_and_hands_facing():
    """005_05-like frame (docs/optimizer.md, "Stability with head and hands"): the head
    faces 120 deg, the hands' line 80, and the previous pelvis was left at 165 deg, 45 deg
    past the head. The head's 60-deg bound alone keeps that pelvis (it then ended about 97
    deg from the truth's heading); bounded by the head and hands' facing it comes back."""
    sensors = _sensors(head_yaw=120.0, hands_yaw=80.0)
    body = _yaw(
        head_hands_facing(sensors["upperneck"].rotation, {j: sensors[j].position for j in ("lwrist", "rwrist")})
    )
    assert 80.0 < body < 120.0
    old = reference_root(_previous(165.0), sensors, OptimizerSettings(hands_heading_limit=180.0), None, None)
    assert _yaw(old.rotation.double().numpy()) == pytest.approx(165.0, abs=1e-4)  # the head's bound alone
    s = OptimizerSettings()
    new = reference_root(_previous(165.0), sensors, s, None, None)
    assert abs(_yaw(new.rotation.double().numpy()) - body) == pytest.approx(s.hands_heading_limit, abs=1e-3)
    assert torch.equal(new.position, _previous(165.0).position)
    # within the bound nothing changes
    inside = reference_root(_previous(body - 0.5 * s.hands_heading_limit), sensors, s, None, None)
    assert _yaw(inside.rotation.double().numpy()) == pytest.approx(body - 0.5 * s.hands_heading_limit, abs=1e-4)


def test_reference_heading_without_hands_keeps_the_head_bound():
    sensors = _sensors(head_yaw=0.0, hands_yaw=0.0)
    for j in ("lwrist", "rwrist"):
        sensors[j].enabled = False
    s = OptimizerSettings(hands_heading_limit=HEADING_LIMIT_DEG + 30.0)  # looser than the head's
    out = reference_root(_previous(170.0), sensors, s, None, None)
    assert _yaw(out.rotation.double().numpy()) == pytest.approx(HEADING_LIMIT_DEG, abs=1e-3)
    # heading = previous: nothing bounds it
    free = reference_root(_previous(170.0), sensors, OptimizerSettings(heading="previous"), None, None)
    assert _yaw(free.rotation.double().numpy()) == pytest.approx(170.0, abs=1e-4)


def test_hands_heading_limit_is_validated():
    from engine.errors import UserError

    with pytest.raises(UserError, match="hands_heading_limit"):
        OptimizerSettings(hands_heading_limit=-1.0)
    with pytest.raises(UserError, match="hands_heading_limit"):
        OptimizerSettings(hands_heading_limit=200.0)


def _hip_3dof() -> dict[str, SensorConstraint]:
    hip = SensorConstraint(name="sensor:root", joint="root", dof=3)
    hip.set_target(np.array([0.3, -0.2, 0.95]), None)
    hip.enabled = True
    return {"root": hip}


def test_3dof_hip_heading_follows_the_body_facing_with_its_time_constant():
    """A hip tracker without rotation: the reference heading is bounded by the body facing
    and then turns towards it by one frame's share of ``body_heading_follow``."""
    from engine.methods.dragposer_root import root_override

    sensors = _hip_3dof()
    override = root_override(sensors)
    assert override is not None and override.rotation is None
    facing = _about_z(30.0)
    s = OptimizerSettings(lines_heading_follow=0.25, body_heading_follow=0.05)
    share = 1.0 - math.exp(-1.0 / (60.0 * 0.25))
    out = reference_root(_previous(50.0), sensors, s, override, facing, 60.0)
    assert _yaw(out.rotation.double().numpy()) == pytest.approx(50.0 - share * 20.0, abs=1e-3)
    # across the +-180 seam it turns the short way
    out = reference_root(_previous(170.0), sensors, s, override, _about_z(-170.0), 60.0)
    assert _yaw(out.rotation.double().numpy()) == pytest.approx(170.0 + share * 20.0, abs=1e-3)
    # a longer time constant or a higher frame rate turns less per frame
    slow = reference_root(_previous(50.0), sensors, OptimizerSettings(lines_heading_follow=1.0), override, facing, 60.0)
    fast_fps = reference_root(_previous(50.0), sensors, s, override, facing, 120.0)
    assert 0.0 < 50.0 - _yaw(slow.rotation.double().numpy()) < share * 20.0
    assert 0.0 < 50.0 - _yaw(fast_fps.rotation.double().numpy()) < share * 20.0
    # 0: bounded only (45 degrees), nothing within the bound moves
    off = OptimizerSettings(lines_heading_follow=0.0)
    assert _yaw(reference_root(_previous(50.0), sensors, off, override, facing, 60.0).rotation.double().numpy()) == (
        pytest.approx(50.0, abs=1e-4)
    )
    far = reference_root(_previous(120.0), sensors, off, override, facing, 60.0)
    assert _yaw(far.rotation.double().numpy()) == pytest.approx(75.0, abs=1e-3)
    # the bound first, then the follow
    far = reference_root(_previous(120.0), sensors, s, override, facing, 60.0)
    assert _yaw(far.rotation.double().numpy()) == pytest.approx(75.0 - share * 45.0, abs=1e-3)
    # the heading network's facing is followed with its own, shorter time constant
    learned = reference_root(_previous(50.0), sensors, s, override, facing, 60.0, learned=True)
    quick = 1.0 - math.exp(-1.0 / (60.0 * 0.05))
    assert _yaw(learned.rotation.double().numpy()) == pytest.approx(50.0 - quick * 20.0, abs=1e-3)
    # a 6-DoF hip's rotation is not touched here
    assert torch.equal(
        reference_root(_previous(50.0), sensors, s, None, facing, 60.0).rotation, _previous(50.0).rotation
    )


def test_follow_heading_keeps_pitch_and_roll():
    from engine.solver.pose import follow_fraction, follow_heading

    tilted = QN.mul(_about_z(40.0), np.array([math.cos(0.2), math.sin(0.2), 0.0, 0.0]))
    out = follow_heading(tilted, _about_z(0.0), 0.5)
    assert _yaw(out) == pytest.approx(20.0, abs=1e-6)
    # the same tilt about the body's own axis: only a turn about the world vertical was added
    assert QN.mul(_about_z(-20.0), out) == pytest.approx(QN.mul(_about_z(-40.0), tilted), abs=1e-9)
    assert follow_fraction(0.0, 60.0) == 0.0
    assert follow_fraction(1.0 / 60.0, 60.0) == pytest.approx(1.0 - math.exp(-1.0))
    # a target looking straight down has no heading: unchanged
    down = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0])
    assert np.array_equal(follow_heading(tilted, down, 0.5), tilted)


def test_ik_and_dragposer_read_the_body_facing_alike():
    """The IK baseline and DragPoser's 3-DoF hip rule read one facing (feet and hands alike)."""
    from engine.solver.pose import LATERAL_PAIRS, body_facing

    pts = {"lankle": np.array([0.1, 0.0, 0.0]), "rankle": np.array([-0.1, 0.0, 0.0])}
    pts |= {"lwrist": np.array([0.0, 0.3, 1.0]), "rwrist": np.array([0.0, -0.3, 1.0])}
    # feet 0.2 m along +X, hands 0.6 m along +Y: the summed left axis points 71.6 deg from +X
    assert {w for *_, w in LATERAL_PAIRS} == {1.0}
    assert _yaw(body_facing(pts)) == pytest.approx(math.degrees(math.atan2(0.6, 0.2)), abs=1e-9)
