"""The gizmo adapter registry: every shape the engine makes has an adapter, a shape
without one is a TypeError, and every constraint kind's gizmo is drawn (under Xvfb)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from engine.constraints import REGISTRY
from engine.gizmos import Gizmo, PointGizmo, gizmo_types
from widgets.viewport.gizmo_adapters import GIZMO_ADAPTERS, PointAdapter
from widgets.viewport.gizmos import ConstraintGizmos, adapter_for


def _engine_shapes() -> list[type[Gizmo]]:
    """The shape classes the engine defines (tests may define strays of their own)."""
    return [cls for cls in gizmo_types() if cls.__module__.split(".")[0] == "engine"]


def test_the_engine_defines_shapes():
    assert {"PointGizmo", "LineGizmo", "BoxGizmo"} <= {cls.__name__ for cls in _engine_shapes()}


@pytest.mark.parametrize("shape", _engine_shapes(), ids=lambda c: c.__name__)
def test_every_shape_has_its_own_adapter(shape):
    adapter = adapter_for(shape)
    assert adapter.shape is shape, f"{shape.__name__} is drawn by {adapter.__name__}, made for {adapter.shape.__name__}"


def test_a_shape_without_an_adapter_is_a_type_error():
    class Cone(Gizmo):
        pass

    with pytest.raises(TypeError, match="no viewport adapter draws gizmo type .*Cone"):
        adapter_for(Cone)
    drawn = ConstraintGizmos(plotter=None, on_edit=lambda name, changes: None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="Cone"):
        drawn.update((("cone", Cone()),))
    assert Gizmo not in GIZMO_ADAPTERS, "the base class must not swallow unknown shapes"


def test_a_subclass_of_a_shape_is_drawn_by_its_base_class_adapter():
    class LabelledDot(PointGizmo):
        pass

    assert adapter_for(LabelledDot) is PointAdapter


def test_shapes_check_their_arrays():
    with pytest.raises(ValueError, match=r"point gizmo position: expected shape \(3\)"):
        PointGizmo([0.0, 1.0])
    with pytest.raises(ValueError, match="not finite"):
        PointGizmo([0.0, np.nan, 1.0])
    p = np.array([0.0, 1.0, 2.0])
    g = PointGizmo(p, edit="position")
    p[0] = 5.0
    assert g.position[0] == 0.0 and not g.position.flags.writeable  # a copy, read-only
    back = pickle.loads(pickle.dumps(PointGizmo(p, anchor=[0.0, 0.0, 1.0])))  # as from the engine process
    assert np.allclose(back.position, p) and not back.position.flags.writeable and not back.anchor.flags.writeable


def _cyan_pixels(img: np.ndarray) -> int:
    """Pixels of the gizmo colour (``style.GIZMO``, #00e5ff), whatever the shading."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return int(np.sum((r < 90) & (g > 150) & (b > 180) & (b >= g - 10)))


@pytest.mark.gui
@pytest.mark.parametrize("kind", sorted(REGISTRY))
def test_each_kind_draws_its_gizmo(kind, qtbot, fake_snapshot):
    """Every registered kind, placed on the pose as the studio places a new one, draws
    through the adapter of its shape, visibly (pixels of the gizmo colour)."""
    from app.constraint_placement import placed_params
    from engine.editing.catalog import constraint_catalog
    from widgets.viewport import Viewport

    snap = fake_snapshot()
    spec = constraint_catalog().get(kind)
    defaults = {} if spec is None else {f.name: f.default for f in spec.fields}
    c = REGISTRY[kind](**{**defaults, **placed_params(kind, defaults, snap.positions)})
    g = c.gizmo(snap.positions)
    view = Viewport()
    qtbot.addWidget(view)
    view.resize(640, 480)
    view.show()
    qtbot.waitExposed(view)
    view.show_snapshot(snap)
    if g is None:  # a kind that draws nothing here (a floor at z = 0, smoothing...) gets no adapter
        view.show_snapshot(fake_snapshot(seq=2, gizmos=((c.name, None),)))
        assert c.name not in view.gizmos.items
        view.close()
        return
    before = _cyan_pixels(view.plotter.screenshot(return_img=True))
    view.show_snapshot(fake_snapshot(seq=2, gizmos=((c.name, g),)))
    item = view.gizmos.items[c.name]
    assert type(item) is adapter_for(type(g))
    assert (item.widget is not None) == bool(g.edit_fields), "an editable shape has a handle"
    after = _cyan_pixels(view.plotter.screenshot(return_img=True))
    assert after > before, f"{kind}: its {type(g).__name__} is not visible ({before} -> {after} px)"
    view.close()
