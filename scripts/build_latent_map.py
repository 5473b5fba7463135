"""Build the latent map (engine/latent/projection.py) shipped as assets/models/latent_map.npz.

The 2D PCA and the density grid are fitted on the pose bank's latents (the shipped VAE
encoder's means of every 4th training frame). The flag rule's thresholds come from poses
the models never saw: the encoder's latents of every ``--stride``-th frame of the
validation files (``engine.authoring.pose_reference.VALIDATION_FILES``); each threshold
is the ``--quantile`` of their distance to the nearest bank latent and of their norm.

    PYTHONPATH=. python scripts/build_latent_map.py --out assets/models/latent_map.npz
        [--bank assets/models/pose_bank.npz] [--vae assets/models/vae.pt] [--stride 4] [--quantile 0.99]
        [--mocap ../shared/data/mocap]

Prints the explained variance, the thresholds and the time taken.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.input_files import file_sha256  # noqa: E402
from engine.latent.projection import fit_map, with_thresholds  # noqa: E402
from engine.latent.readouts import DEFAULT_BANK, NearestLatents, bank_latents  # noqa: E402


def encode_motion(vae, motion) -> np.ndarray:
    """The VAE encoder's mean latents ``(F, L)`` of a clip's true poses."""
    import torch

    from engine.kinematics.features import encoder_input, pose_from_motion

    local = torch.as_tensor(motion.local_rot, dtype=torch.float64)
    root = torch.as_tensor(motion.root_pos, dtype=torch.float64)
    offsets = torch.as_tensor(motion.skeleton.offsets, dtype=torch.float64)
    rot, disp = pose_from_motion(local, root)
    dq = encoder_input(rot, disp, offsets.expand(rot.shape[0], -1, -1)).float()
    with torch.no_grad():
        mu, _ = vae.encode(dq)
    return mu.double().numpy()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--bank", type=Path, default=DEFAULT_BANK)
    p.add_argument("--vae", type=Path, default=Path(__file__).resolve().parent.parent / "assets" / "models" / "vae.pt")
    p.add_argument("--stride", type=int, default=4, help="every N-th validation frame (default 4)")
    p.add_argument(
        "--mocap",
        type=Path,
        default=Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "mocap",
        help="folder holding the validation files (default: ../shared/data/mocap)",
    )
    p.add_argument("--quantile", type=float, default=0.99, help="threshold quantile over unseen poses (default 0.99)")
    args = p.parse_args()
    t0 = time.perf_counter()
    from engine.authoring.pose_reference import validation_files
    from engine.models.loading import load_vae
    from engine.motion.retarget import load_motion

    bank = bank_latents(args.bank)
    m = fit_map(bank, vae_sha256=file_sha256(args.vae))
    vae, _ = load_vae(args.vae)
    unseen = np.concatenate([encode_motion(vae, load_motion(f))[:: args.stride] for f in validation_files(args.mocap)])
    nearest, _ = NearestLatents(bank).query(unseen)
    norms = np.linalg.norm(unseen, axis=1)
    m = with_thresholds(m, np.quantile(nearest, args.quantile), np.quantile(norms, args.quantile))
    m.save(args.out)
    print(
        f"wrote {args.out}: {len(bank)} bank latents, explained variance {m.explained[0]:.3f} + "
        f"{m.explained[1]:.3f} = {m.explained.sum():.3f}"
    )
    q = (0.5, 0.9, 0.99)
    print(
        f"unseen poses: {len(unseen)} (validation files, every {args.stride}th frame); nearest-bank distance "
        f"p50/p90/p99 {' / '.join(f'{v:.3f}' for v in np.quantile(nearest, q))}, norm p50/p90/p99 "
        f"{' / '.join(f'{v:.3f}' for v in np.quantile(norms, q))}"
    )
    print(
        f"thresholds (quantile {args.quantile}): nearest {m.nn_threshold:.3f}, norm {m.norm_threshold:.3f}; "
        f"{time.perf_counter() - t0:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
