"""Is a VAE training step cheaper than at revision REV? Interleaved A/B of the shipped
recipe's step (batch 256, limb mix 0.5, bone scale 0.15, continuity loss), each version in
its own process on the same prepared split, reporting CPU and wall milliseconds per step and
the total loss after the same steps (the same random stream: it must agree closely).

    PYTHONPATH=. python research/train_step_ab.py --data prepared [--baseline 1f2a60e]
        [--steps 40] [--threads 1] [--rounds 3] [--split val]

CPU time at one thread is the figure to read on a busy machine; wall time at two threads
only on an idle one.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from research.ab_versions import ROOT, checkout

STEP = r"""
import inspect, json, sys, time, tomllib
import torch
torch.set_num_threads(int(sys.argv[3]))
from engine.training import vae as V
from engine.training.data import load_split, read_manifest
from engine.models.vae import PoseVAE
keys = V.VAETrainConfig.__dataclass_fields__
cfg = V.VAETrainConfig(**{k: v for k, v in tomllib.load(open(sys.argv[5], "rb")).items() if k in keys})
cfg.bone_scale = 0.15
data = load_split(sys.argv[1], sys.argv[4])
one_pass = "bone_scale" in inspect.signature(V.batch_of).parameters
torch.manual_seed(0)
vae = PoseVAE(cfg.model_config(), read_manifest(sys.argv[1])["stats"])
objective = V.VAEObjective(vae, cfg)
opt = torch.optim.AdamW(vae.parameters(), lr=1e-4, weight_decay=1e-4, fused=one_pass)
pairs = torch.nonzero(data.has_next).squeeze(1)
gen = torch.Generator().manual_seed(0)
steps, warm = int(sys.argv[2]), 3
for i in range(steps + warm):
    if i == warm:
        cpu, wall = time.process_time(), time.perf_counter()
    idx = pairs[torch.randint(len(pairs), (cfg.batch_size,), generator=gen)]
    if one_pass:
        b = V.batch_of(data, idx, cfg.limb_mix, gen, pairs, cfg.bone_scale)
    else:
        b = V.scale_bones(V.batch_of(data, idx, cfg.limb_mix, gen, pairs), cfg.bone_scale, gen)
    losses = objective(b)
    opt.zero_grad(set_to_none=True)
    losses["total"].backward()
    opt.step()
    values = [float(v.detach()) for v in losses.values()]
print(json.dumps({"cpu_ms": 1000 * (time.process_time() - cpu) / steps,
                  "wall_ms": 1000 * (time.perf_counter() - wall) / steps, "loss": values[-1]}))
"""


def run(root: Path, args) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root), OMP_NUM_THREADS=str(args.threads))
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            STEP,
            str(args.data),
            str(args.steps),
            str(args.threads),
            args.split,
            str(ROOT / "assets/models/vae.toml"),
        ],
        env=env,
        check=True,
        capture_output=True,
        text=True,
        cwd=root,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=Path("prepared"))
    ap.add_argument("--baseline", default="1f2a60e", help="git revision to compare with (default: %(default)s)")
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--split", default="val", help="prepared split to draw batches from (default: %(default)s)")
    args = ap.parse_args()
    args.data = args.data.resolve()  # each version runs in its own folder
    with tempfile.TemporaryDirectory() as tmp:
        versions = {"baseline": checkout(args.baseline, Path(tmp)), "tree": ROOT}
        rows: dict[str, list[dict]] = {k: [] for k in versions}
        for r in range(args.rounds):
            for name, root in versions.items():
                rows[name].append(run(root, args))
                print(
                    f"round {r + 1} {name:8s} " + " ".join(f"{k}={v:.8g}" for k, v in rows[name][-1].items()),
                    flush=True,
                )
    med = {k: sorted(x["cpu_ms"] for x in v)[len(v) // 2] for k, v in rows.items()}
    print(
        f"median CPU ms/step: baseline {med['baseline']:.1f}, tree {med['tree']:.1f}, "
        f"ratio {med['baseline'] / med['tree']:.2f}x"
    )


if __name__ == "__main__":
    main()
