"""A/B timing of two versions of a method, interleaved frame by frame in one process
(for a busy machine: compare the two, don't read absolute figures).

    PYTHONPATH=. python research/bench_ab.py [--baseline REV] [--method dragposer] [--frames 200]
                                            [--sensors 6] [--iterations 10] [--mode realtime] [--bank]
                                            [--scene SCENE.json]

``--baseline REV`` loads ``engine/`` as it was at git revision REV (``git archive``
into a temporary folder, imported under its own module objects) next to the working
tree's; without it the fast and the reference solver paths of the working tree are
compared. Both versions run on the same frames of the bundled clip, alternating which
goes first; the table gives per-frame medians and minimums, wall clock and the thread's
CPU time (on a loaded machine the CPU time leaves out the time the process waited for a
core), and for dragposer the per-iteration breakdown (wall clock). DragPoser runs without
the pose bank (the temporal predictor gives the prior) unless ``--bank`` gives it the
shipped bank as ``dragposer-studio bench`` and the studio do (each version its own copy).
``--scene`` adds a run of each version with the scene's constraints besides the trackers
(each version loads the scene with its own code, as ``bench --scene`` does), and prints
each version's ratio of the scene's ms per iteration to its trackers-only one. ``--cpu``
makes the solver's own per-iteration timings thread CPU time instead of wall clock (the
``time`` module of the version's ``engine.solver`` modules answers ``perf_counter`` with
``thread_time``; a few microseconds per iteration more, alike in both): on a loaded
machine the wall-clock breakdown counts the waits for a core.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np
import torch

from ab_versions import ROOT, EngineVersion, checkout

CLIP = ROOT / "assets" / "clips" / "example.bvh"


def _build(v: EngineVersion, method: str, a: argparse.Namespace, motion, **kw):
    """A method instance of one engine version, reset for ``motion`` (``scene=PATH``: with
    the scene's constraints)."""
    scene = kw.pop("scene", None)
    with v:
        if method == "ik":
            from engine.methods.ik import IKMethod

            m = IKMethod()
        else:
            from engine.methods.dragposer import DragPoserMethod
            from engine.models import load_default_models

            models = load_default_models()
            if a.mode != "realtime":
                kw["mode"] = a.mode
            if a.bank:
                from engine.solver.tracker_prior import default_bank

                kw["bank"] = default_bank()
            m = DragPoserMethod(models.vae, models.predictor, iterations=a.iterations, **kw)
        if scene is not None:
            from engine.methods import driver
            from engine.scene import load_scene

            driver.set_constraints(m, load_scene(scene)[0])
        m.reset(motion.skeleton, motion.fps)
        if a.cpu:
            _cpu_clock()
    return m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="git revision to compare with (default: fast vs reference solver path)")
    ap.add_argument("--method", default="dragposer", choices=("dragposer", "ik"))
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--mode", default="realtime", choices=("realtime", "offline"))
    ap.add_argument("--bank", action="store_true", help="dragposer with the shipped pose bank (the product's prior)")
    ap.add_argument("--scene", type=Path, help="also run each version with this scene's constraints")
    ap.add_argument("--cpu", action="store_true", help="the solver's timings in thread CPU time")
    a = ap.parse_args()
    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        new = EngineVersion(ROOT, "working tree")
        runs = {}
        if a.baseline:
            old = EngineVersion(checkout(a.baseline, Path(tmp)), f"baseline {a.baseline}")
            for v in (old, new):
                motion, tracking = _clip(v, a.sensors)  # each version's own loader and simulation
                runs[v.label] = (v, _build(v, a.method, a, motion), tracking, [], [])
                if a.scene:
                    runs[f"{v.label} + scene"] = (v, _build(v, a.method, a, motion, scene=a.scene), tracking, [], [])
        else:
            motion, tracking = _clip(new, a.sensors)
            for fast in (True, False):
                runs["fast" if fast else "reference"] = (
                    new,
                    _build(new, "dragposer", a, motion, fast=fast, scene=a.scene),
                    tracking,
                    [],
                    [],
                )
        _run(runs, a.frames)


def _clip(v: EngineVersion, sensors: str):
    with v:
        from engine.motion.retarget import load_motion
        from engine.tracking import simulate

        motion = load_motion(CLIP)
        return motion, simulate(motion, sensors)


def _cpu_clock() -> None:
    """The current version's ``engine.solver`` modules read thread CPU time for ``perf_counter``."""
    clock = types.SimpleNamespace(perf_counter=time.thread_time, time=time.time)
    for name, module in list(sys.modules.items()):
        if name.startswith("engine.solver") and getattr(module, "time", None) is time:
            module.time = clock


def _run(runs: dict, frames: int) -> None:
    labels = list(runs)
    n = min(frames, *(len(r[2]) for r in runs.values()))
    for i in range(n):
        for label in labels if i % 2 else labels[::-1]:
            v, m, tracking, frame_ms, iter_ms = runs[label]
            with v:
                t0, c0 = time.perf_counter(), time.thread_time()
                res = m.step(tracking.frame(i))
            if i >= 10:
                frame_ms.append((1000.0 * (time.perf_counter() - t0), 1000.0 * (time.thread_time() - c0)))
                if getattr(res, "timings", None):
                    iter_ms.append(res.timings)
    medians: dict[str, float] = {}
    for label in labels:
        _, _, _, frame_ms, iter_ms = runs[label]
        f, cpu = np.array(frame_ms).T
        line = (
            f"{label:<30} frame ms median {np.median(f):7.2f} min {f.min():7.2f} "
            f"(cpu median {np.median(cpu):7.2f} min {cpu.min():7.2f})"
        )
        if iter_ms:
            it = np.array([t["ms_per_iteration"] for t in iter_ms])
            parts = {k: np.median([t[k] for t in iter_ms]) for k in ("decoder", "fk_losses", "backward", "step")}
            line += f" | ms/iteration median {np.median(it):6.3f} min {it.min():6.3f} | " + " ".join(
                f"{k} {v:.3f}" for k, v in parts.items()
            )
            medians[label] = float(np.median(it))
        print(line, flush=True)
    for label in labels:
        if label.endswith(" + scene") and label[: -len(" + scene")] in medians:
            base = medians[label[: -len(" + scene")]]
            print(f"{label:<30} {medians[label] / base:5.3f}x its trackers-only ms/iteration (median)")


if __name__ == "__main__":
    main()
