"""``data prepare``: BVH folders -> retargeted, mirrored training shards + statistics.

Output layout (``--out DIR``)::

    DIR/manifest.json          inputs (path, sha256, rig, split, frames...), stats, hash
    DIR/shards/<name>.npz      one clip each: local_rot (F,22,4), root_pos (F,3), offsets (22,3)

* **Split** (deterministic, by take): the *folder rule* sorts the files of each source
  folder by path and makes every 8th one (positions 3, 11, 19, ...) ``val``, the rest
  ``train``. A file that names no take follows its folder rule. Copies of one take on
  several rigs (``cmu_trial`` in the shared manifest) always share a split: a take with
  a copy in a reference folder (:data:`REFERENCE_SOURCES`) follows that copy's folder
  rule, so those folders' validation files stay validation; the other takes are sorted
  by take key and every 8th one (positions 3, 11, ...) is ``val``. About one take in 8
  is validation. Files matching an ``--eval-only`` pattern (default ``dragposer/*``:
  those clips derive from AMASS, whose licence is non-commercial) go to ``test`` and
  are never used for training or statistics.
* **Rest frames and rates**: a leading rest frame is dropped (a profile's ``skip_frames``
  or :func:`engine.motion.retarget.rest_frame_count`), the true frame rate comes from the manifest.
* **Mirroring**: every train/val clip also gets a left/right mirrored copy.
* **Statistics**: mean/std of the encoder's root-space dual quaternions and of the
  root displacement over the train shards, accumulated as running sums, so memory does
  not grow with the corpus; the files are streamed one at a time.
* **Incremental**: a shard whose source hash and settings are unchanged is not rebuilt;
  a re-run with unchanged inputs rewrites nothing.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from engine.atomic import atomic_path, write_bytes
from engine.errors import UserError
from engine.input_files import file_sha256
from engine.kinematics.features import encoder_input, mirror_motion, pose_from_motion
from engine.motion.clip import Motion
from engine.motion.retarget import CURRENT, load_with_report, manifest_entry, manifest_fps
from engine.motion.source_file import SOURCE_SUFFIXES

FORMAT = 1
#: Bumped whenever the feature definition changes, so cached statistics are recomputed.
FEATURES_VERSION = 2
VAL_EVERY, VAL_PHASE = 8, 3
#: Source folders that defined the validation split first; a take with a copy in one of them
#: follows that copy's folder rule, so their validation takes stay validation.
REFERENCE_SOURCES = ("cmu_iclone", "cmu_daz")
#: Source folders added after the split was first drawn: a take whose every copy lies in
#: one of them is drawn from that folder's own pool (every 8th of its takes), so adding
#: the folder moves no take of the folders before it between train and validation.
LATER_SOURCES = ("cmu_asf",)
#: Evaluation-only folders by default: ``dragposer/`` derives from AMASS (non-commercial),
#: ``hdm05/`` is CC BY-SA (its ShareAlike would extend to weights trained on it).
EVAL_ONLY = ("dragposer/*", "hdm05/*")


@dataclass
class PrepareResult:
    out: Path
    written: int = 0
    reused: int = 0
    failed: list[tuple[str, str]] = field(default_factory=list)
    unchanged: bool = False


def _save_npz(path: Path, **arrays: np.ndarray) -> None:
    with atomic_path(path, suffix=".npz") as tmp:
        np.savez(tmp, **arrays)  # type: ignore[arg-type]  # numpy's stubs: **arrays could name allow_pickle


def discover(inputs: list[Path]) -> list[tuple[Path, str]]:
    """All motion files (BVH and AMC, :data:`SOURCE_SUFFIXES`) under ``inputs`` as (absolute
    path, path relative to its input root)."""
    found = []
    for root in inputs:
        if root.is_file():
            found.append((root.resolve(), root.name))
            continue
        if not root.is_dir():
            raise UserError(f"{root}: no such file or folder")
        for p in sorted(root.rglob("*")):
            if p.suffix.lower() not in SOURCE_SUFFIXES or not p.is_file():
                continue
            found.append((p.resolve(), p.relative_to(root).as_posix()))
    return found


def assign_splits(
    rel_paths: list[str],
    eval_only: list[str],
    takes: dict[str, str] | None = None,
    reference: tuple[str, ...] = REFERENCE_SOURCES,
) -> dict[str, str]:
    """Deterministic train/val/test split (see module docs).

    Parameters
    ----------
    rel_paths : list of str
        Input files, relative to their input root (``mocap/<source>/...`` or ``<source>/...``).
    eval_only : list of str
        ``fnmatch`` patterns of files that only ever go to ``test``.
    takes : dict, optional
        File -> the take it records (``cmu_trial`` of the shared manifest). Every copy of
        one take gets the same split.
    reference : tuple of str
        Source folders whose own folder rule decides the split of every take with a copy
        in them (the first in this order wins), so their validation files stay validation.

    Returns
    -------
    dict
        File -> ``"train"``, ``"val"`` or ``"test"``.
    """
    splits: dict[str, str] = {}
    folder_rule: dict[str, str] = {}
    groups: dict[str, list[str]] = {}
    for rel in rel_paths:
        if any(fnmatch.fnmatch(rel, pat) or fnmatch.fnmatch(rel, f"*/{pat}") for pat in eval_only):
            splits[rel] = "test"
            continue
        groups.setdefault(_source_folder(rel), []).append(rel)
    for members in groups.values():
        for i, rel in enumerate(sorted(members)):
            folder_rule[rel] = "val" if i % VAL_EVERY == VAL_PHASE else "train"
    copies: dict[str, list[str]] = {}
    for rel in folder_rule:
        take = (takes or {}).get(rel)
        if take:
            copies.setdefault(take, []).append(rel)
        else:
            splits[rel] = folder_rule[rel]
    rank = {src: i for i, src in enumerate(reference)}
    pooled: list[str] = []
    for take, members in copies.items():
        anchors = sorted((rank[_source_folder(r)], r) for r in members if _source_folder(r) in rank)
        if anchors:
            for r in members:
                splits[r] = folder_rule[anchors[0][1]]
        else:
            pooled.append(take)
    pools: dict[str, list[str]] = {}
    for take in pooled:
        folders = {_source_folder(r) for r in copies[take]}
        later = sorted(folders) if folders <= set(LATER_SOURCES) else []
        pools.setdefault(later[0] if later else "", []).append(take)
    for takes_in_pool in pools.values():
        for i, take in enumerate(sorted(takes_in_pool)):
            for r in copies[take]:
                splits[r] = "val" if i % VAL_EVERY == VAL_PHASE else "train"
    return splits


def split_files(files: list[tuple[Path, str]], eval_only: list[str]) -> tuple[dict[str, str], dict[str, str]]:
    """Split of discovered files, with the takes read from the shared manifest.

    Parameters
    ----------
    files : list of (Path, str)
        :func:`discover` output: absolute path and path relative to its input root.
    eval_only : list of str
        Patterns of evaluation-only files.

    Returns
    -------
    splits : dict
        Relative path -> split (:func:`assign_splits`).
    takes : dict
        Relative path -> ``cmu_trial``, for the files the manifest names a take for.
    """
    named = {rel: (manifest_entry(path) or {}).get("cmu_trial") for path, rel in files}
    takes: dict[str, str] = {rel: take for rel, take in named.items() if take}
    return assign_splits([rel for _, rel in files], eval_only, takes), takes


def _source_folder(rel: str) -> str:
    """The source a file belongs to: its first folder (below ``mocap/`` when present)."""
    parts = rel.split("/")
    if parts[0] == "mocap" and len(parts) > 2:
        return parts[1]
    return parts[0] if len(parts) > 1 else ""


def _shard_name(rel: str, mirrored: bool) -> str:
    stem = rel[:-4] if rel.lower().endswith(SOURCE_SUFFIXES) else rel
    return stem.replace("/", "__") + ("__mirror" if mirrored else "") + ".npz"


def _feature_sums(motion: Motion) -> dict[str, list]:
    rot, disp = pose_from_motion(motion.local_rot, motion.root_pos)
    dq = encoder_input(rot, disp, motion.skeleton.offsets)
    return {
        "n": int(dq.shape[0]),
        "dq_sum": dq.sum(0).tolist(),
        "dq_sq": (dq**2).sum(0).tolist(),
        "disp_sum": disp.sum(0).tolist(),
        "disp_sq": (disp**2).sum(0).tolist(),
    }


def _stats(entries: list[dict]) -> dict[str, list]:
    train = [e for e in entries if e["split"] == "train"]
    if not train:
        raise UserError("no training files: every input failed or is marked eval-only")
    n = sum(e["sums"]["n"] for e in train)
    out = {}
    for key in ("dq", "disp"):
        s = sum(np.asarray(e["sums"][f"{key}_sum"]) for e in train)
        sq = sum(np.asarray(e["sums"][f"{key}_sq"]) for e in train)
        mean = s / n
        std = np.sqrt(np.maximum(sq / n - mean**2, 0.0))
        out[f"{key}_mean"] = mean.tolist()
        out[f"{key}_std"] = np.maximum(std, 1e-4).tolist()
    out["frames"] = n
    return out


def prepare(
    inputs: list[Path],
    out: Path,
    eval_only: list[str] | None = None,
    mirror: bool = True,
    progress: bool = True,
    rig_map: Path | None = None,
) -> PrepareResult:
    """Run the whole preparation (see module docs). Returns what was done.

    ``rig_map`` is a joint mapping file used for every input instead of rig detection."""
    eval_only = list(EVAL_ONLY) if eval_only is None else eval_only
    files = discover(inputs)
    if not files:
        raise UserError(f"no .bvh or .amc files found under {', '.join(map(str, inputs))}")
    splits, takes = split_files(files, eval_only)
    settings = {
        "format": FORMAT,
        "features": FEATURES_VERSION,
        "mirror": mirror,
        "eval_only": eval_only,
        "retarget": CURRENT.version,
        "rig_map": file_sha256(rig_map) if rig_map else None,
    }
    man_path = out / "manifest.json"
    old = {}
    if man_path.is_file():
        try:
            prev = json.loads(man_path.read_text())
            if prev.get("settings") == settings:
                old = {e["source"] + ("#m" if e["mirrored"] else ""): e for e in prev.get("files", [])}
        except (OSError, json.JSONDecodeError, KeyError):
            old = {}

    result = PrepareResult(out=out)
    entries: list[dict] = []
    bar = tqdm(files, desc="data prepare", unit="file", disable=not progress)
    for path, rel in bar:
        bar.set_postfix_str(rel[-40:])
        try:
            digest = file_sha256(path)
            variants = [False, True] if (mirror and splits[rel] != "test") else [False]
            cached = [old.get(rel + ("#m" if m else "")) for m in variants]
            if all(c and c["sha256"] == digest and (out / c["shard"]).is_file() for c in cached):
                # A shard does not depend on the split, but its entry records it: a changed rule
                # must reach the reused entries too.
                entries.extend(dict(c, split=splits[rel]) for c in cached)  # type: ignore[arg-type]
                result.reused += len(cached)
                continue
            motion, report = load_with_report(path, manifest_fps(path), rig_map, strategy=CURRENT)
            if len(motion) < 8:
                raise UserError(f"{path}: only {len(motion)} frames after retargeting")
            for m in variants:
                clip = motion
                if m:
                    rot, pos, off = mirror_motion(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
                    clip = Motion(rot, pos, type(motion.skeleton)(off), motion.fps, motion.name + "_mirror")
                shard = "shards/" + _shard_name(rel, m)
                _save_npz(
                    out / shard,
                    local_rot=clip.local_rot.astype(np.float32),
                    root_pos=clip.root_pos.astype(np.float32),
                    offsets=clip.skeleton.offsets.astype(np.float32),
                )
                entries.append(
                    {
                        "source": rel,
                        "path": str(path),
                        "sha256": digest,
                        "rig": report.rig,
                        "split": splits[rel],
                        "take": takes.get(rel),
                        "mirrored": m,
                        "shard": shard,
                        "frames": len(clip),
                        "source_fps": report.source_fps,
                        "skipped": report.skip,
                        "scale": report.scale,
                        "sums": _feature_sums(clip),
                    }
                )
                result.written += 1
        except UserError as exc:
            result.failed.append((str(path), str(exc)))
            tqdm.write(f"skipped {path}: {exc}", file=sys.stderr)
        except (ValueError, KeyError, IndexError, FloatingPointError) as exc:
            result.failed.append((str(path), f"{type(exc).__name__}: {exc}"))
            tqdm.write(f"skipped {path}: {type(exc).__name__}: {exc}", file=sys.stderr)

    stats = _stats(entries)
    digest = hashlib.sha256(
        json.dumps([settings, sorted((e["shard"], e["sha256"], e["split"]) for e in entries)]).encode()
    ).hexdigest()[:16]
    manifest = {
        "format": FORMAT,
        "fps": 60,
        "settings": settings,
        "hash": digest,
        "split_rule": f"by take: every {VAL_EVERY}th file from index {VAL_PHASE} of each source folder "
        f"sorted by path is val; a take (manifest cmu_trial) with a copy in {list(REFERENCE_SOURCES)} "
        f"follows that copy, the other takes sorted by key every {VAL_EVERY}th from index {VAL_PHASE} "
        f"(takes only in {list(LATER_SOURCES)} in a pool of their folder's own); "
        f"eval-only patterns {eval_only} are test",
        "files": entries,
        "failed": [{"path": p, "reason": r} for p, r in result.failed],
        "stats": stats,
    }
    text = json.dumps(manifest, indent=1)
    if man_path.is_file() and man_path.read_text() == text:
        result.unchanged = True
    else:
        write_bytes(man_path, text.encode())
    return result
