"""Motion files out: the format follows the file name's extension.

``.bvh`` is written by :mod:`engine.motion.bvh` (canonical skeleton) or
:mod:`engine.motion.write_back` (the source rig); ``.glb`` and ``.gltf`` by
:mod:`engine.motion.gltf` (docs/export.md). Any other extension is an error that lists
the known ones, raised before any work by :func:`motion_format`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from engine.errors import UserError

if TYPE_CHECKING:  # the command line reads this module: no numpy/FK import at parse time
    from engine.motion.clip import Motion

#: Extension -> what it holds; the save dialogs offer these.
MOTION_FORMATS: dict[str, str] = {
    ".bvh": "BVH motion",
    ".glb": "glTF 2.0 binary",
    ".gltf": "glTF 2.0 JSON",
}

#: The extensions written as glTF.
GLTF_SUFFIXES = (".glb", ".gltf")


def motion_format(path: str | Path, flag: str = "--out") -> str:
    """The extension of ``path`` in lower case (``".bvh"``, ``".glb"`` or ``".gltf"``).

    Raises
    ------
    UserError
        For any other extension, naming ``flag`` and listing the known ones.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in MOTION_FORMATS:
        known = ", ".join(f"{ext} ({what})" for ext, what in MOTION_FORMATS.items())
        got = f"extension {suffix!r}" if suffix else "no extension"
        raise UserError(f"{flag} {path}: {got} is not a motion format this program writes; known: {known}")
    return suffix


@dataclass(frozen=True)
class GltfContents:
    """What a glTF file holds besides the main character (ignored by BVH, which cannot).

    Attributes
    ----------
    mesh : bool
        Add the skinned mannequin to every character.
    ghosts : tuple of (str, Motion)
        Comparison characters by method name, on the same skeleton and frames.
    tracking : Tracking or None
        Tracker targets to add as animated boxes.
    """

    mesh: bool = True
    ghosts: tuple[tuple[str, Motion], ...] = ()
    tracking: Any = None


def save_motion(
    path: str | Path,
    motion: Motion,
    on_rig: tuple[Any, Any] | None = None,
    fps: float | None = None,
    contents: GltfContents | None = None,
) -> None:
    """Write ``motion`` to ``path`` atomically in the format of its extension: on the
    canonical skeleton, or with ``on_rig = (raw, report)`` onto the hierarchy of the
    source file it was retargeted from, at ``fps`` (default: the source's).

    Raises
    ------
    UserError
        An unknown extension (:func:`motion_format`), or ``contents`` that only glTF
        holds asked of a BVH file.
    """
    fmt = motion_format(path)
    contents = contents or GltfContents()
    if fmt == ".bvh":
        if contents.ghosts or contents.tracking is not None or not contents.mesh:
            raise UserError(
                f"{path}: a BVH file holds one skeleton; comparison characters, tracker nodes and "
                "the mesh option apply to .glb / .gltf files"
            )
        if on_rig is None:
            from engine.motion.bvh import save_motion_bvh

            save_motion_bvh(path, motion)
        else:
            from engine.motion.write_back import save_on_source_rig

            save_on_source_rig(path, motion, *on_rig, fps=fps)
        return
    from engine.motion import gltf_characters as gc
    from engine.motion.gltf import save_gltf

    def build(m: Motion, name: str, colour: gc.RGBA):
        if on_rig is None:
            return gc.character_of(m, name, colour)
        return gc.character_on_source_rig(m, *on_rig, fps=fps, name=name, colour=colour)

    characters = [build(motion, "", gc.MAIN_COLOUR)]
    characters += [build(m, name, gc.ghost_colour(k)) for k, (name, m) in enumerate(contents.ghosts)]
    trackers = None
    if contents.tracking is not None:
        trackers = gc.trackers_of(contents.tracking, on_rig[1].floor_shift if on_rig is not None else 0.0)
    save_gltf(path, characters, trackers, mesh=contents.mesh, name=motion.name)
