"""The tracker networks against the pose bank's neighbours as the prior alone, no solver.

Each frame's prior latent (the bank's mean latent of 24 neighbours, or the tracker network
of the combination, engine/solver/tracker_net.py) is decoded and put on the true root, as
``legs_prior_proxy.py bank`` screens bank variants; printed is the mean error of the leg
joints and of all joints, cm, on the given files (first ``--max-frames`` frames) and on
the first ``--val-clips`` clips of the validation split of ``--data``.

    PYTHONPATH=. python research/learned_prior.py FILE... [--sensors 4] [--max-frames 600]
        [--nets assets/models/tracker_nets.npz] [--val-clips 40] [--data prepared]

This screen is where the networks started (docs/accuracy.md, "A tracker network as the
prior"): with preset ``4`` on the ``dragposer/`` clips it gave legs / all 12.77 / 8.47 cm
for the bank and 10.74 / 5.98 for the network; on 40 validation clips 9.28 / 5.48 and
7.06 / 3.67.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.kinematics.fk import fk  # noqa: E402
from engine.motion.clip import Motion  # noqa: E402
from engine.solver import tracker_prior as TP  # noqa: E402
from engine.solver.tracker_net import WINDOW, TrackerNet, TrackerNets  # noqa: E402
from research.legs_prior_proxy import LEGS, Variant, _clips, prior_errors  # noqa: E402


class NetVariant:
    """A tracker network behind ``prior_errors``'s interface (``joints``, ``history()``, ``latents``)."""

    def __init__(self, net: TrackerNet) -> None:
        self.net, self.joints = net, net.joints

    def history(self) -> int:
        return WINDOW - 1

    def latents(self, pos: np.ndarray, rot: np.ndarray, k: int) -> torch.Tensor:
        return torch.from_numpy(self.net.latents(pos, rot))


def val_clips(data: Path, n: int, sensors: str):
    from engine.tracking import simulate

    man = json.loads((data / "manifest.json").read_text())
    out = []
    for entry in [e for e in man["files"] if e["split"] == "val" and not e["mirrored"]][:n]:
        d = np.load(data / entry["shard"])
        m = Motion(d["local_rot"], d["root_pos"], sk.Skeleton(offsets=d["offsets"]))
        out.append((entry["source"], m, simulate(m, sensors), fk(m.local_rot, m.root_pos, m.skeleton.offsets)[0]))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--nets", default="assets/models/tracker_nets.npz")
    ap.add_argument("--val-clips", type=int, default=40)
    ap.add_argument("--data", default="prepared")
    args = ap.parse_args()
    from engine.models import load_default_models

    vae, bank = load_default_models().vae, TP.default_bank()
    if bank is None:
        raise SystemExit("no shipped pose bank for the shipped VAE")
    clips = _clips(args.files, args.max_frames, args.sensors)
    joints = tuple(j for j in clips[0][2].joints if j in TP.BANK_JOINTS)
    net = TrackerNets.load(args.nets).get(joints)
    if net is None:
        raise SystemExit(f"{args.nets}: no network for {joints}")
    sets = [("files", clips), ("CMU validation clips", val_clips(Path(args.data), args.val_clips, args.sensors))]
    print(f"{'set':<24} {'prior':<20} {'legs cm':>8} {'all cm':>7}")
    for name, cs in sets:
        for label, variant in (("bank, 24 neighbours", Variant(bank, joints=joints)), ("network", NetVariant(net))):
            e = prior_errors(cs, variant, vae, 24)
            print(f"{name:<24} {label:<20} {e[:, LEGS].mean():8.2f} {e.mean():7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
