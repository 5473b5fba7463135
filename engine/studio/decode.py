"""Latent debugging: an edited latent's pose, drawn on the pose on screen.

The decoder's bare output for a frame's latent lacks what the solve adds after it (the
root placement from the trackers, the exact reach of tracked hands and feet): drawn as
is it sat about 10 cm off the reconstruction and a foot above the floor. The studio
draws the *change* an edited latent makes, added to the pose on screen, so the
unedited latent lands exactly on it.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.methods.base import DecodesLatents


def decoded_on_pose(
    method: DecodesLatents, latent: np.ndarray, shown: np.ndarray | None, pose: np.ndarray | None
) -> np.ndarray:
    """World joints (22, 3) m of ``latent`` (L,) relative to the frame on screen, whose
    latent is ``shown`` (L,) and pose ``pose`` (22, 3) m; the bare decoded pose when
    ``shown`` or ``pose`` is missing or ``shown`` of another size."""
    out = np.asarray(method.decode_latent(np.asarray(latent, float)), float).reshape(sk.NUM_JOINTS, 3)
    if shown is None or pose is None or np.size(shown) != np.size(latent):
        return out
    base = np.asarray(method.decode_latent(np.asarray(shown, float)), float).reshape(sk.NUM_JOINTS, 3)
    return out + (np.asarray(pose, float) - base)


def decode_request(
    method: object, name: str, latent: np.ndarray, shown: np.ndarray | None, pose: np.ndarray | None
) -> tuple[np.ndarray | None, str]:
    """A studio request to decode ``latent``: the pose (:func:`decoded_on_pose`, exact on
    screen) and an empty message, or None and the error to report (a method without a
    latent, or a decode that failed)."""
    if not isinstance(method, DecodesLatents):
        return None, f"{name}: cannot decode latents"
    try:
        return decoded_on_pose(method, latent, shown, pose), ""
    except Exception as exc:  # the studio reports it and keeps running
        return None, f"decode latent: {exc}"
