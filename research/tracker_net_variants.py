"""Variants of the tracker networks, trained and run in the realtime solver in one process.

    PYTHONPATH=. python research/tracker_net_variants.py FILE... [--sensors 4] [--max-frames 600]
        [--history 8] [--seeds 1] [--setting both] [--data prepared] [--epochs 20]

Trains the network of the preset's combination as ``train tracker-net`` does, with
``--history`` instants (4 frames apart) instead of 8 and, with ``--seeds N``, N networks
from different seeds whose latents are averaged (an ensemble), then runs DragPoser realtime
on each file with that network in place of the shipped one (``tracker_prior`` =
``--setting``) and prints Pos cm / Rot deg / jitter over all frames. The shipped networks'
row comes from the same loop with ``--seeds 0``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.methods import dragposer_parts as DPP  # noqa: E402
from engine.solver import tracker_net as TN  # noqa: E402
from engine.solver import tracker_prior as TP  # noqa: E402


class Ensemble(TN.TrackerNet):
    """The mean latent of several networks of one combination."""

    def __init__(self, nets: list[TN.TrackerNet]) -> None:
        first = nets[0]
        super().__init__(first.joints, first.mean, first.std, first.weights, first.biases)
        object.__setattr__(self, "members", nets)

    def forward(self, x: np.ndarray) -> np.ndarray:
        return np.mean([TN.TrackerNet.forward(n, x) for n in self.members], axis=0)


def set_history(h: int) -> None:
    """Every module that reads the window's length, at ``h`` instants."""
    TN.HISTORY, TN.WINDOW = h, TP.LAG * h + 1
    DPP.WINDOW = TN.WINDOW
    import engine.training.tracker_net as TT

    TT.WINDOW = TN.WINDOW


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--history", type=int, default=8)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--setting", default="both")
    ap.add_argument("--data", default="prepared")
    ap.add_argument("--epochs", type=int, default=20)
    args = ap.parse_args()
    from engine.methods import get_method, run_method
    from engine.metrics import evaluate_motion
    from engine.models import load_default_models
    from engine.motion.retarget import load_motion
    from engine.tracking import parse_sensors, simulate
    from engine.training.tracker_net import load_takes, samples, train_net

    set_history(args.history)
    joints = TP.combination(s.joint for s in parse_sensors(args.sensors) if s.dof == 6)
    shipped = TN.default_tracker_nets()
    nets = dict(shipped.nets) if shipped is not None else {}
    if args.seeds:
        takes = load_takes(Path(args.data), "train", load_default_models().vae)
        x, z = samples(takes, joints)
        members = [train_net(joints, x, z, epochs=args.epochs, seed=s) for s in range(args.seeds)]
        nets[joints] = members[0] if len(members) == 1 else Ensemble(members)
    TN.default_tracker_nets.cache_clear()
    TN.default_tracker_nets = lambda vae_path=None: TN.TrackerNets(nets)  # type: ignore[assignment]
    import engine.methods.dragposer as DP

    DP.default_tracker_nets = TN.default_tracker_nets
    rows = []
    for f in args.files:
        m = load_motion(f, max_frames=args.max_frames)
        method = get_method("dragposer", mode="realtime", tracker_prior=args.setting)
        rec, _ = run_method(method, simulate(m, args.sensors), m.skeleton, progress=False, reference=m)
        e = evaluate_motion(m, rec)
        rows.append((e["frames"], e["pos_cm"], e["rot_deg"], e["jitter"]))
    t = np.array(rows)
    w = t[:, 0] / t[:, 0].sum()
    print(
        f"history {args.history} seeds {args.seeds} {args.setting} {args.sensors}: "
        f"pos {(w * t[:, 1]).sum():.3f} rot {(w * t[:, 2]).sum():.2f} jitter {(w * t[:, 3]).sum():.2f}",
        flush=True,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
