"""Where a clean and a perturbed DragPoser run part, and which solve input carries it.

    PYTHONPATH=. python research/offline_divergence.py FILE.bvh [--mode offline] [--max-frames 200]
        [--sensors 3-head-hands] [--noise 1e-6] [--seed 1] [--jump 0.01]

Reconstructs the clip from clean simulated trackers and from trackers moved by
N(0, ``--noise``) metres, recording every frame's solve inputs. It prints how many frames
stopped at the iteration cap in each run and on how many the two runs took different
iteration counts (a stopping rule that flips on a tiny change shows there), how far apart
the two runs' latents and poses are (first frame beyond 1e-4, 1e-3, 1e-2 latent units;
mean and worst pose distance, cm), and at the first frame where one solve turns a latent
difference below ``--jump`` into one above it, re-solves that frame from the clean run's
inputs with one of the perturbed run's inputs swapped in at a time (start latent, context
pieces, tracker targets) and along a fraction of the start difference, with the iteration cap
and the update rule varied: the input whose swap reproduces the jump carries it.
Development diagnostic (docs/optimizer.md, "Stability with head and hands").
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def record(motion, preset: str, mode: str, noise: float, seed: int) -> dict:
    """One reconstruction with every solve's inputs (start, context, targets, settings)."""
    from engine.methods import get_method
    from engine.tracking import simulate

    tracking = simulate(motion, preset, noise_pos_m=noise, seed=seed)
    method = get_method("dragposer", mode=mode)
    method.reset(motion.skeleton, tracking.fps)
    opt, real, inputs = method.optimizer, method.optimizer.solve, []

    def solve(start, terms, ctx, settings=None):
        inputs.append(
            {
                "start": start.clone(),
                "ctx": ctx,
                "settings": settings or opt.settings,
                "targets": {
                    c.name: (c.position.copy(), None if c.rotation is None else c.rotation.copy())
                    for c in terms
                    if c.kind == "sensor"
                },
                # the smoothing target moves with the history: keep this frame's
                "smooth": (method.smooth.weight, method.smooth.target.copy()),
                # so do the gait term's targets (planned from the travel so far), when it is in the solve
                "gait": (method.gait.weight, method.gait.targets) if any(c is method.gait for c in terms) else None,
            }
        )
        return real(start, terms, ctx, settings)

    opt.solve = solve
    results = [method.step(tracking.frame(i)) for i in range(len(tracking))]
    return {
        "method": method,
        "inputs": inputs,
        "latent": np.stack([r.latent for r in results]),
        "positions": np.stack([r.positions for r in results]),
        "iterations": np.array([r.iterations for r in results]),
    }


def resolve(method, inputs: dict, start=None, ctx=None, targets=None, **settings):
    """Solve one frame with ``method``'s optimizer from the recorded ``inputs``, optionally
    replacing the start latent, the context, the targets or settings; returns the latent."""
    opt = method.optimizer
    terms = [*method.sensors.values(), method.prior, method.smooth, method.ground, *method.constraints]
    for c in method.sensors.values():
        c.position, rotation = (targets or inputs["targets"])[c.name]
        if rotation is not None:
            c.rotation = rotation
    method.smooth.weight, method.smooth.target = inputs["smooth"][0], inputs["smooth"][1].copy()
    if inputs["gait"] is not None:
        method.gait.weight = inputs["gait"][0]
        method.gait.set_targets(inputs["gait"][1])
        terms.append(method.gait)
    sol = type(opt).solve(
        opt,
        inputs["start"] if start is None else start,
        terms,
        inputs["ctx"] if ctx is None else ctx,
        dataclasses.replace(inputs["settings"], **settings),
    )
    return sol.latent.numpy().astype(np.float64), sol.losses[-1]["total"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file")
    ap.add_argument("--mode", default="offline", choices=("realtime", "offline"))
    ap.add_argument("--max-frames", type=int, default=200)
    ap.add_argument("--sensors", default="3-head-hands")
    ap.add_argument("--noise", type=float, default=1e-6)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jump", type=float, default=0.01, help="latent difference that counts as parted")
    args = ap.parse_args()

    import torch

    from engine.motion.retarget import load_motion

    motion = load_motion(args.file, max_frames=args.max_frames or None)
    a = record(motion, args.sensors, args.mode, 0.0, 0)
    b = record(motion, args.sensors, args.mode, args.noise, args.seed)
    cap = a["inputs"][-1]["settings"].steps_cap()
    print(
        f"{Path(args.file).parent.name}/{Path(args.file).stem}, {args.mode}, {len(a['latent'])} frames, "
        f"noise {args.noise:g} m: frames at the cap ({cap}) {np.mean(a['iterations'] == cap):.0%} / "
        f"{np.mean(b['iterations'] == cap):.0%}; frames with different iteration counts "
        f"{int(np.sum(a['iterations'] != b['iterations']))}"
    )
    dlat = np.abs(a["latent"] - b["latent"]).max(-1)
    apart = np.linalg.norm(a["positions"] - b["positions"], axis=-1).mean(-1) * 100.0
    first = {t: (int(np.argmax(dlat > t)) if (dlat > t).any() else None) for t in (1e-4, 1e-3, 1e-2)}
    print(
        f"latent difference: first frame above {', '.join(f'{t:g}: {f}' for t, f in first.items())}; "
        f"max {dlat.max():.3f}, mean {dlat.mean():.3f}; poses apart: mean {apart.mean():.3f} cm, "
        f"worst frame {apart.max():.2f} cm"
    )
    starts = np.array([np.abs(x["start"].numpy() - y["start"].numpy()).max() for x, y in zip(a["inputs"], b["inputs"])])
    jumps = np.nonzero((starts < args.jump) & (dlat >= args.jump))[0]
    if not len(jumps):
        print(f"no solve turns a start difference below {args.jump:g} into one above it")
        return 0
    k = int(jumps[0])
    method, ia, ib = a["method"], a["inputs"][k], b["inputs"][k]
    ref, ref_loss = resolve(method, ia)
    if np.abs(ref - a["latent"][k]).max() > 1e-6:
        print(f"frame {k}: re-solving the clean run's inputs did not reproduce its latent; no swap analysis")
        return 1
    print(
        f"frame {k}: start latents {starts[k]:.2e} apart, solved latents {dlat[k]:.2e}; re-solved from the "
        f"clean inputs with ... swapped in (latent difference to the clean solve, final loss):"
    )

    def show(label: str, out) -> None:
        lat, loss = out
        print(f"  {label:<34} {np.abs(lat - ref).max():.2e}  {loss:.5e}")

    show("nothing (clean)", (ref, ref_loss))
    show("everything", resolve(method, ia, ib["start"], ib["ctx"], ib["targets"]))
    show("start latent", resolve(method, ia, start=ib["start"]))
    show("tracker targets", resolve(method, ia, targets=ib["targets"]))
    for name in ("previous_root", "root_anchor", "previous_positions", "prediction"):
        show(
            f"context {name}",
            resolve(method, ia, ctx=dataclasses.replace(ia["ctx"], **{name: getattr(ib["ctx"], name)})),
        )
    d = ib["start"] - ia["start"]
    for f in (0.1, 0.01):
        show(f"{f:g} x the start difference", resolve(method, ia, start=ia["start"] + f * d))
    g = np.random.default_rng(0).standard_normal(d.shape[0]).astype(np.float32)
    show(
        "a random start change as large",
        resolve(method, ia, start=ia["start"] + float(d.abs().max()) * torch.from_numpy(g / np.abs(g).max())),
    )
    print("  the start latent swapped in, with:")
    for label, kw in (
        (f"{4 * cap} iterations", {"max_iterations": 4 * cap, "iterations": 4 * cap}),
        ("optimizer adam", {"optimizer": "adam"}),
        ("momentum 0.9", {"momentum": 0.9}),
    ):
        base, _ = resolve(method, ia, **kw)
        lat, loss = resolve(method, ia, start=ib["start"], **kw)
        print(f"    {label:<32} {np.abs(lat - base).max():.2e}  {loss:.5e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
