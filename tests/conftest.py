"""Shared fixtures: where the shared mocap data lives, tiny synthetic motions, and the
display: pytest-xvfb starts Xvfb so the VTK viewport really renders; without any display
Qt falls back to offscreen and the tests marked ``gui`` (VTK) are skipped, saying why."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("DRAGPOSER_SHARED_DATA", REPO.parent / "shared" / "data"))
MOCAP = SHARED_DATA / "mocap"


@pytest.hookimpl(trylast=True)
def pytest_configure(config):
    # after pytest-xvfb has (or has not) set DISPLAY; a pytest-xdist controller runs no
    # test and starts no Xvfb (each worker starts its own): its environment, which the
    # workers inherit, must not send them offscreen
    controller = config.getoption("dist", "no") != "no" and not os.environ.get("PYTEST_XDIST_WORKER")
    if controller:
        return
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    # One torch thread in every test process: the tests' solves are single poses and small
    # batches, whose ops a second intra-op thread only slows on two shared cores (the pose
    # window's floor test: 34 s with two, 14 s with one, on the loaded 2-core machine), and
    # with two pytest-xdist workers each core runs a worker. Set once here, not by whichever
    # fixture happens to run first, so a test's speed does not depend on the order.
    import torch

    torch.set_num_threads(1)


@pytest.fixture(autouse=True)
def _cycles_collected_between_events(request):
    """A test of Qt widgets collects garbage as the studio does: from a GUI-thread timer,
    between events (app.collector). With automatic collection a widget an earlier test
    dropped, or this test's own window once its function returned, could be deleted by a
    collection that happened to start inside a paint: a segfault whose test depended on
    how many objects the tests before it had made."""
    if "qtbot" not in request.fixturenames:
        yield
        return
    request.getfixturevalue("qapp")  # the collector's timer needs the application
    from app.collector import collected_between_events

    with collected_between_events():
        yield


def pytest_addoption(parser):
    parser.addoption(
        "--soak",
        action="store_true",
        help="also run the reliability runs marked soak (kill and recover; docs/reliability.md)",
    )


def pytest_collection_modifyitems(config, items):
    if not config.getoption("--soak"):
        later = pytest.mark.skip(reason="a reliability run (minutes): run before closing with --soak")
        for item in items:
            if "soak" in item.keywords:
                item.add_marker(later)
    if os.environ.get("DISPLAY") and os.environ.get("QT_QPA_PLATFORM") != "offscreen":
        return
    skip = pytest.mark.skip(reason="VTK viewport needs a display: install xvfb (pytest-xvfb starts it)")
    for item in items:
        if "gui" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session", autouse=True)
def shipped_models_unchanged():
    """The shipped models are loaded once per process and shared by every test that builds
    DragPoser or asks for them (:func:`engine.models.loading.load_default_models`): at the
    end they must still hold what their files hold, frozen, so no test changed the models
    that later tests ran with."""
    yield
    loading = sys.modules.get("engine.models.loading")
    for shared in list(loading._SHIPPED.values()) if loading is not None else []:
        import torch

        fresh = loading.load_models(loading.DEFAULT_VAE, loading.DEFAULT_PREDICTOR if shared.predictor else None)
        for kind, model, file in (("vae", shared.vae, fresh.vae), ("predictor", shared.predictor, fresh.predictor)):
            if model is None:
                continue
            changed = [k for k, t in model.state_dict().items() if not torch.equal(t, file.state_dict()[k])]
            assert not changed, f"a test changed the shared shipped {kind}: {changed[:5]}"
            assert not model.training and not any(p.requires_grad for p in model.parameters()), (
                f"a test unfroze the shared shipped {kind}"
            )


@pytest.fixture(scope="session")
def shared_mocap() -> Path:
    """``../shared/data/mocap``; tests using it skip when it is absent."""
    if not (MOCAP / "manifest.json").is_file():
        pytest.skip(f"shared motion data not found at {MOCAP} (set DRAGPOSER_SHARED_DATA)")
    return MOCAP


@pytest.fixture
def synthetic_motion():
    """A smooth 120-frame canonical motion (walk-like sway), deterministic."""
    from engine import skeleton as sk
    from engine.kinematics import quaternion as Q
    from engine.motion.clip import Motion

    f = 120
    t = np.arange(f) / 60.0
    rng = np.random.default_rng(7)
    amp = rng.uniform(0.05, 0.4, size=(sk.NUM_JOINTS, 3))
    phase = rng.uniform(0, 2 * np.pi, size=(sk.NUM_JOINTS, 3))
    aa = amp[None] * np.sin(2 * np.pi * 1.0 * t[:, None, None] + phase[None])
    angle = np.linalg.norm(aa, axis=-1)
    axis = aa / np.maximum(angle[..., None], 1e-9)
    rot = Q.from_axis_angle(axis, angle)
    root = np.stack([0.3 * t, -1.2 * t, 0.95 + 0.02 * np.sin(4 * np.pi * t)], axis=-1)
    return Motion(rot, root, sk.Skeleton.canonical(), 60.0, "synthetic")
