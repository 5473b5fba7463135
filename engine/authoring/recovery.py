"""The pose window's whole state as a scene document, and back: what its autosave keeps.

A saved scene holds the keys, animation, constraints, settings and height
(:func:`engine.authoring.document.authoring_to_dict`); the autosave needs the rest of
the model too, so :func:`document` adds ``recovery``: the frame shown, the targets of the
pose being made (not yet a key), the planted feet, the facing and the pose itself (latent,
local rotations, root, joint positions), and ``shown``: the targets, facing and pose the
frame showed when it was entered, which an edit not keyed is told from
(:meth:`~engine.authoring.session_keys.KeyEditing.unkeyed_edit`). JSON writes every float64 so it reads back
bit for bit, so :func:`recover` gives back exactly the state that was written; it is one
undo step, so the recovered edits count as unsaved.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.authoring.document import authoring_from_dict, authoring_to_dict
from engine.authoring.targets import JointTarget, target_from_json
from engine.errors import UserError


def _floats(a: np.ndarray) -> list:
    return np.asarray(a, float).tolist()


def _pose_dict(p: Pose) -> dict[str, list]:
    return {
        "latent": _floats(p.latent),
        "local_rot": _floats(p.local_rot),
        "root_pos": _floats(p.root_pos),
        "positions": _floats(p.positions),
    }


def document(session: Any) -> dict[str, Any]:
    """The scene document of an :class:`engine.authoring.session.AuthoringSession` with
    its ``recovery`` part (see the module doc)."""
    m = session.mode
    doc = authoring_to_dict(session.scene)
    doc["recovery"] = {
        "frame": int(session.frame),
        "targets": {j: t.to_dict() for j, t in m.targets.items()},
        "planted": {j: _floats(v) for j, v in m.planted.items()},
        "heading": float(m.heading),
        "pose": _pose_dict(m.pose),
    }
    entered, shown = session.shown
    if entered == session.frame:
        doc["recovery"]["shown"] = {
            "targets": {t.joint: t.to_dict() for t in shown.targets},
            "heading": float(shown.heading),
            "pose": _pose_dict(shown.pose),
        }
    return doc


def _array(value: Any, shape: tuple[int, ...], where: str) -> np.ndarray:
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if a.shape != shape or not np.isfinite(a).all():
        raise UserError(f"{where} must be {'x'.join(map(str, shape))} finite numbers")
    return a


def _targets(raw: Any, where: str) -> dict[str, JointTarget]:
    if not isinstance(raw, dict):
        raise UserError(f"{where} must be an object (joint -> target)")
    targets = {}
    for j, t in raw.items():
        target = target_from_json(j, t, f"{where}: {j}")
        if isinstance(t, dict) and t.get("rotation") is not None:
            # stored after the target normalised it; normalising again may move its last bit
            target.rotation = _array(t["rotation"], (4,), f"{where}: {j}: rotation")
        targets[j] = target
    return targets


def _heading(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise UserError(f"{where} must be a number of degrees")
    return float(value)


def _pose(raw: Any, where: str, model_latent: np.ndarray) -> Pose:
    if not isinstance(raw, dict):
        raise UserError(f"{where} must be an object")
    latent = np.array(raw.get("latent", []), dtype=np.float64) if isinstance(raw.get("latent"), list) else None
    if latent is None or latent.ndim != 1 or latent.size == 0 or not np.isfinite(latent).all():
        raise UserError(f"{where}: field 'latent' must be a list of finite numbers")
    J = sk.NUM_JOINTS
    pose = Pose(
        latent,
        _array(raw.get("local_rot"), (J, 4), f"{where}: local_rot"),
        _array(raw.get("root_pos"), (3,), f"{where}: root_pos"),
        _array(raw.get("positions"), (J, 3), f"{where}: positions"),
    )
    if latent.size != model_latent.size:
        raise UserError(f"{where}: field 'latent' has {latent.size} values; the pose model has {model_latent.size}")
    pose.latent = latent.astype(model_latent.dtype)
    return pose


def recover(session: Any, doc: Any, where: str = "autosave") -> None:
    """Make the state :func:`document` wrote ``session``'s: the scene as a new document
    (:meth:`~engine.authoring.session.AuthoringSession.open_scene`), then the frame,
    targets, planted feet, facing and pose as one undo step ("recovered session"), the
    frame as entered when ``shown`` says what it showed then (an edit not keyed is said
    as before the crash). Everything is checked first; errors name ``where`` and the field."""
    if not isinstance(doc, dict):
        raise UserError(f"{where}: not a scene document")
    # the scene part is checked as any scene file is; ``recovery`` is this module's own
    loaded = authoring_from_dict({k: v for k, v in doc.items() if k != "recovery"}, where)
    rec = doc.get("recovery")
    if not isinstance(rec, dict):
        raise UserError(f"{where}: field 'recovery' must be an object")
    frame = rec.get("frame", 0)
    if isinstance(frame, bool) or not isinstance(frame, int) or not 0 <= frame < loaded.animation.frames:
        raise UserError(f"{where}: recovery: field 'frame' must be a frame of the animation, got {frame!r}")
    raw_planted = rec.get("planted") or {}
    if not isinstance(raw_planted, dict):
        raise UserError(f"{where}: recovery: fields 'targets' and 'planted' must be objects (joint -> ...)")
    targets = _targets(rec.get("targets") or {}, f"{where}: recovery: targets")
    unknown = sorted(set(raw_planted) - set(sk.JOINT_INDEX))
    if unknown:
        raise UserError(f"{where}: recovery: planted: unknown joint(s) {', '.join(unknown)}")
    planted = {j: _array(v, (3,), f"{where}: recovery: planted: {j}") for j, v in raw_planted.items()}
    heading = _heading(rec.get("heading", 0.0), f"{where}: recovery: field 'heading'")
    model_latent = np.asarray(session.mode.pose.latent)
    pose = _pose(rec.get("pose"), f"{where}: recovery: pose", model_latent)
    raw_shown = rec.get("shown")
    shown = None
    if raw_shown is not None:
        if not isinstance(raw_shown, dict):
            raise UserError(f"{where}: recovery: field 'shown' must be an object")
        shown = (
            _targets(raw_shown.get("targets") or {}, f"{where}: recovery: shown: targets"),
            _heading(raw_shown.get("heading", 0.0), f"{where}: recovery: shown: field 'heading'"),
            _pose(raw_shown.get("pose"), f"{where}: recovery: shown: pose", model_latent),
        )
    session.open_scene(loaded)
    m = session.mode

    def change() -> None:
        session.frame = frame
        if shown is not None:
            t, h, p = shown
            state = dataclasses.replace(session.state(), targets=tuple(t.values()), heading=h, pose=p)
            session.shown = (frame, state)
        m.targets, m.planted, m.heading, m.pose = targets, planted, heading, pose

    session.edit("recovered session", change, framed=True)
