"""The studio's screenshot of a frame range selected on the timeline, for docs/authoring.md.

Opens the bundled example clip, selects frames 60-150 on the timeline (as a Shift-drag
does), shows frame 100 and saves the window.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/range_screenshot.py docs/images/timeline_range.png
"""

import sys
import time

from PyQt6.QtWidgets import QApplication

from app.main import EXAMPLE_CLIP
from app.main_window import MainWindow

app = QApplication(sys.argv)
w = MainWindow(engine="thread")
w.resize(1600, 980)
w.files.open_path(EXAMPLE_CLIP, ask=False)
w.show()
w.session.pause()
w.session.seek(100)
w.timeline.set_selection(60, 150)
deadline = time.monotonic() + 60
while (w.session.latest is None or w.session.latest.frame != 100) and time.monotonic() < deadline:
    app.processEvents()
    time.sleep(0.02)
for _ in range(20):
    app.processEvents()
    time.sleep(0.02)
ok = w.files.export_screenshot(sys.argv[1] if len(sys.argv) > 1 else "timeline_range.png")
w.close()
sys.exit(0 if ok else 1)
