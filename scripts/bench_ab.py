"""A/B timing of two versions of a method, interleaved frame by frame in one process
(for a busy machine: compare the two, don't read absolute figures).

    PYTHONPATH=. python scripts/bench_ab.py [--baseline REV] [--method dragposer] [--frames 200]
                                            [--sensors 6] [--iterations 10] [--mode realtime]

``--baseline REV`` loads ``engine/`` as it was at git revision REV (``git archive``
into a temporary folder, imported under its own module objects) next to the working
tree's; without it the fast and the reference solver paths of the working tree are
compared. Both versions run on the same frames of the bundled clip, alternating which
goes first; the table gives per-frame medians and minimums, wall clock and the thread's
CPU time (on a loaded machine the CPU time leaves out the time the process waited for a
core), and for dragposer the per-iteration breakdown (wall clock).
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
CLIP = ROOT / "assets" / "clips" / "example.bvh"
NEEDED = ("engine.methods.dragposer", "engine.methods.ik", "engine.models", "engine.retarget", "engine.tracking")


def _import_engine(root: Path) -> dict:
    """Import what a run needs from the ``engine`` package under ``root``; returns the
    module objects and leaves ``sys.modules`` without any ``engine`` entry, so another
    version can be imported next to it (modules keep their own globals)."""
    for name in [m for m in sys.modules if m == "engine" or m.startswith("engine.")]:
        del sys.modules[name]
    sys.path.insert(0, str(root))
    try:
        mods = {name: importlib.import_module(name) for name in NEEDED}
    finally:
        sys.path.remove(str(root))
        for name in [m for m in sys.modules if m == "engine" or m.startswith("engine.")]:
            del sys.modules[name]
    return mods


def _checkout(rev: str, into: Path) -> Path:
    data = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "engine", "assets/models"], check=True,
                          capture_output=True).stdout  # fmt: skip
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(into, filter="data")
    return into


def _build(mods: dict, method: str, a: argparse.Namespace, motion, **kw):
    """A method instance of one engine version, reset for ``motion``."""
    if method == "dragposer":
        models = mods["engine.models"].load_default_models()
        if a.mode != "realtime":
            kw["mode"] = a.mode
        m = mods["engine.methods.dragposer"].DragPoserMethod(models.vae, models.predictor, iterations=a.iterations,
                                                             **kw)  # fmt: skip
    else:
        m = mods["engine.methods.ik"].IKMethod()
    m.reset(motion.skeleton, motion.fps)
    return m


def _versions(a: argparse.Namespace, tmp: Path) -> dict[str, dict]:
    if a.baseline:
        return {f"baseline {a.baseline}": _import_engine(_checkout(a.baseline, tmp)), "working tree": _import_engine(ROOT)}
    return {"working tree": _import_engine(ROOT)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="git revision to compare with (default: fast vs reference solver path)")
    ap.add_argument("--method", default="dragposer", choices=("dragposer", "ik"))
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--mode", default="realtime", choices=("realtime", "offline"))
    a = ap.parse_args()
    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        versions = _versions(a, Path(tmp))
        runs = {}
        tracking = None
        for label, mods in versions.items():
            motion = mods["engine.retarget"].load_motion(CLIP)
            tracking = tracking or mods["engine.tracking"].simulate(motion, a.sensors)
            if a.baseline:
                runs[label] = (_build(mods, a.method, a, motion), [], [])
            else:
                for fast in (True, False):
                    runs["fast" if fast else "reference"] = (_build(mods, "dragposer", a, motion, fast=fast), [], [])
        _run(runs, tracking, a.frames)


def _run(runs: dict, tracking, frames: int) -> None:
    labels = list(runs)
    n = min(frames, len(tracking))
    for i in range(n):
        for label in (labels if i % 2 else labels[::-1]):
            m, frame_ms, iter_ms = runs[label]
            t0, c0 = time.perf_counter(), time.thread_time()
            res = m.step(tracking.frame(i))
            if i >= 10:
                frame_ms.append((1000.0 * (time.perf_counter() - t0), 1000.0 * (time.thread_time() - c0)))
                if getattr(res, "timings", None):
                    iter_ms.append(res.timings)
    for label in labels:
        _, frame_ms, iter_ms = runs[label]
        f, cpu = np.array(frame_ms).T
        line = (f"{label:<22} frame ms median {np.median(f):7.2f} min {f.min():7.2f} "
                f"(cpu median {np.median(cpu):7.2f} min {cpu.min():7.2f})")
        if iter_ms:
            it = np.array([t["ms_per_iteration"] for t in iter_ms])
            parts = {k: np.median([t[k] for t in iter_ms]) for k in ("decoder", "fk_losses", "backward", "step")}
            line += (f" | ms/iteration median {np.median(it):6.3f} min {it.min():6.3f} | "
                     + " ".join(f"{k} {v:.3f}" for k, v in parts.items()))  # fmt: skip
        print(line, flush=True)


if __name__ == "__main__":
    main()
