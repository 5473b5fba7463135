"""The batched offline solve against the realtime one, per frame, at two versions of the
engine in one process, by thread CPU time (for a busy machine).

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/offline_batch_ab.py [--baseline REV] [--frames 600]
                                                 [--repeats 2] [--clip FILE.bvh]

For each version (``--baseline REV`` via ``git archive``, and the working tree; see
:mod:`ab_versions`) and each repeat, alternating which version goes first: the clip's
(default: the bundled one) first ``--frames`` frames with six simulated trackers, solved by DragPoser
realtime (``step`` frame by frame, 10 iterations) and offline (the whole-clip batched
solve that ``dragposer-studio bench --mode offline`` times, ``solve_clip``), each from a
freshly reset method. Prints the thread CPU milliseconds per frame of each, and their
ratio (the issue-49 target is offline at most 0.6x realtime). Setup (models, pose bank)
is outside the timed calls. No user constraints: the batched solve does not take them.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from ab_versions import ROOT, EngineVersion, checkout

CLIP = ROOT / "assets" / "clips" / "example.bvh"


def _method(v: EngineVersion, mode: str, motion):
    with v:
        from engine.methods import driver, get_method

        m = get_method("dragposer", mode=mode)
        driver.reset(m, motion.skeleton, motion.fps, reference=motion)
    return m


def _time(v: EngineVersion, mode: str, motion, tracking, frames: int) -> float:
    """Thread CPU ms per frame of one solve of the first ``frames`` frames."""
    m = _method(v, mode, motion)
    with v:
        from engine.methods import driver

        inputs = [tracking.frame(i) for i in range(min(frames, len(tracking)))]
        c0 = time.thread_time()
        if mode == "offline":
            results = driver.solve_clip(m, inputs)
            assert results is not None, "the batched solve did not take the clip"
        else:
            for f in inputs:
                driver.step(m, f)
        return 1000.0 * (time.thread_time() - c0) / len(inputs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", default="main")
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--clip", type=Path, default=CLIP, help="BVH clip (default: the bundled one)")
    a = ap.parse_args()
    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        versions = [
            EngineVersion(checkout(a.baseline, Path(tmp)), f"baseline {a.baseline}"),
            EngineVersion(ROOT, "tree"),
        ]
        clips = {}
        for v in versions:
            with v:
                from engine.motion.retarget import load_motion
                from engine.tracking import simulate

                motion = load_motion(a.clip)
                clips[v.label] = (motion, simulate(motion, "6"))
        times: dict[tuple[str, str], list[float]] = {}
        for rep in range(a.repeats):
            for v in versions if rep % 2 == 0 else versions[::-1]:
                for mode in ("realtime", "offline"):
                    ms = _time(v, mode, *clips[v.label], a.frames)
                    times.setdefault((v.label, mode), []).append(ms)
                    print(f"{v.label:<22} {mode:<9} {ms:7.2f} cpu ms/frame", flush=True)
        for v in versions:
            rt, off = (float(np.median(times[(v.label, m)])) for m in ("realtime", "offline"))
            print(
                f"{v.label:<22} realtime {rt:6.2f}  offline {off:6.2f} cpu ms/frame (median)  offline/realtime {off / rt:5.3f}"
            )


if __name__ == "__main__":
    main()
