"""A constraint kind is one module: the registry finds it, a kind lacking a part is
refused, and a kind defined outside the package (a plug-in) is solved like the shipped
ones from its one term."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
import torch

import engine.constraints as package
from engine import skeleton as sk
from engine.constraints import REGISTRY
from engine.constraints.base import FRAME_FIELDS, Constraint, missing_parts, param
from engine.editing.catalog import constraint_catalog, describe
from engine.solver import FrameContext, OptimizerSettings, PoseOptimizer, RootFrame
from tests.engine.test_constraints import CASES


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
    assert missing == [
        "term()",
        "acts_on()",
        "examples()",
        "placement()",
        "editor metadata on field 'joint' (engine.constraints.base.param)",
    ]
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
        joint_count: int = param(2, editor="int")
        end_joint_label: str = param("hand", editor="str")
        which: str = param("a", editor="choice", choices=("a", "b"))
        spread: float = param(0.5, editor="float", unit="m")

        def term(self, frame):
            raise NotImplementedError

        @classmethod
        def examples(cls, positions):
            return []

        def acts_on(self):
            return ()

        @classmethod
        def placement(cls, params, positions):
            return {}

    spec = describe(Named)
    tags = {f.name: (f.tag, f.choices, f.unit) for f in spec.fields if f.name not in FRAME_FIELDS}
    assert tags == {
        "joint_count": ("int", (), ""),
        "end_joint_label": ("str", (), ""),
        "which": ("choice", ("a", "b"), ""),
        "spread": ("float", (), "m"),
    }
    assert {f.name: f.tag for f in constraint_catalog()["floor"].fields}["joints"] == "joints"


def test_joints_a_kind_acts_on():
    acts = {c.name or c.kind: c.acts_on() for c in CASES}
    assert acts["distance"] == ("lwrist", "rwrist") and acts["floor"] == ("lankle", "rankle", "ltoe", "rtoe")
    assert acts["look_at"] == ("upperneck",) and acts["pin"] == ("rwrist",)
    for c in CASES:
        assert set(c.acts_on()) <= set(sk.JOINT_NAMES) and c.acts_on()


@pytest.fixture(scope="module")
def shipped_vae():
    from engine.models import load_default_models

    return load_default_models().vae


def test_a_plug_in_kind_is_solved_from_its_term_on_both_objectives(registry, shipped_vae):
    """A kind defined outside the package (its term only) runs on the numpy objective,
    and the autograd reference gives the same solve."""
    from engine.constraints.residual import Kit, Residuals, Term

    class HeadHeightTerm(Term):
        def __init__(self, name, height):
            self.names, self.owner, self.height = (name,), np.zeros(1, dtype=np.intp), height

        def residual(self, kit: Kit, P, W, z, jac=False, rows=None):
            j = sk.JOINT_INDEX["upperneck"]
            r = P[:, j, 2:3] - self.height
            if not jac:
                return Residuals(r)
            d = np.zeros((len(P), 1, 1, 3))
            d[..., 2] = 1.0
            return Residuals(r, np.array([j]), d)

    @dataclass
    class HeadHeight(Constraint):
        kind: ClassVar[str] = "test_head_height"
        height: float = param(1.5, editor="float", unit="m")

        def term(self, frame):
            return HeadHeightTerm(self.name, self.height)

        @classmethod
        def examples(cls, positions):
            return [cls(height=float(positions[sk.JOINT_INDEX["upperneck"], 2]) + 0.2)]

        def acts_on(self):
            return ("upperneck",)

        @classmethod
        def placement(cls, params, positions):
            return {}

    HeadHeight.check_complete()
    settings = OptimizerSettings(iterations=3, optimizer="sgd", step_size=0.5)
    offsets = sk.Skeleton.canonical().offsets
    fast, ref = PoseOptimizer(shipped_vae, offsets, settings), PoseOptimizer(shipped_vae, offsets, settings, fast=False)
    ctx = FrameContext(RootFrame(torch.tensor([1.0, 0, 0, 0]), torch.tensor([0.0, 0.0, 0.95])))
    z = torch.zeros(24)
    a, b = fast.solve(z, [HeadHeight(name="head")], ctx), ref.solve(z, [HeadHeight(name="head")], ctx)
    assert a.timings.fast and not b.timings.fast
    assert a.losses[-1]["head"] < a.losses[0]["head"]
    np.testing.assert_allclose(a.latent.numpy(), b.latent.numpy(), atol=1e-5)
