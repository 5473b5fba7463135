"""Constraint kinds of the pose optimizer; importing this package registers them all.

See :mod:`engine.constraints.base` for the interface and ``docs/optimizer.md`` for the
parameters of every kind.
"""

from engine.constraints.balance import BalanceConstraint
from engine.constraints.base import REGISTRY, Constraint, from_dict
from engine.constraints.bounds import BoundsConstraint
from engine.constraints.distance import DistanceConstraint
from engine.constraints.end_effector import EndEffectorConstraint
from engine.constraints.floor import FloorConstraint
from engine.constraints.ground import GroundConstraint
from engine.constraints.look_at import LookAtConstraint
from engine.constraints.pin import PinConstraint
from engine.constraints.sensor import SensorConstraint
from engine.constraints.smooth import SmoothConstraint
from engine.constraints.temporal_prior import TemporalPriorConstraint
from engine.solver.state import PoseState  # what every loss(state) receives

__all__ = [
    "REGISTRY", "BalanceConstraint", "BoundsConstraint", "Constraint", "DistanceConstraint",
    "EndEffectorConstraint", "FloorConstraint", "GroundConstraint", "LookAtConstraint", "PinConstraint", "PoseState",
    "SensorConstraint", "SmoothConstraint", "TemporalPriorConstraint", "from_dict",
]  # fmt: skip
