"""A scene's baked motion as BVH: one function, so the ``bake`` command and the studio
write the same bytes for the same scene."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from engine.authoring.bake import Baked, bake
from engine.authoring.document import AuthoringScene
from engine.motion.bvh import save_motion_bvh


def bake_to_bvh(scene: AuthoringScene, vae, out: str | Path, fps: float | None = None,
                progress: Callable[[int, int], None] | None = None) -> Baked:  # fmt: skip
    """Bake ``scene`` (:func:`engine.authoring.bake.bake`) and write it to ``out`` as a
    BVH file on the character's skeleton, atomically."""
    baked = bake(scene, vae, fps, progress)
    save_motion_bvh(out, baked.motion)
    return baked
