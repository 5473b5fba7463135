"""SparsePoser's realtime step, old code against new, interleaved in one process.

    PYTHONPATH=. .venv/bin/python research/sparseposer_ab.py --baseline 87f96de [--frames 400] [CLIP.bvh]

The baseline's ``engine/methods/sparseposer.py`` and ``engine/models/sparseposer_infer.py``
are read from git (the rest of the engine is the working tree's), both methods get the
shipped weights and one torch thread, and each frame is stepped by both (alternating
which goes first), so a shared, loaded machine slows both alike. Prints wall-clock and
thread-CPU milliseconds per frame (minimum and median) and the largest pose difference.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def _old_module(rev: str, tmp: Path):
    """The baseline's method module, importing the baseline's inference helpers."""

    def show(path: str) -> str:
        return subprocess.run(
            ["git", "-C", str(REPO), "show", f"{rev}:{path}"], check=True, capture_output=True, text=True
        ).stdout

    (tmp / "sp_old_infer.py").write_text(show("engine/models/sparseposer_infer.py"))
    method = show("engine/methods/sparseposer.py").replace("engine.models.sparseposer_infer", "sp_old_infer")
    (tmp / "sp_old_method.py").write_text(method)
    sys.path.insert(0, str(tmp))
    spec = importlib.util.spec_from_file_location("sp_old_method", tmp / "sp_old_method.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("clip", nargs="?", type=Path, default=REPO / "assets" / "clips" / "example.bvh")
    p.add_argument("--baseline", required=True, help="git revision of the old code")
    p.add_argument("--frames", type=int, default=400)
    args = p.parse_args()

    from engine.methods.sparseposer import SparsePoserMethod
    from engine.models.loading import load_sparseposer
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    with tempfile.TemporaryDirectory() as tmp:
        old_cls = _old_module(args.baseline, Path(tmp)).SparsePoserMethod
    model, _ = load_sparseposer()
    motion = load_motion(args.clip)
    tracking = simulate(motion, "6")
    n = min(len(motion), args.frames)
    methods = {"old": old_cls(model=model), "new": SparsePoserMethod(model=model)}
    wall: dict[str, list[float]] = {k: [] for k in methods}
    cpu: dict[str, list[float]] = {k: [] for k in methods}
    for m in methods.values():
        m.reset(motion.skeleton, motion.fps)
    d_rot = d_pos = 0.0
    for i in range(n):
        frame, res = tracking.frame(i), {}
        for name in ("old", "new") if i % 2 == 0 else ("new", "old"):
            c0, t0 = time.thread_time(), time.perf_counter()
            res[name] = methods[name].step(frame)
            wall[name].append(1000.0 * (time.perf_counter() - t0))
            cpu[name].append(1000.0 * (time.thread_time() - c0))
        d_rot = max(d_rot, float(np.abs(res["old"].local_rot - res["new"].local_rot).max()))
        d_pos = max(d_pos, float(np.abs(res["old"].positions - res["new"].positions).max()))
    for name in methods:
        w, c = np.asarray(wall[name][10:]), np.asarray(cpu[name][10:])  # after a warm-up
        print(
            f"{name}: wall min {w.min():.2f} median {np.median(w):.2f} ms; "
            f"thread CPU min {c.min():.2f} median {np.median(c):.2f} ms"
        )
    print(
        f"{n} frames of {args.clip.name}; max |local rotation difference| {d_rot:.1e}, max |position difference| "
        f"{d_pos:.1e} m"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
