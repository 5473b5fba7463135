"""A studio that autosaves, is edited and then is killed or quits cleanly, for
tests/app/test_autosave.py (run in a subprocess)::

    python -m tests.app.autosave_child STATE CLIP OUT kill|quit

Opens CLIP, edits sensors, a constraint, a setting, the frame and a range re-solve, waits
until the autosave has written the last of them, writes what the window holds to OUT
(``OUT.json``: the scene; ``OUT.npz``: the clip's arrays), then kills itself with
SIGKILL or closes the window and quits as ``gui`` does.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np


def _wait(app, done, seconds: float = 60.0) -> None:
    end = time.monotonic() + seconds
    while not done():
        if time.monotonic() > end:
            raise TimeoutError("the child studio waited too long")
        app.processEvents()
        time.sleep(0.01)


def main(state: str, clip: str, out: str, end: str) -> int:
    from PyQt6.QtCore import QSettings
    from PyQt6.QtWidgets import QApplication, QMessageBox

    from app.main import start_autosave
    from app.main_window import MainWindow
    from app.range_actions import resolve_range

    app = QApplication(sys.argv[:1])
    QMessageBox.question = lambda *a, **k: QMessageBox.StandardButton.Discard  # quitting discards the edits
    w = MainWindow(settings=QSettings(str(Path(state) / "studio.ini"), QSettings.Format.IniFormat), engine="thread")
    files = start_autosave(w, Path(state))
    auto = w.autosave.studio
    auto.timer.setInterval(200)
    assert w.files.open_path(clip, ask=False)
    w.show()
    s = w.session
    _wait(app, lambda: s.latest is not None)
    s.sensors.set_preset("4")
    s.sensors.edit("lwrist", weight=2.5)
    s.constraints.add("floor")
    s.set_settings({"lr": 0.03})
    s.seek(12)
    resolve_range(w, 5, 15, blend=2).wait()
    s.seek(20)
    # what the window held at each write: the seek's frame may reach the session after a
    # write already under way, so wait for a write made from the state that is dumped below
    written: list[str] = []
    auto.saved.connect(lambda _path: written.append(json.dumps(s.to_scene(), sort_keys=True)))
    _wait(
        app,
        lambda: bool(written) and not auto.timer.isActive() and written[-1] == json.dumps(s.to_scene(), sort_keys=True),
    )
    Path(out + ".json").write_text(json.dumps(s.to_scene()))
    np.savez(out + ".npz", local_rot=s.motion.local_rot, root_pos=s.motion.root_pos)
    if end == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    w.close()
    app.processEvents()
    assert files is not None
    files.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:5]))
