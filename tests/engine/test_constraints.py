"""Constraint kinds: losses fall towards satisfaction, hand-built states, JSON, errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import (
    REGISTRY,
    BalanceConstraint,
    BoundsConstraint,
    DistanceConstraint,
    EndEffectorConstraint,
    FloorConstraint,
    LookAtConstraint,
    PinConstraint,
    SensorConstraint,
    TemporalPriorConstraint,
    from_dict,
)
from engine.errors import UserError
from engine.gizmos import Gizmo, LineGizmo, PointGizmo, gizmo_types
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.solver import PoseState

J = sk.JOINT_INDEX

REST = sk.Skeleton.canonical().rest_positions()
STAND = np.array([0.0, 0.0, 1.0])  # root height with the toes just above the floor


def state_of(local: torch.Tensor, root: torch.Tensor, latent=None, prediction=None, previous=None) -> PoseState:
    pos, rot = fk(Q.normalize(local), root, sk.REST_OFFSETS)
    lat = torch.zeros(4, dtype=torch.float64) if latent is None else latent
    return PoseState(pos, rot, local, lat, previous, 0, prediction)


def rest_state(root=STAND, **kw) -> PoseState:
    return state_of(
        Q.identity((22,), like=torch.zeros(1, dtype=torch.float64)), torch.as_tensor(root, dtype=torch.float64), **kw
    )


def descend(constraint, steps: int = 40, lr: float = 0.02, previous=None):
    """Adam on local rotations and root position; returns the loss before and after."""
    torch.manual_seed(0)
    local = (
        Q.identity((22,), like=torch.zeros(1, dtype=torch.float64)) + 0.05 * torch.randn(22, 4, dtype=torch.float64)
    ).requires_grad_(True)
    root = torch.tensor(STAND, dtype=torch.float64, requires_grad=True)
    opt = torch.optim.Adam([local, root], lr=lr)
    first = None
    for _ in range(steps):
        loss = constraint.loss(state_of(local, root, previous=previous))
        first = float(loss.detach()) if first is None else first
        opt.zero_grad()
        loss.backward()
        opt.step()
    return first, float(constraint.loss(state_of(local, root, previous=previous)).detach())


CASES = [
    SensorConstraint(
        joint="lwrist",
        position=REST[J["lwrist"]] + STAND + [0.1, -0.2, 0.1],
        rotation=Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.6),
    ),
    SensorConstraint(joint="rankle", dof=3, position=REST[J["rankle"]] + STAND + [0.0, -0.15, 0.1]),
    EndEffectorConstraint(joint="rwrist", position=REST[J["rwrist"]] + STAND + [0.1, -0.25, 0.0]),
    EndEffectorConstraint(
        joint="lwrist",
        position=REST[J["lwrist"]] + STAND,
        use_rotation=True,
        rotation=Q.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.5),
    ),
    LookAtConstraint(target=np.array([1.5, -1.0, 1.2])),
    FloorConstraint(clearance=0.1),
    BalanceConstraint(tolerance=0.0),
    BalanceConstraint(mode="com_over_feet", tolerance=0.0),
    DistanceConstraint(distance=0.5),
    BoundsConstraint(joint="lwrist", box_min=np.array([-0.2, -0.5, 1.0]), box_max=np.array([0.5, 0.5, 1.2])),
    PinConstraint(joint="rwrist", position=REST[J["rwrist"]] + STAND + [0.0, -0.1, -0.1]),
]


@pytest.mark.parametrize("c", CASES, ids=lambda c: c.kind)
def test_loss_falls_when_the_pose_moves_towards_satisfying_it(c):
    before, after = descend(c)
    assert math.isfinite(before) and before > 0
    assert after < 0.5 * before


def test_floor_sliding_term_pulls_a_planted_foot_back():
    prev = rest_state().positions.detach().clone()
    prev[J["ltoe"], :2] += torch.tensor([0.05, 0.0], dtype=torch.float64)
    c = FloorConstraint(joints=("ltoe",), clearance=-1.0, contact_height=1.5)  # only sliding counts
    before, after = descend(c, previous=prev)
    assert after < 0.2 * before


def test_hand_built_satisfied_and_unsatisfied_states():
    s = rest_state()
    wrist = s.positions[J["lwrist"]].detach().numpy()
    assert float(SensorConstraint(joint="lwrist", position=wrist).loss(s)) < 1e-12
    assert SensorConstraint(joint="lwrist", position=wrist).satisfied(s)
    far = SensorConstraint(joint="lwrist", position=wrist + [0.0, 0.0, 0.1])
    assert float(far.loss(s)) == pytest.approx(0.01) and not far.satisfied(s)
    turned = SensorConstraint(
        joint="lwrist", position=wrist, rotation=Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.radians(60))
    )
    assert float(turned.loss(s)) == pytest.approx(0.1 * math.sin(math.radians(30)) ** 2)
    assert not turned.satisfied(s)
    assert float(SensorConstraint(joint="lwrist", connected=False, position=wrist + 1).loss(s)) == 0.0

    head = s.positions[J["upperneck"]].detach().numpy()
    assert float(LookAtConstraint(target=head + [0, -2.0, 0]).loss(s)) < 1e-12  # rest head faces -Y
    assert float(LookAtConstraint(target=head + [0, 2.0, 0]).loss(s)) == pytest.approx(2.0)
    for deg, ok in ((4.5, True), (5.5, False)):  # the default tolerance: 5 degrees
        aside = head + 2.0 * np.array([math.sin(math.radians(deg)), -math.cos(math.radians(deg)), 0.0])
        assert LookAtConstraint(target=aside).satisfied(s) == ok, deg
        turn = Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.radians(deg))
        assert SensorConstraint(joint="lwrist", position=wrist, rotation=turn).satisfied(s) == ok, deg
        assert SensorConstraint(joint="lwrist", position=wrist + [0, 0, deg / 500]).satisfied(s) == ok, deg  # 1 cm
    assert float(FloorConstraint().loss(s)) == 0.0  # toes above the floor
    assert float(FloorConstraint().loss(rest_state(root=[0, 0, 0.9]))) > 0
    assert (
        float(BoundsConstraint(joint="root", box_min=np.array([-1, -1, 0.5]), box_max=np.array([1, 1, 1.5])).loss(s))
        == 0
    )
    assert float(
        BoundsConstraint(joint="root", box_min=np.array([-1, -1, 1.1]), box_max=np.array([1, 1, 1.5])).loss(s)
    ) == pytest.approx(0.01)
    span = float(np.linalg.norm(REST[J["lwrist"]] - REST[J["rwrist"]]))
    assert float(DistanceConstraint(distance=span).loss(s)) < 1e-12
    assert float(DistanceConstraint(distance=span - 0.1).loss(s)) == pytest.approx(0.01)
    lean = float(np.linalg.norm(REST[J["upperneck"], :2]))
    assert float(BalanceConstraint(tolerance=lean + 0.001).loss(s)) == 0.0
    assert float(BalanceConstraint(tolerance=0.0).loss(s)) == pytest.approx(lean**2)


def test_temporal_prior_is_the_latent_mse_and_zero_without_prediction():
    z = torch.tensor([1.0, 2.0, 3.0, 4.0], dtype=torch.float64)
    c = TemporalPriorConstraint()
    assert float(c.loss(rest_state(latent=z))) == 0.0
    assert float(c.loss(rest_state(latent=z, prediction=torch.zeros(4, dtype=torch.float64)))) == pytest.approx(7.5)


def test_an_unset_pin_targets_the_previous_position_and_is_never_changed():
    """A published constraint is read by the engine thread without a lock: its loss must
    not write to it."""
    s = rest_state()
    prev = s.positions.detach() + torch.tensor([0.0, 0.1, 0.0], dtype=torch.float64)
    pin = PinConstraint(joint="lankle")
    assert not np.isfinite(pin.position).any() and pin.gizmo() is None
    assert float(pin.loss(s)) == 0.0  # no previous pose: nothing to hold yet
    s.previous_positions = prev
    assert float(pin.loss(s)) == pytest.approx(0.01)
    assert not np.isfinite(pin.position).any()  # unchanged
    held = pin.settled(prev.numpy())
    assert held is not pin and np.allclose(held.position, prev[J["lankle"]].numpy())
    assert isinstance(held.gizmo(), PointGizmo) and not np.isfinite(pin.position).any()
    assert held.settled(prev.numpy() + 1.0) is held  # captured once
    follow = PinConstraint(joint="lankle", follow_previous=True)
    assert float(follow.loss(s)) == pytest.approx(0.01)
    assert follow.settled(prev.numpy()) is follow


def test_the_trackers_term_gives_each_tracker_its_own_loss():
    """All trackers of a frame are one term; its per-tracker losses are each tracker's loss
    alone (a lost tracker's is zero)."""
    from engine.constraints.base import frame_inputs, state_arrays
    from engine.constraints.residual import torch_kit

    s = rest_state()
    s.rotation_matrices = None
    items = [c for c in CASES if c.kind == "sensor"] + [SensorConstraint(joint="root", connected=False)]
    (term,) = SensorConstraint.terms(items, frame_inputs(s))
    kit = torch_kit()
    batched = term.losses(term.residual(kit, *state_arrays(s)), kit)[0]
    single = torch.stack([c.loss(s) for c in items])
    assert torch.allclose(batched, single, atol=1e-10) and float(single[-1]) == 0.0 and float(single[:-1].sum()) > 0


@pytest.mark.parametrize("kind", sorted(REGISTRY))
def test_every_kind_survives_a_json_round_trip(kind):
    c = REGISTRY[kind](name=f"my {kind}", weight=2.5, enabled=False)
    text = json.dumps(c.to_dict(), allow_nan=False)
    back = from_dict(json.loads(text))
    assert type(back) is type(c) and back.to_dict() == c.to_dict()
    for g in (c.gizmo(), c.gizmo(REST)):
        assert g is None or isinstance(g, Gizmo)


def test_gizmos_are_shapes_whose_edit_fields_the_constraint_has():
    drawn = set()
    for c in CASES:
        for g in (c.gizmo(), c.gizmo(REST)):
            assert g is None or type(g) in gizmo_types(), (c.kind, g)
            if g is not None:  # a drag writes fields the constraint has
                drawn.add(c.kind)
                assert all(f in c.to_dict() for f in g.edit_fields), (c.kind, g.edit_fields)
    assert {"pin", "look_at", "bounds", "distance", "end_effector"} <= drawn
    look = next(c for c in CASES if c.kind == "look_at")
    assert look.gizmo(REST).edit_fields == ("target",), "the look-at target stays draggable with a pose"
    assert isinstance(look.gizmo(REST), LineGizmo) and isinstance(look.gizmo(), PointGizmo)


@pytest.mark.parametrize(
    "data, field",
    [
        ({"kind": "sensor", "joint": "tail"}, "joint"),
        ({"kind": "sensor", "dof": 4}, "dof"),
        ({"kind": "bounds", "box_min": [0, 0]}, "box_min"),
        ({"kind": "distance", "joint_b": "nose"}, "joint_b"),
        ({"kind": "pin", "colour": "red"}, "colour"),
        ({"kind": "end_effector", "weight": "heavy"}, "weight"),
        ({"kind": "look_at", "enabled": "yes"}, "enabled"),
        ({"kind": "floor", "joints": ["lankle", "hoof"]}, "joints"),
        ({"kind": "balance", "mode": "tiptoe"}, "mode"),
    ],
)
def test_bad_fields_are_named(data, field):
    with pytest.raises(UserError, match=field):
        from_dict(data)


def test_unknown_kind_lists_the_known_ones():
    with pytest.raises(UserError, match="end_effector"):
        from_dict({"kind": "teleport"})


def test_nan_targets_give_non_finite_losses_not_exceptions():
    s = rest_state()
    for c in (
        SensorConstraint(joint="lwrist", position=np.full(3, np.nan)),
        EndEffectorConstraint(position=np.array([np.inf, 0, 0])),
        LookAtConstraint(target=np.full(3, np.nan)),
    ):
        assert not torch.isfinite(c.loss(s))
