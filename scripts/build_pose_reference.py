"""Build the pose benchmark's reference poses shipped as assets/reference/validation_poses.npz.

The naturalness measure of ``bench --pose-tasks`` (engine/authoring/pose_reference.py)
compares a pose with real poses of the 9 validation files (all CMU: ``cmu_daz/`` and
``cmu_iclone/``). This stores their canonical local rotations, every ``--stride``-th
frame, so the installed package reads no motion data beside it. Provenance and licence:
assets/README.md.

    PYTHONPATH=. python scripts/build_pose_reference.py --mocap ../shared/data/mocap \\
        --out assets/reference/validation_poses.npz [--stride 4]

Regenerate it whenever ``RETARGET_VERSION`` changes (the file records the version).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.atomic import atomic_path  # noqa: E402
from engine.authoring.pose_reference import STRIDE, VALIDATION_FILES, validation_files  # noqa: E402
from engine.input_files import file_sha256  # noqa: E402

REPO = Path(__file__).resolve().parent.parent


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument(
        "--mocap",
        type=Path,
        default=REPO.parent / "shared" / "data" / "mocap",
        help="folder holding the validation files (default: ../shared/data/mocap)",
    )
    p.add_argument("--out", type=Path, default=REPO / "assets" / "reference" / "validation_poses.npz")
    p.add_argument("--stride", type=int, default=STRIDE, help=f"every N-th frame (default {STRIDE})")
    args = p.parse_args()
    from engine.motion.retarget import load_motion
    from engine.motion.retarget_strategy import RETARGET_VERSION

    rots, takes, shas = [], [], []
    for i, path in enumerate(validation_files(args.mocap)):
        local = load_motion(path).local_rot[:: args.stride]
        rots.append(local.astype(np.float32))
        takes.append(np.full(len(local), i, np.int16))
        shas.append(file_sha256(path))
    with atomic_path(args.out, suffix=".npz") as tmp:
        np.savez_compressed(
            tmp,
            local_rot=np.concatenate(rots),
            take=np.concatenate(takes),
            names=np.array(VALIDATION_FILES),
            source_sha256=np.array(shas),
            stride=np.int64(args.stride),
            retarget_version=np.int64(RETARGET_VERSION),
        )
    print(
        f"wrote {args.out}: {sum(len(r) for r in rots)} poses of {len(rots)} files, every {args.stride}th frame, "
        f"retarget version {RETARGET_VERSION}, {args.out.stat().st_size / 1e3:.0f} kB"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
