"""A ``data prepare`` folder with only the validation split, for the pose-mode benchmark's
naturalness reference (``bench --pose-tasks --reference-data OUT``) without preparing the
training shards: the same split rule (:func:`engine.data.prepare.split_files`), the same
retargeting and mirrored copies, shards holding the local rotations only (all the
reference reads). With the shared data of this checkout: 50 files, 12 394 poses, spread
median 5.2 cm, 95th percentile 12.7 cm, as a full ``data prepare`` folder's val split.

    PYTHONPATH=. python research/pose_val_reference.py OUT [--data ../shared/data]
"""

import argparse
import json
from pathlib import Path

import numpy as np

from engine.cli.data import DEFAULT_DATA
from engine.data.prepare import EVAL_ONLY, _shard_name, discover, split_files
from engine.kinematics.features import mirror_motion
from engine.motion.retarget import CURRENT, load_with_report, manifest_fps

parser = argparse.ArgumentParser()
parser.add_argument("out", type=Path)
parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
args = parser.parse_args()
(args.out / "shards").mkdir(parents=True, exist_ok=True)
files = discover([args.data])
splits, takes = split_files(files, list(EVAL_ONLY))
entries = []
for path, rel in files:
    if splits[rel] != "val":
        continue
    motion, _ = load_with_report(path, manifest_fps(path), None, strategy=CURRENT)
    for mirrored in (False, True):
        rot = motion.local_rot
        if mirrored:
            rot = mirror_motion(motion.local_rot, motion.root_pos, motion.skeleton.offsets)[0]
        shard = "shards/" + _shard_name(rel, mirrored)
        np.savez(args.out / shard, local_rot=np.asarray(rot, np.float32))
        entries.append(
            {
                "source": rel,
                "path": str(path),
                "split": "val",
                "take": takes.get(rel),
                "mirrored": mirrored,
                "shard": shard,
            }
        )
(args.out / "manifest.json").write_text(json.dumps({"files": entries}, indent=1))
print(f"{args.out}: {sum(not e['mirrored'] for e in entries)} val files and their mirrors")
