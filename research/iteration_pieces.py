"""The pieces of one realtime iteration of the working tree, each timed alone (thread CPU, us).

    PYTHONPATH=. python research/iteration_pieces.py [SENSORS] [REPEATS]

Solves 21 frames of the bundled clip (6 sensors by default), keeps the last frame's
:class:`~engine.solver.objective.FastObjective`, then times, in turn and repeatedly:
decoder forward, chain forward (root + FK), the terms' residuals with and without
Jacobians, a whole evaluation, the gradient accumulation, the chain's and the decoder's
reverse passes and a whole gradient; then each term alone, in a tight loop. The pieces
run one after another as in an iteration, so each starts with the caches the previous
one left (the decoder's 3.6 MB of weights evict most else): the minimum, not the sum of
hot-loop figures, is what an iteration pays.
"""

from __future__ import annotations

import sys
import time

import numpy as np
import torch
from threadpoolctl import threadpool_limits

import engine.solver.optimizer as opt
from engine.constraints.residual import NUMPY
from engine.constraints.term_stack import TermStack
from engine.methods.dragposer import DragPoserMethod
from engine.models import load_default_models
from engine.motion.retarget import load_motion
from engine.solver.frame import SolveTimings
from engine.tracking import simulate


def _objective(sensors: str):
    """The fast objective and start latent of frame 20 of the bundled clip."""
    motion = load_motion("assets/clips/example.bvh")
    tracking = simulate(motion, sensors)
    models = load_default_models()
    m = DragPoserMethod(models.vae, models.predictor, iterations=10)
    m.reset(motion.skeleton, motion.fps)
    captured = {}
    run = opt.PoseOptimizer._run

    def spy(self, obj, z0, *a, **k):
        captured["obj"], captured["z"] = obj, z0
        return run(self, obj, z0, *a, **k)

    opt.PoseOptimizer._run = spy  # type: ignore[method-assign]
    for i in range(21):
        m.step(tracking.frame(i))
    opt.PoseOptimizer._run = run  # type: ignore[method-assign]
    return captured["obj"], captured["z"]


def _timed(f) -> int:
    c = time.thread_time_ns()
    f()
    return time.thread_time_ns() - c


def main() -> None:
    sensors = sys.argv[1] if len(sys.argv) > 1 else "6"
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
    torch.set_num_threads(1)
    obj, z = _objective(sensors)
    timings = SolveTimings()
    obj.evaluate(z, timings)
    obj.gradient()
    out = obj.decoder.forward(z)
    g_out = obj.chain.backward(np.zeros_like(obj.P), np.zeros_like(obj.P))
    gen = np.random.default_rng(0)
    gp, gr = gen.random(obj.P.shape), gen.random(obj.P.shape)

    def terms(jac: bool) -> None:
        for t in obj.terms:
            t.residual(NUMPY, obj.P, obj.W, obj.z, jac=jac)

    def gradients() -> None:
        obj.stack.gradients(obj.res, obj.r, obj.weights[None], obj.z.shape[1], obj.chain.unorder)

    pieces = {
        "decoder fwd": lambda: obj.decoder.forward(z),
        "chain fwd": lambda: obj.chain.forward(out[None], obj.root),
        "terms jac": lambda: terms(True),
        "terms nojac": lambda: terms(False),
        "evaluate": lambda: obj.evaluate(z, timings),
        "gradients": gradients,
        "chain bwd": lambda: obj.chain.backward(gp, gr),
        "decoder bwd": lambda: obj.decoder.backward(g_out[0]),
        "gradient": obj.gradient,
    }
    print("terms:", [type(t).__name__ for t in obj.terms])
    spent: dict[str, list[int]] = {k: [] for k in pieces}
    with threadpool_limits(1):
        for _ in range(repeats):
            for k, f in pieces.items():
                spent[k].append(_timed(f))
        for k, v in spent.items():
            print(f"{k:14s} min {np.min(v) / 1e3:7.1f} med {np.median(v) / 1e3:7.1f} us")
        print("each term alone, tight loop (min us): residual with Jacobians, gradients, losses")
        per_term = np.split(obj.weights, np.cumsum([len(t.names) for t in obj.terms])[:-1])
        for t, w in zip(obj.terms, per_term):
            jac, acc, loss = [], [], []
            one = TermStack([t])
            for _ in range(repeats):
                res = t.residual(NUMPY, obj.P, obj.W, obj.z, jac=True)
                jac.append(_timed(lambda t=t: t.residual(NUMPY, obj.P, obj.W, obj.z, jac=True)))
                r = one.stack([res])
                acc.append(_timed(lambda one=one, w=w, res=res, r=r: one.gradients([res], r, w[None], obj.z.shape[1])))
                loss.append(_timed(lambda t=t, res=res: t.losses(res)))
            print(
                f"  {type(t).__name__:12s} {np.min(jac) / 1e3:6.1f} {np.min(acc) / 1e3:6.1f} {np.min(loss) / 1e3:6.1f}"
            )


if __name__ == "__main__":
    main()
