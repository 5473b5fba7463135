"""The studio's screenshot of a pin limited to a frame range, for docs/studio.md.

Opens the bundled example clip paused at frame 130, pins the left elbow where it is (as
Ctrl-drag does), limits the pin to frames 100-160 with 10 frames of blend each side (as
the constraint editor's *only frames*, start, end and blend fields do), shows the
Constraints tab and saves the window: the editor's range row and the cyan span along
the top of the scrub bar.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/constraint_range_screenshot.py docs/images/constraint_range.png
"""

import sys
import time

from PyQt6.QtWidgets import QApplication, QTabWidget

from app.main import EXAMPLE_CLIP
from app.main_window import MainWindow
from engine import skeleton as sk


def settle(app: QApplication, until=lambda: True, seconds: float = 60.0) -> None:
    deadline = time.monotonic() + seconds
    while not until() and time.monotonic() < deadline:
        app.processEvents()
        time.sleep(0.02)
    for _ in range(20):
        app.processEvents()
        time.sleep(0.02)


app = QApplication(sys.argv)
w = MainWindow(method="dragposer", engine="thread")
w.resize(1600, 980)
w.files.open_path(EXAMPLE_CLIP, ask=False)
w.show()
s = w.session
s.pause()
s.seek(130)
settle(app, lambda: s.latest is not None and s.latest.frame == 130 and s.latest.method == "dragposer", 180)
name = s.constraints.pin("lelbow", s.latest.positions[sk.JOINT_INDEX["lelbow"]])
s.constraints.edit(name, frames=(100, 160), blend_in=10, blend_out=10)
tabs = w.constraint_panel.parentWidget()
while not isinstance(tabs, QTabWidget):
    tabs = tabs.parentWidget()
tabs.setCurrentWidget(w.constraint_panel)
seq = s.latest.seq
settle(app, lambda: w.timeline.slider.span() == (100, 160, 10, 10) and s.latest.seq > seq + 1, 180)
settle(app, lambda: False, 3.0)  # the plots and their legend update a few times a second
ok = w.files.export_screenshot(sys.argv[1] if len(sys.argv) > 1 else "constraint_range.png")
w.undo.set_clean()
w.close()
sys.exit(0 if ok else 1)
