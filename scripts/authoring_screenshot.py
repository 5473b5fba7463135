"""The pose and key window's screenshot for docs/authoring.md, made by the app itself.

Poses the 1.75 m character (left wrist raised and forward, right wrist out), keys it at
frames 0 and 40, shows frame 40 and saves the window.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/authoring_screenshot.py docs/images/authoring.png
"""

import sys

import numpy as np
from PyQt6.QtWidgets import QApplication

from app.pose_window import PoseWindow
from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.models import load_default_models

app = QApplication(sys.argv)
vae = load_default_models().vae
w = PoseWindow(vae, PoseMode(vae, 1.75))
w.resize(1400, 860)
w.show()
lw, rw = (w.mode.pose.positions[sk.JOINT_INDEX[j]].copy() for j in ("lwrist", "rwrist"))
for k in range(1, 11):
    w.drag_joint("lwrist", lw + np.array([0.0, -0.15, 0.05]) * k / 10)
w.add_key(0)
for k in range(1, 21):
    w.drag_joint("lwrist", lw + np.array([0.05, -0.25, 0.55]) * k / 20)
    w.drag_joint("rwrist", rw + np.array([-0.25, -0.1, 0.25]) * k / 20)
w.settle()
w.add_key(40)
w.keys.length.setValue(61)
w.go_to(40)
w.viewport.set_camera("home", w.mode.pose.root_pos)
for _ in range(5):
    app.processEvents()
ok = w.files.screenshot(sys.argv[1] if len(sys.argv) > 1 else "authoring.png")
w.undo.setClean()
w.close()
sys.exit(0 if ok else 1)
