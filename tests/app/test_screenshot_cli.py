"""``dragposer-studio gui --screenshot``: the headless check, run for real."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from tests.conftest import REPO
from tests.widgets.test_viewport import orange_fraction

pytestmark = pytest.mark.gui


def test_gui_screenshot_plays_saves_the_window_and_exits_0(tmp_path):
    out = tmp_path / "studio.png"
    env = {**os.environ, "XDG_CONFIG_HOME": str(tmp_path / "config"), "OMP_NUM_THREADS": "1"}
    env.pop("QT_QPA_PLATFORM", None)  # the real window on the test's X display
    cmd = [
        sys.executable,
        "-m",
        "engine.cli.main",
        "gui",
        "--method",
        "ik",
        "--screenshot",
        str(out),
        "--after-frames",
        "10",
    ]
    done = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    from PyQt6.QtGui import QImage

    img = QImage(str(out)).convertToFormat(QImage.Format.Format_RGB888)
    assert (img.width(), img.height()) == (1600, 980)  # the whole window, not just the 3D view
    arr = np.frombuffer(img.constBits().asstring(img.sizeInBytes()), np.uint8)
    arr = arr.reshape(img.height(), img.bytesPerLine())[:, : img.width() * 3].reshape(img.height(), img.width(), 3)
    assert orange_fraction(arr) > 0.001  # the reconstructed skeleton is in the picture
    # remembered settings were written where QSettings keeps them (here a temporary home)
    assert (tmp_path / "config" / "dragposer-studio" / "studio.conf").is_file()
