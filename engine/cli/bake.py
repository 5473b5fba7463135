"""``dragposer-studio bake SCENE.json --out OUT.bvh [--fps F]``: an authored scene to BVH
(or glTF, by ``--out``'s extension: docs/export.md).

Solves the scene's keys and in-betweens (:mod:`engine.authoring.bake`) headlessly and
writes the motion atomically, the same bytes the studio exports for the same scene.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from engine.cli.export_options import add_export_options, check_export, export_contents


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "bake",
        help="bake an authored scene (keys, targets, constraints) into a BVH motion",
        description="Solve the keys of SCENE.json (scene format version 2, docs/authoring.md) and "
        "their in-betweens through the pose VAE and write the motion as BVH.",
    )
    p.add_argument("scene", type=Path, metavar="SCENE.json", help="authoring scene")
    p.add_argument("--out", type=Path, required=True, metavar="OUT.bvh", help="file to write: .bvh, .glb or .gltf")
    p.add_argument("--fps", type=float, metavar="F", help="output frame rate (default: the scene's)")
    p.add_argument("--vae", type=Path, metavar="VAE.pt", help="user-trained VAE weights (default: the shipped model)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_export_options(p)
    p.set_defaults(func=_bake)


def _bake(args: argparse.Namespace) -> int:
    import torch
    from tqdm import tqdm

    from engine.authoring.bake import output_frames
    from engine.authoring.document import load_authoring
    from engine.authoring.export import bake_to_file
    from engine.models.loading import load_default_models, load_vae
    from engine.validation import check_input_file, check_output_path

    check_input_file(args.scene, "scene")
    check_output_path(args.out)
    check_export(args, [args.out])
    scene = load_authoring(args.scene)
    frames, rate, _ = output_frames(scene, args.fps)
    vae = load_vae(args.vae)[0] if args.vae else load_default_models().vae
    torch.set_num_threads(1)  # one small pose per step: more threads only add overhead
    bar = tqdm(total=frames + len(scene.keys), unit="frame", desc="bake", disable=args.no_progress, file=sys.stderr)

    def progress(done: int, total: int) -> None:
        bar.n = done
        bar.refresh()

    try:
        baked = bake_to_file(scene, vae, args.out, args.fps, progress, export_contents(args))
    finally:
        bar.close()
    print(f"{args.out}: {len(baked.motion)} frames at {rate:g} fps, {len(scene.keys)} keys")
    return 0
