"""A constraint kind is one module: the registry finds it, and a kind lacking a part is
refused; published constraints are never changed; a kind without a fast-path term is
reported, never silently slow."""

from __future__ import annotations

import copy
import warnings
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
import torch

import engine.constraints as package
from engine import skeleton as sk
from engine.constraints import REGISTRY, SensorConstraint
from engine.constraints.base import FRAME_FIELDS, Constraint, missing_parts, param
from engine.constraints.terms import FrameInputs
from engine.solver import FrameContext, OptimizerSettings, PoseOptimizer, RootFrame
from engine.solver.slow_path import SlowPathWarning
from engine.studio.catalog import constraint_catalog, describe
from tests.engine.test_constraints import CASES, rest_state
from tests.engine.test_fast_terms import _cases


@pytest.fixture
def registry():
    """Kinds a test defines are taken out of the registry afterwards."""
    before = dict(REGISTRY)
    yield
    REGISTRY.clear()
    REGISTRY.update(before)


@pytest.mark.parametrize("kind", sorted(REGISTRY))
def test_every_registered_kind_declares_every_part(kind):
    cls = REGISTRY[kind]
    assert missing_parts(cls) == []
    assert getattr(package, cls.__name__) is cls  # found by the package, no list to edit
    assert cls.__module__ == f"engine.constraints.{cls.__module__.rsplit('.', 1)[-1]}"


def test_a_kind_lacking_parts_is_refused_naming_them(registry):
    @dataclass
    class Half(Constraint):
        kind: ClassVar[str] = "test_half"
        joint: str = "lwrist"

        def loss(self, state):
            return state.positions.sum() * 0

    missing = missing_parts(Half)
    assert missing == ["acts_on()", "placement()", "fast_term() or no_fast_term",
                       "editor metadata on field 'joint' (engine.constraints.base.param)"]  # fmt: skip
    with pytest.raises(TypeError, match="test_half.*acts_on"):
        Half.check_complete()
    with pytest.raises(TypeError, match="editor metadata"):
        describe(Half)


def test_a_kind_module_that_fails_to_import_fails_the_package(monkeypatch):
    real = package.importlib.import_module

    def broken(name):
        if name.endswith(".look_at"):
            raise SyntaxError("invalid syntax")
        return real(name)

    monkeypatch.setattr(package.importlib, "import_module", broken)
    with pytest.raises(ImportError, match="engine.constraints.look_at failed to import: invalid syntax"):
        package._discover()


def test_editor_tags_come_from_field_metadata_not_names(registry):
    @dataclass
    class Named(Constraint):
        kind: ClassVar[str] = "test_named"
        no_fast_term: ClassVar[str] = "a test kind"
        joint_count: int = param(2, editor="int")
        end_joint_label: str = param("hand", editor="str")
        which: str = param("a", editor="choice", choices=("a", "b"))
        spread: float = param(0.5, editor="float", unit="m")

        def loss(self, state):
            return state.positions.sum() * 0

        def acts_on(self):
            return ()

        @classmethod
        def placement(cls, params, positions):
            return {}

    spec = describe(Named)
    tags = {f.name: (f.tag, f.choices, f.unit) for f in spec.fields if f.name not in FRAME_FIELDS}
    assert tags == {"joint_count": ("int", (), ""), "end_joint_label": ("str", (), ""), "which": ("choice", ("a", "b"), ""),
                    "spread": ("float", (), "m")}  # fmt: skip
    assert {f.name: f.tag for f in constraint_catalog()["floor"].fields}["joints"] == "joints"


def test_joints_a_kind_acts_on():
    acts = {c.name or c.kind: c.acts_on() for c in CASES}
    assert acts["distance"] == ("lwrist", "rwrist") and acts["floor"] == ("lankle", "rankle", "ltoe", "rtoe")
    assert acts["look_at"] == ("upperneck",) and acts["pin"] == ("rwrist",)
    for c in CASES:
        assert set(c.acts_on()) <= set(sk.JOINT_NAMES) and c.acts_on()


@pytest.mark.parametrize("index", range(16))
def test_solving_never_changes_a_constraint(index):
    """The studio publishes its constraint objects to the engine thread without copies or
    a lock: a loss, a fast-path term or a check must not write to them."""
    state = rest_state()
    state.previous_positions = state.positions.detach() + 0.05
    c = _cases(state.positions.detach().numpy())[index]
    before = copy.deepcopy(c.to_dict())
    c.loss(state), c.satisfied(state), c.gizmo(state.positions.detach().numpy())
    term = c.fast_term(FrameInputs(state.previous_positions.numpy()))
    pos = state.positions.detach().numpy()
    term.evaluate(pos, np.tile(np.eye(3), (22, 1, 1)), np.zeros((22, 3)), np.zeros((22, 3)))
    after = c.to_dict()
    assert before.keys() == after.keys()
    for k in before:
        assert np.array_equal(np.asarray(before[k], dtype=object), np.asarray(after[k], dtype=object)), k


def test_a_kind_without_a_fast_term_is_flagged_and_warned_about_once(registry, shipped_vae):
    @dataclass
    class Slow(Constraint):
        kind: ClassVar[str] = "test_slow"
        no_fast_term: ClassVar[str] = "a test kind"
        height: float = param(1.5, editor="float", unit="m")

        def loss(self, state):
            return (state.positions[sk.JOINT_INDEX["upperneck"], 2] - self.height) ** 2

        def acts_on(self):
            return ("upperneck",)

        @classmethod
        def placement(cls, params, positions):
            return {}

    Slow.check_complete()
    opt = PoseOptimizer(shipped_vae, sk.Skeleton.canonical().offsets, OptimizerSettings(iterations=2))
    ctx = FrameContext(RootFrame(torch.tensor([1.0, 0, 0, 0]), torch.tensor([0.0, 0.0, 0.95])))
    sensor = SensorConstraint(name="s", joint="lwrist", position=np.array([0.3, -0.2, 1.0]))
    z = torch.zeros(24)
    fast = opt.solve(z, [sensor], ctx)
    assert fast.timings.fast and fast.slow_kinds == () and "slow_path" not in fast.timings.per_iteration()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        first = opt.solve(z, [sensor, Slow(name="slow")], ctx)
        second = opt.solve(z, [sensor, Slow(name="slow")], ctx)
    assert first.slow_kinds == second.slow_kinds == ("test_slow",) and not first.timings.fast
    assert first.timings.per_iteration()["slow_path"] == 1.0
    assert [w.category for w in seen] == [SlowPathWarning]
    assert any("test_slow" in m for m in first.warnings) and not any("test_slow" in m for m in second.warnings)


@pytest.fixture(scope="module")
def shipped_vae():
    from engine.models import load_default_models

    return load_default_models().vae


def test_the_studio_snapshot_timing_carries_the_slow_path_flag(registry):
    """DragPoser with a kind without a fast term: each frame's timings (what the engine
    thread copies into the snapshot's ``timing``, the studio's badge) say ``slow_path``;
    the warning line comes with the first such frame only."""
    from pathlib import Path

    from engine.methods.dragposer import create
    from engine.motion.retarget import load_motion
    from engine.studio.frame_figures import timing_of as _timing
    from engine.tracking import simulate

    @dataclass
    class Slow(Constraint):
        kind: ClassVar[str] = "test_slow_method"
        no_fast_term: ClassVar[str] = "a test kind"

        def loss(self, state):
            return (state.positions[sk.JOINT_INDEX["upperneck"], 2] - 1.5) ** 2

        def acts_on(self):
            return ("upperneck",)

        @classmethod
        def placement(cls, params, positions):
            return {}

    motion = load_motion(Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh", max_frames=3)
    tracking = simulate(motion, "6")
    method = create(iterations=2)
    method.reset(motion.skeleton, motion.fps)
    plain = method.step(tracking.frame(0))
    method.set_constraints([Slow(name="slow")])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SlowPathWarning)
        first, second = method.step(tracking.frame(1)), method.step(tracking.frame(2))
    assert "slow_path" not in _timing(plain, 1.0)
    assert _timing(first, 1.0)["slow_path"] == _timing(second, 1.0)["slow_path"] == 1.0
    assert sum("test_slow_method" in w for w in first.warnings + second.warnings) == 1
