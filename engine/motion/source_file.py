"""Motion files on their own rig, whatever the format: BVH, or Acclaim AMC with its ASF.

:func:`load_source` is what every command and the studio call to read a user's motion
file; it returns the :class:`~engine.motion.bvh.RawBVH` that retargeting takes. The
format follows the extension (:data:`SOURCE_SUFFIXES`). An AMC file needs its skeleton:
``asf`` when given (``--asf``), else the ``skeleton`` its data manifest lists, else the one
ASF file beside it, else the ASF beside it whose name starts the AMC's name
(``HDM_bd.asf`` for ``HDM_bd_squat1Reps_001_120.amc``, ``02.asf`` for ``02_01.amc``).
"""

from __future__ import annotations

from pathlib import Path

from engine.errors import BVHError, UserError
from engine.motion.asf_amc import AsfAmcError, load_amc
from engine.motion.bvh import RawBVH, load_bvh
from engine.motion.retarget_inputs import manifest_entry, manifest_fps

#: Motion file extensions that can be read (lower case).
SOURCE_SUFFIXES = (".bvh", ".amc")
#: Frame rate given to an AMC file when neither the manifest nor ``--fps`` gives one: the
#: CMU and HDM05 databases capture at 120 frames/s.
AMC_DEFAULT_FPS = 120.0


def is_source_file(path: str | Path) -> bool:
    """Whether ``path`` has the extension of a readable motion file."""
    return Path(path).suffix.lower() in SOURCE_SUFFIXES


def find_skeleton(amc: str | Path, asf: str | Path | None = None) -> Path:
    """The ASF skeleton of an AMC motion (see the module docs); an error naming the AMC and
    what was looked for when there is none or the choice is ambiguous."""
    amc = Path(amc)
    if asf is not None:
        if not Path(asf).is_file():
            raise UserError(f"--asf: no such file: {asf}")
        return Path(asf)
    entry = manifest_entry(amc)
    if entry and entry.get("skeleton") and entry.get("path"):
        listed = Path(str(entry["path"]))
        base = amc.resolve()
        for _ in listed.parts:
            base = base.parent
        candidate = base / str(entry["skeleton"])
        if candidate.is_file():
            return candidate
    beside = sorted(amc.parent.glob("*.asf")) + sorted(amc.parent.glob("*.ASF"))
    if len(beside) == 1:
        return beside[0]
    starting = [p for p in beside if amc.stem.lower().startswith(p.stem.lower())]
    if starting:
        return max(starting, key=lambda p: len(p.stem))
    if not beside:
        raise AsfAmcError(amc, "no ASF skeleton beside this AMC motion; give one with --asf SKELETON.asf")
    names = ", ".join(p.name for p in beside[:6])
    raise AsfAmcError(
        amc,
        f"several ASF skeletons beside this AMC motion ({names}) and none whose name starts "
        "the AMC's; choose one with --asf SKELETON.asf",
    )


def load_source(
    path: str | Path, max_frames: int | None = None, asf: str | Path | None = None, fps: float | None = None
) -> RawBVH:
    """Read a motion file on its own rig (see the module docs).

    ``max_frames`` keeps only the first frames (every line is still checked); ``asf`` is
    the skeleton of an AMC file; ``fps`` the true frame rate of an AMC file (BVH files keep
    their header's; retargeting applies the true rate of either separately)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".amc":
        rate = fps or manifest_fps(Path(path)) or AMC_DEFAULT_FPS
        return load_amc(path, find_skeleton(path, asf), max_frames, rate)
    if suffix == ".asf":
        raise BVHError(
            path,
            "an ASF file holds a skeleton without motion; open one of its .amc motions "
            "(the skeleton is found beside it, or given with --asf)",
        )
    if asf is not None:
        raise UserError(f"--asf applies to .amc motions, not to {Path(path).name}")
    return load_bvh(path, max_frames)
