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
