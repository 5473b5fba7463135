"""Shared fixtures: where the shared mocap data lives, tiny synthetic motions, and the
display: pytest-xvfb starts Xvfb so the VTK viewport really renders; without any display
Qt falls back to offscreen and the tests marked ``gui`` (VTK) are skipped, saying why."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("DRAGPOSER_SHARED_DATA", REPO.parent / "shared" / "data"))
MOCAP = SHARED_DATA / "mocap"


@pytest.hookimpl(trylast=True)
def pytest_configure(config):
    # after pytest-xvfb has (or has not) set DISPLAY
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")


def pytest_collection_modifyitems(config, items):
    if os.environ.get("DISPLAY") and os.environ.get("QT_QPA_PLATFORM") != "offscreen":
        return
    skip = pytest.mark.skip(reason="VTK viewport needs a display: install xvfb (pytest-xvfb starts it)")
    for item in items:
        if "gui" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def shared_mocap() -> Path:
    """``../shared/data/mocap``; tests using it skip when it is absent."""
    if not (MOCAP / "manifest.json").is_file():
        pytest.skip(f"shared motion data not found at {MOCAP} (set DRAGPOSER_SHARED_DATA)")
    return MOCAP


@pytest.fixture
def synthetic_motion():
    """A smooth 120-frame canonical motion (walk-like sway), deterministic."""
    from engine.kinematics import quaternion as Q
    from engine.motion.clip import Motion
    from engine import skeleton as sk

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
