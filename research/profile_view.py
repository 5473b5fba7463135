"""What one 3D-view draw costs in the real window, apart from the engine and the panels.

Opens the studio at 1600x1000 on a clip with a sensor preset (IK in a thread, so no
model loads), plays a few seconds to collect snapshots, pauses, stops the display
timer, then draws the collected snapshots again and again with
``Viewport.show_snapshot`` and prints the cost per draw: CPU time of the whole process
(Mesa's rasterizer thread included; it is what a loaded machine distorts least) and
wall time. Compare two versions by running this alternately from each tree::

    xvfb-run -a -s "-screen 0 1600x1000x24" python research/profile_view.py --draws 200

``--profile`` prints the Python functions that took the most time instead.
"""

from __future__ import annotations

import argparse
import os
import sys
import time


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("clip", nargs="?", default="assets/clips/example.bvh")
    ap.add_argument("--sensors", default="6", help="sensor preset (default 6)")
    ap.add_argument("--draws", type=int, default=200, help="draws to time (default 200)")
    ap.add_argument("--profile", action="store_true", help="cProfile the draws instead")
    args = ap.parse_args()
    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))  # as the studio does
    import numpy as np
    from PyQt6.QtCore import QSettings
    from PyQt6.QtWidgets import QApplication

    app = QApplication(sys.argv[:1])
    from app.main_window import MainWindow

    settings = QSettings(os.devnull, QSettings.Format.IniFormat)
    w = MainWindow(method="ik", settings=settings, engine="thread")
    w.resize(1600, 1000)
    w.show()
    w.files.open_path(args.clip)
    w.session.sensors.set_preset(args.sensors)
    snaps = []

    def pump(seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            app.processEvents()
            time.sleep(0.005)
            s = w.session.latest
            if s is not None and (not snaps or snaps[-1].seq != s.seq):
                snaps.append(s)

    pump(3.0)  # the first solve
    w.session.set_playing(True)
    pump(4.0)
    w.session.set_playing(False)
    pump(0.5)
    w.timer.stop()
    vp = w.viewport
    try:
        if len(snaps) < 2:
            print("error: the engine produced fewer than two snapshots", file=sys.stderr)
            return 1
        if args.profile:
            import cProfile
            import pstats

            prof = cProfile.Profile()
            prof.enable()
            for i in range(args.draws):
                vp.show_snapshot(snaps[i % len(snaps)])
            prof.disable()
            pstats.Stats(prof).sort_stats("tottime").print_stats(15)
            return 0
        cpu, wall = [], []
        for i in range(args.draws):
            c, t = time.process_time(), time.perf_counter()
            vp.show_snapshot(snaps[i % len(snaps)])
            cpu.append((time.process_time() - c) * 1000.0)
            wall.append((time.perf_counter() - t) * 1000.0)
        size = vp.plotter.render_window.GetSize()
        print(f"view {size[0]}x{size[1]}, {len(snaps)} snapshots, {args.draws} draws")
        print(
            f"cpu  ms per draw: median {np.median(cpu):5.1f}  p25 {np.percentile(cpu, 25):5.1f}  min {np.min(cpu):5.1f}"
        )
        print(
            f"wall ms per draw: median {np.median(wall):5.1f}  p25 {np.percentile(wall, 25):5.1f}  min {np.min(wall):5.1f}"
        )
        return 0
    finally:
        w.close()


if __name__ == "__main__":
    sys.exit(main())
