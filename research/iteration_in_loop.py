"""What each piece of a realtime iteration costs *inside* real solves (thread CPU, us).

    PYTHONPATH=. python research/iteration_in_loop.py [FRAMES]

Wraps the fast path's methods (decoder forward and backward, the chain's passes, the
terms' residuals, losses and gradient accumulation, the update step) with thread-CPU
timers and runs the bundled clip with 6 sensors, 10 iterations, one thread. Unlike
``iteration_pieces.py`` (each piece alone in a loop, caches warm), every piece here starts
with the caches the decoder's 3.6 MB of weights left it, as in the product; the timers
add about a microsecond each. Frames 0-19 are left out (warming up).
"""

from __future__ import annotations

import collections
import sys
import time

import numpy as np
import torch
from threadpoolctl import threadpool_limits

import engine.constraints.term_stack as term_stack
import engine.models.fused as fused
import engine.solver.chain as chain
import engine.solver.objective as objective
import engine.solver.optimizer as optimizer
import engine.solver.update as update

SPENT: dict[str, list[int]] = collections.defaultdict(list)


def _wrap(cls: type, name: str, label: str) -> None:
    f = getattr(cls, name)

    def timed(*a, **k):
        c = time.thread_time_ns()
        out = f(*a, **k)
        SPENT[label].append(time.thread_time_ns() - c)
        return out

    setattr(cls, name, timed)


def main() -> None:
    frames = int(sys.argv[1]) if len(sys.argv) > 1 else 300
    for cls, name, label in (
        (fused.DenseDecoder, "forward", "decoder forward"),
        (fused.DenseDecoder, "backward", "decoder backward"),
        (chain.PoseChain, "forward", "chain forward"),
        (chain.PoseChain, "backward", "chain backward"),
        (objective.FastObjective, "_residuals", "terms' residuals"),
        (term_stack.TermStack, "losses", "the terms' losses"),
        (term_stack.TermStack, "gradients", "the terms' gradients"),
        (objective.FastObjective, "evaluate", "evaluate (all)"),
        (objective.FastObjective, "gradient", "gradient (all)"),
        (update.LatentUpdate, "step", "update step"),
        (optimizer.PoseOptimizer, "_run", "solve loop"),
    ):
        _wrap(cls, name, label)

    from engine.methods.dragposer import DragPoserMethod
    from engine.models import load_default_models
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    torch.set_num_threads(1)
    motion = load_motion("assets/clips/example.bvh")
    tracking = simulate(motion, "6")
    models = load_default_models()
    m = DragPoserMethod(models.vae, models.predictor, iterations=10)
    m.reset(motion.skeleton, motion.fps)
    with threadpool_limits(1):
        for i in range(frames):
            if i == 20:
                SPENT.clear()
            m.step(tracking.frame(i))
    n = frames - 20
    for label, v in SPENT.items():
        us = np.array(v) / 1e3
        print(
            f"{label:26s} calls/frame {len(us) / n:5.1f}  median {np.median(us):7.1f} us  per frame {us.sum() / n:8.1f} us"
        )


if __name__ == "__main__":
    main()
