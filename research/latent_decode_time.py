"""How long a map point takes to come back as the debug pose: from ``decode_latent`` to the
engine's snapshot holding the decoded pose (docs/latent.md, "What it costs").

A headless engine thread (no window) on the bundled clip with DragPoser, paused at frame
5; ``--points`` map points around the frame's own are decoded one after another; the
first decode of a session is printed apart (it pays torch's first-use imports).

    PYTHONPATH=. python research/latent_decode_time.py [--points 10]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def wait_for(cond, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise SystemExit("timed out")
        time.sleep(0.002)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--points", type=int, default=10)
    args = p.parse_args()
    from engine.latent.projection import default_map
    from engine.motion.retarget import load_motion
    from engine.studio.session import Session

    root = Path(__file__).resolve().parent.parent
    s = Session(method="dragposer")
    s.set_motion(load_motion(root / "assets" / "clips" / "example.bvh").slice(0, 60))
    w = s.start_engine()
    try:
        wait_for(lambda: w.latest is not None and w.latest.latent_view is not None)
        s.step(5)
        wait_for(lambda: w.latest.latent_view is not None and w.latest.latent_view.frame == 5)
        time.sleep(1.0)  # the deferred predictor work after the frame
        m, view = default_map(), w.latest.latent_view
        times = []
        for k in range(args.points + 1):
            seq = w.latest.seq
            z = m.move_to(view.latent, view.xy + 0.3 * np.array([np.cos(k), np.sin(k)]))
            t0 = time.perf_counter()
            s.decode_latent(z)
            wait_for(lambda seq=seq: w.latest.seq > seq and w.latest.decoded is not None, 30)
            times.append(1000 * (time.perf_counter() - t0))
        rest = np.array(times[1:])
        print(
            f"first decode {times[0]:.0f} ms; then {len(rest)} decodes: median {np.median(rest):.1f} ms, "
            f"max {rest.max():.1f} ms"
        )
    finally:
        w.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
