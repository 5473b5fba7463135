"""How far real poses with both hands overhead lean the trunk, against all poses, and how
far the pose-mode benchmark's hands-overhead results are from the nearest of them.

Every ``--stride``-th file of the shared data's train and val splits (``data prepare``'s
rule; ``test`` files left out), every 4th frame and its mirror image, laid out on the
benchmark's character (:mod:`engine.authoring.pose_reference`). *Arms up*: both wrists
at least ``--above`` metres above the head joint (``upperneck``). *Lean*: the
pelvis-to-head-joint line's angle from vertical in the body's sagittal plane, degrees,
positive forward. Training poses are included, so the distances favour the VAE's poses
(its decoder learned them); the lean figures are the data's own.

    PYTHONPATH=. python research/arms_up_lean.py [--stride 3] [--above 0.15]
"""

import argparse
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.authoring import pose_reference as R
from engine.authoring.pose_mode import PoseMode
from engine.authoring.pose_tasks import run_task, select_tasks
from engine.cli.data import DEFAULT_DATA
from engine.data.prepare import EVAL_ONLY, discover, split_files
from engine.models import load_default_models
from engine.motion.retarget import CURRENT, load_with_report, manifest_fps

parser = argparse.ArgumentParser()
parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
parser.add_argument("--stride", type=int, default=3, help="every Nth file (default 3)")
parser.add_argument("--above", type=float, default=0.15, help="wrists above the head joint, metres")
args = parser.parse_args()
J = sk.JOINT_INDEX
vae = load_default_models().vae
offsets = PoseMode(vae).character.skeleton.offsets
files = discover([args.data])
splits, takes = split_files(files, list(EVAL_ONLY))
use = [(p, r) for p, r in files if splits[r] != "test"][:: args.stride]
clips = [
    (str(takes.get(r) or p), load_with_report(p, manifest_fps(p), None, strategy=CURRENT)[0].local_rot) for p, r in use
]
ref = R.ReferenceSet.from_rotations(clips, offsets, 4, True, f"every {args.stride}th non-test file")


def lean_deg(aligned: np.ndarray) -> np.ndarray:
    head = aligned[..., J["upperneck"] - 1, :]  # aligned poses face -Y and have no root row
    return np.degrees(np.arctan2(-head[..., 1], head[..., 2]))


P = ref.poses
head_z = P[:, J["upperneck"] - 1, 2]
up = (P[:, J["lwrist"] - 1, 2] > head_z + args.above) & (P[:, J["rwrist"] - 1, 2] > head_z + args.above)
lean = lean_deg(P)
print(f"{len(use)} files, {len(P)} poses; arms up: {up.sum()} poses of {len(set(ref.takes[up]))} takes")
for name, m in (("all poses", np.ones(len(P), bool)), ("arms up", up)):
    print(f"  {name}: lean percentiles 5/25/50/75/95 = {np.round(np.percentile(lean[m], [5, 25, 50, 75, 95]), 1)} deg")
for k in sorted(set(ref.takes[up])):
    m = up & (ref.takes == k)
    print(f"    {Path(ref.names[k]).name:>12}: {m.sum():4d} poses, median lean {np.median(lean[m]):6.1f} deg")
task = select_tasks(["hands_overhead"])[0]
for poser, opts in (("pose-mode", []), ("pose-mode", ["keep_trunk=true"]), ("ik", [])):
    q = R.aligned(np.array(run_task(task, poser, vae, ref, opts).positions))
    d = R.pose_distances(q[None], P)[0]
    print(
        f"hands_overhead {poser} {' '.join(opts)}: lean {float(lean_deg(q)):.1f} deg, "
        f"{100 * d.min():.2f} cm from the nearest pose, {100 * d[up].min():.2f} cm from the nearest arms-up pose"
    )
