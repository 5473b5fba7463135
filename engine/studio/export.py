"""Saving a reconstruction as BVH or glTF: the studio's File > Save reconstruction and
``reconstruct --out`` write through :func:`write_reconstruction`.

:class:`ExportJob` is what the studio's export runs off the GUI thread: a copy of the
session's clip, sensors, constraints, settings and method taken when the export starts
(:meth:`ExportJob.of_session`), solved by :func:`reconstruct_clip`
with a fresh method, then written. The file is written atomically, so a file is either
complete or absent, and a cancelled job writes nothing.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.methods import driver
from engine.methods.base import Method
from engine.motion.clip import Motion
from engine.sensors import Sensor
from engine.studio.clip_source import ClipSource
from engine.studio.method_edits import make_method

if TYPE_CHECKING:
    from engine.motion.bvh import RawBVH
    from engine.motion.formats import GltfContents
    from engine.studio.session import Session


def reconstruct_clip(
    motion: Motion,
    sensors: tuple[Sensor, ...],
    constraints: tuple[Constraint, ...],
    settings: Mapping[str, Any],
    method_name: str,
    factory: Callable[[str], Method] | None = None,
    progress: Callable[[int], bool | None] | None = None,
) -> Motion:
    """Run a fresh method over every frame of ``motion`` with the studio's sensor edits.

    ``motion`` is the ground truth of a method that needs one (the autoencoder).
    Returns the reconstruction as a :class:`engine.motion.clip.Motion` (same skeleton and fps).
    ``progress(frame)`` is called after each frame and may return True to cancel.

    Raises
    ------
    UserError, FloatingPointError
        Settings the method rejects; a non-finite pose.
    """
    rots, roots = [], []
    for f, (rot, root) in enumerate(solve_frames(motion, sensors, constraints, settings, method_name, factory)):
        rots.append(rot)
        roots.append(root)
        if progress is not None and progress(f):
            break
    name = f"{motion.name} ({method_name})"
    return Motion(np.array(rots), np.array(roots), motion.skeleton, motion.fps, name, motion.start)


def solve_frames(
    motion: Motion,
    sensors: tuple[Sensor, ...],
    constraints: tuple[Constraint, ...],
    settings: Mapping[str, Any],
    method_name: str,
    factory: Callable[[str], Method] | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Solve ``motion``'s frames one by one with a fresh method (as :func:`reconstruct_clip`),
    yielding each frame's local rotations ``(J, 4)`` and root position ``(3,)`` as soon as
    it is solved (a consumer may draw frame f while f + 1 is solved)."""
    source = ClipSource(motion)
    source.set_sensors(tuple(sensors))
    constraints = copy.deepcopy(tuple(constraints))  # a separate run: its own pin captures
    method = (factory or make_method)(method_name)
    driver.start(
        method,
        motion.skeleton,
        motion.fps,
        reference=motion,
        settings=settings,
        constraints=constraints,
        sensors=source.sensors,
    )
    for f in range(len(motion)):
        res = driver.step(method, source.frame(f))
        yield np.asarray(res.local_rot, float), np.asarray(res.root_pos, float)


def write_reconstruction(
    path: str | Path,
    rec: Motion,
    on_rig: tuple[RawBVH, Any] | None = None,
    fps: float | None = None,
    contents: GltfContents | None = None,
) -> None:
    """Write ``rec`` to ``path`` atomically, as BVH or glTF by its extension
    (:func:`engine.motion.formats.save_motion`, docs/export.md): on the canonical
    skeleton, or with ``on_rig = (raw, report)`` onto the hierarchy of the source file it
    was retargeted from (docs/skeleton.md), at ``fps`` (default: the source's frame rate)."""
    from engine.motion.formats import save_motion

    save_motion(path, rec, on_rig, fps, contents)


def source_rig(source: str | Path, rig_map: str | Path | None = None) -> tuple[RawBVH, Any]:
    """``(raw, report)`` of the BVH ``source`` retargeted with the joint mapping file
    ``rig_map`` (what :func:`write_reconstruction` needs to write onto its hierarchy)."""
    from engine.motion.retarget import manifest_fps, retarget
    from engine.motion.source_file import load_source

    raw = load_source(source)
    return raw, retarget(raw, manifest_fps(Path(source)), rig_map=rig_map)[1]


def skipped_note(report: Any, start_s: float = 0.0) -> str:
    """What a file written onto the source rig lacks of the source (for the message that
    says it was written): the first frames the rig's profile skips on loading, a rest pose
    (``report.skip``), and for a trimmed clip the frames before its ``start_s`` seconds;
    "" when none."""
    skip = int(getattr(report, "skip", 0) or 0)
    cut = int(round(start_s * float(getattr(report, "source_fps", 0) or 0)))
    if not skip and not cut:
        return ""
    parts = []
    if skip:
        parts.append(f"without the source's first {skip} frame{'s' * (skip > 1)}, its rest pose, skipped on loading")
    if cut:
        parts.append(f"trimmed: the {cut} source frame{'s' * (cut > 1)} after it left out" if skip else "trimmed")
    return f" ({'; '.join(parts)}: frame i here is the source's frame i + {skip + cut})"


@dataclass(frozen=True)
class ExportJob:
    """A studio export: solve ``motion`` with ``method`` and the studio's edits, then
    write ``path`` (onto the hierarchy of the BVH ``source`` when given, mapped with
    ``rig_map``).

    Attributes
    ----------
    motion : Motion
    sensors : tuple of Sensor
    constraints : tuple of Constraint
    settings : Mapping
        Optimizer settings by name (the session's :class:`~engine.solver.settings_edit.SettingsEdit`).
    method : str
        Registered method name.
    path : Path
        Output file (.bvh, .glb or .gltf).
    source : Path or None
        The BVH the clip was opened from, to write onto its rig; None: canonical skeleton.
    rig_map : Path or None
        The joint mapping file the clip was opened with.
    """

    motion: Motion
    sensors: tuple[Sensor, ...]
    constraints: tuple[Constraint, ...]
    settings: Mapping[str, Any]
    method: str
    path: Path
    source: Path | None = None
    rig_map: Path | None = None

    @classmethod
    def of_session(cls, session: Session, path: str | Path, on_source_rig: bool = False) -> ExportJob:
        """What saving ``session``'s reconstruction to ``path`` needs, copied now (later
        edits do not reach a running export). With ``on_source_rig`` the BVH is written
        on the hierarchy of the file the clip came from.

        Raises
        ------
        UserError
            With tracker input (saving re-solves a clip), with no clip, or with
            ``on_source_rig`` for a clip that was not opened from a file.
        """
        if session.source is not None:
            raise UserError("saving re-solves a clip; tracker input has none")
        if session.motion is None:
            raise UserError("open a motion first")
        if on_source_rig and session.path is None:
            raise UserError("this clip was not opened from a BVH file")
        return cls(
            session.motion,
            tuple(session.sensors.values()),
            tuple(session.constraints),
            session.settings,
            session.method,
            Path(path),
            session.path if on_source_rig else None,
            session.rig_map if on_source_rig else None,
        )

    def run(
        self,
        factory: Callable[[str], Method] | None = None,
        progress: Callable[[int], None] | None = None,
        cancelled: Callable[[], bool] | None = None,
    ) -> Motion | None:
        """Solve and write; returns the reconstruction, or None when ``cancelled()``
        became true (checked after every frame and before writing: nothing is written).

        ``factory(name) -> Method`` defaults to the registry; ``progress(frame)`` is
        called after each solved frame.
        """

        def after(frame: int) -> bool:
            if progress is not None:
                progress(frame)
            return cancelled is not None and cancelled()

        rec = reconstruct_clip(
            self.motion, self.sensors, self.constraints, self.settings, self.method, factory=factory, progress=after
        )
        if cancelled is not None and cancelled():
            return None
        write_reconstruction(self.path, rec, source_rig(self.source, self.rig_map) if self.source else None)
        return rec
