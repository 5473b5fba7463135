"""A scene's baked motion as BVH or glTF: one function, so the ``bake`` command and the studio
write the same bytes for the same scene."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from engine.authoring.bake import Baked, bake
from engine.authoring.document import AuthoringScene
from engine.motion.formats import GltfContents, save_motion


def bake_to_file(
    scene: AuthoringScene,
    vae,
    out: str | Path,
    fps: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    contents: GltfContents | None = None,
) -> Baked:
    """Bake ``scene`` (:func:`engine.authoring.bake.bake`) and write it to ``out`` on the
    character's skeleton, atomically, as BVH or glTF by the extension
    (:func:`engine.motion.formats.save_motion`)."""
    baked = bake(scene, vae, fps, progress)
    save_motion(out, baked.motion, contents=contents)
    return baked
