"""Ablation: how far would a perfect temporal predictor take a sparse sensor set?

The temporal prior pulls each frame's latent towards the predictor's latent
(``temporal_weight``). This script replaces the shipped predictor by an *oracle* that
returns the ground truth's own latents (the VAE encoder's mean of the true poses,
:class:`engine.methods.autoencoder.AutoencoderMethod`) for the predictor steps it is
asked for, and reconstructs the same clips and trackers with the same solver. The
oracle cheats on purpose: the gap between its error and the shipped predictor's is what
a better predictor could still gain; what is left with the oracle is the solver's and
the VAE's share.

    PYTHONPATH=. python research/oracle_prior.py FILE... --sensors 4 [--max-frames 150]
        [--weights 0.01,0.1,1,10] [--future 16] [--predictors shipped,oracle] [--json out.json]

Prints, per temporal weight, Pos / Rot / EE over all files with the shipped predictor
and with the oracle.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.solver import temporal  # noqa: E402


class OraclePredictor:
    """A :class:`~engine.solver.temporal.LatentPredictor` that answers with the true latents.

    ``latents (F, L)``: the encoder's mean of every frame of the clip; ``every``: frames
    per predictor step. The step a run starts at is set by :func:`_tracking_runs`."""

    def __init__(self, latents: np.ndarray, every: int) -> None:
        self.latents = torch.as_tensor(latents, dtype=torch.float32)
        self.every = every
        self.first_step = 0

    def predict(self, past_latents, past_cond, first, steps: int) -> torch.Tensor:
        frames = [min(self.every * (self.first_step + s), len(self.latents) - 1) for s in range(steps)]
        return self.latents[frames][None]


def _tracking_runs() -> None:
    """Tell an oracle which predictor step each run starts at (the protocol does not)."""
    piece = temporal._Run.piece

    def tracked(self, cache):
        if isinstance(self.predictor, OraclePredictor):
            self.predictor.first_step = self.first_step
        return piece(self, cache)

    temporal._Run.piece = tracked


def true_latents(motion) -> np.ndarray:
    """Encoder means ``(F, L)`` of the clip's true poses (shipped VAE)."""
    from engine.methods.autoencoder import AutoencoderMethod

    ae = AutoencoderMethod()
    ae.reset(motion.skeleton, reference=motion)
    return ae._latent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--mode", default="realtime")
    ap.add_argument("--max-frames", type=int, default=150)
    ap.add_argument("--weights", default="0.01,0.1,1,10")
    ap.add_argument("--future", type=int, default=16)
    ap.add_argument("--predictors", default="shipped,oracle", help="which to run, comma-separated")
    ap.add_argument("--json")
    args = ap.parse_args()

    from engine.methods import get_method, run_method
    from engine.metrics import evaluate_motion
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    _tracking_runs()
    clips = [load_motion(f, max_frames=args.max_frames) for f in args.files]
    truths = [true_latents(m) for m in clips]
    out = {}
    for w in (float(x) for x in args.weights.split(",")):
        for name in args.predictors.split(","):
            method = get_method("dragposer", mode=args.mode)
            # the predictor must be the prior: the profiles' tracker prior would replace it
            method.configure(temporal_weight=w, future_window=args.future, prior="predictor")
            shipped = method.predictor
            rows = []
            for motion, lat in zip(clips, truths):
                method.predictor = (
                    shipped if name == "shipped" else OraclePredictor(lat, method.settings.predictor_every)
                )
                rec, _ = run_method(
                    method, simulate(motion, args.sensors), motion.skeleton, progress=False, reference=motion
                )
                rows.append((len(motion), evaluate_motion(motion, rec)))
            n = sum(k for k, _ in rows)
            agg = {key: sum(k * r[key] for k, r in rows) / n for key in ("pos_cm", "rot_deg", "ee_cm")}
            out[f"{name} w={w:g}"] = agg
            print(
                f"{name:<8} temporal_weight {w:<6g} Pos {agg['pos_cm']:6.2f} cm  Rot {agg['rot_deg']:5.1f} deg  "
                f"EE {agg['ee_cm']:6.2f} cm",
                flush=True,
            )
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
