"""The one way every caller resets, configures and steps a method (engine/methods/driver.py)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.constraints import PinConstraint
from engine.errors import UserError
from engine.methods import driver, get_method
from engine.methods.base import FrameResult, Method
from engine.sensors import Sensor, SensorFrame
from engine.studio.export import reconstruct_clip
from engine.studio.method_edits import apply_constraints
from tests.stand_ins import RestPoseMethod


class Oracle(RestPoseMethod):
    """Needs the ground truth, like the autoencoder ceiling; remembers what it was given."""

    name = "oracle"
    needs_ground_truth = True

    def reset(self, skeleton, fps=sk.FPS, *, reference=None):
        if reference is None:
            raise UserError("oracle: reset without the ground-truth clip")
        self.reference = reference
        super().reset(skeleton, fps)


class Deadlined(RestPoseMethod):
    """Takes a deadline and weights and constraints; records the calls."""

    name = "deadlined"
    takes_deadline = True

    def __init__(self):
        self.deadlines, self.weights, self.constraints, self.values = [], {}, [], {}

    def step(self, sensors, deadline=None):
        self.deadlines.append(deadline)
        return super().step(sensors)

    def configure(self, **values):
        self.values.update(values)

    def set_constraints(self, constraints):
        self.constraints = list(constraints)

    def add_constraint(self, constraint):
        self.constraints.append(constraint)

    def set_sensor_weight(self, joint, weight):
        self.weights[joint] = weight


class NaNPose(RestPoseMethod):
    name = "nan"

    def step(self, sensors, deadline=None):
        res = super().step(sensors)
        return FrameResult(res.local_rot, res.root_pos, np.full_like(res.positions, np.nan))


def _frame(k: int = 0) -> SensorFrame:
    return SensorFrame(k, {"root": Sensor("root", np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0, 0.0]))})


def test_the_ground_truth_reaches_only_the_methods_that_need_it(synthetic_motion):
    oracle = Oracle()
    driver.reset(oracle, synthetic_motion.skeleton, synthetic_motion.fps, reference=synthetic_motion)
    assert oracle.reference is synthetic_motion
    with pytest.raises(UserError, match="needs the ground-truth clip"):
        driver.reset(Oracle(), synthetic_motion.skeleton, synthetic_motion.fps)
    rest = RestPoseMethod()  # its reset takes no reference keyword by name: none is passed
    driver.reset(rest, synthetic_motion.skeleton, synthetic_motion.fps, reference=synthetic_motion)


def test_the_deadline_reaches_only_the_methods_that_take_one():
    m = Deadlined()
    m.reset(sk.Skeleton.canonical())
    driver.step(m, _frame(), deadline=12.5)
    driver.step(m, _frame(1))
    assert m.deadlines == [12.5, None]

    class NoDeadline(RestPoseMethod):
        def step(self, sensors):  # an older signature: called without the keyword
            return super().step(sensors)

    plain = NoDeadline()
    plain.reset(sk.Skeleton.canonical())
    assert np.all(np.isfinite(driver.step(plain, _frame(), deadline=12.5).positions))


def test_a_non_finite_pose_raises_and_names_the_method():
    m = NaNPose()
    m.reset(sk.Skeleton.canonical())
    with pytest.raises(FloatingPointError, match="'nan'.*frame 3"):
        driver.step(m, _frame(3))


def test_edits_reach_only_the_methods_with_the_capability():
    pin = PinConstraint(name="pin", joint="lwrist", position=(0.3, 0.2, 1.0))
    sensors = (Sensor("lwrist", weight=2.0), Sensor("root", weight=0.5))
    ik = get_method("ik")
    assert not driver.configure(ik, {"lr": 0.1})
    assert not driver.set_constraints(ik, [pin])
    assert not driver.set_sensor_weights(ik, sensors)
    assert apply_constraints(ik, (pin,)) == ["ik ignores constraints"]
    m = Deadlined()
    assert driver.configure(m, {"lr": 0.1}) and m.values == {"lr": 0.1}
    assert driver.set_constraints(m, (pin,)) and m.constraints == [pin]
    assert driver.set_sensor_weights(m, sensors) and m.weights == {"lwrist": 2.0, "root": 0.5}
    ignored = driver.start(ik, sk.Skeleton.canonical(), sk.FPS, settings={"lr": 0.1}, constraints=[pin])
    assert ignored == ["ik has no optimizer settings", "ik ignores constraints"]


def test_the_studio_export_gives_a_ground_truth_method_its_clip(synthetic_motion):
    built: list[Method] = []

    def factory(name):
        built.append(Oracle())
        return built[-1]

    rec = reconstruct_clip(synthetic_motion, (), (), {}, "oracle", factory=factory)
    assert len(rec) == len(synthetic_motion) and built[0].reference is synthetic_motion


def test_a_whole_clip_solve_is_checked_like_a_step():
    class WholeClip(NaNPose):
        def solve_clip(self, frames):
            return [self.step(f) for f in frames]

    m = WholeClip()
    m.reset(sk.Skeleton.canonical())
    with pytest.raises(FloatingPointError, match="frame 0"):
        driver.solve_clip(m, [_frame(0), _frame(1)])
    assert driver.solve_clip(RestPoseMethod(), [_frame(0)]) is None  # steps frame by frame
