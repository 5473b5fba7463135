"""The window around the engine: optimizer settings reach the method, the latent debugger
decodes and draws."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.worker_methods import RestPoseMethod

pytestmark = pytest.mark.gui


class LatentStandIn(RestPoseMethod):
    """A rest-pose method with a 24-D latent, a decoder and ``configure`` (no model needed)."""

    name = "latent"

    def __init__(self) -> None:
        self.configured: list[dict] = []

    def configure(self, **values) -> None:
        self.configured.append(values)

    def step(self, sensors):
        res = super().step(sensors)
        res.latent = np.linspace(-1.0, 1.0, 24)
        return res

    def decode_latent(self, z):
        """Rest pose shifted along x by ``z[0]`` metres."""
        return sk.Skeleton.canonical().rest_positions() + [float(z[0]), 0.0, 1.0]


@pytest.fixture
def latent_method(studio, qtbot):
    """Switch the studio to :class:`LatentStandIn`; yields the instance the engine uses."""
    made: list[LatentStandIn] = []
    inner = studio.worker._factory

    def factory(name):
        if name != "latent":
            return inner(name)
        made.append(LatentStandIn())
        return made[-1]

    studio.worker._factory = factory
    studio.session.set_method("latent")
    qtbot.waitUntil(lambda: studio.worker.latest.method == "latent" and studio.worker.latest.latent is not None)
    return made[-1]


def test_optimizer_settings_from_the_panel_reach_the_method(studio, qtbot, latent_method):
    from engine.optimizer import OPTIMIZERS, OptimizerSettings

    panel = studio.optimizer_panel
    update, anchor = panel.editors["optimizer"], panel.editors["root_anchor"]
    assert tuple(update.itemText(i) for i in range(update.count())) == tuple(OPTIMIZERS)
    assert {anchor.itemText(i) for i in range(anchor.count())} >= {"upperneck", "none"}
    assert update.currentText() == OptimizerSettings().optimizer  # the engine's default until set
    seq = studio.worker.latest.seq
    rule = next(v for v in OPTIMIZERS if v != update.currentText())
    update.setCurrentText(rule)
    anchor.setCurrentText("none")
    panel.editors["iterations"].setValue(3)
    wanted = {"optimizer": rule, "root_anchor": "none", "iterations": 3}
    assert {k: studio.session.settings[k] for k in wanted} == wanted
    # the worker passes the method every setting made so far, then solves the frame again
    qtbot.waitUntil(lambda: any(wanted.items() <= c.items() for c in latent_method.configured))
    qtbot.waitUntil(lambda: studio.worker.latest.seq > seq)


def test_latent_debugger_decodes_an_edited_latent_and_draws_it(studio, qtbot, latent_method):
    inspector = studio.latent
    qtbot.waitUntil(lambda: inspector.debug_box.isEnabled() and inspector.latent is not None)
    assert np.allclose(inspector.bars.opts["height"], np.linspace(-1, 1, 24))
    studio.session.play()
    inspector.debug.setChecked(True)
    assert not studio.session.playing
    inspector.dim.setValue(0)
    inspector.value.setValue(150)  # z[0] = 1.5: the stand-in shifts the pose 1.5 m along x
    qtbot.waitUntil(lambda: studio.worker.latest.decoded is not None and studio.viewport.decoded.visible)
    assert np.allclose(studio.viewport.decoded.mesh.points[0, 0], 1.5)
    inspector.debug.setChecked(False)
    qtbot.waitUntil(lambda: studio.worker.latest.decoded is None and not studio.viewport.decoded.visible)

