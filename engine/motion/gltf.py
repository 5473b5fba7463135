"""glTF 2.0 files (``.glb`` binary, ``.gltf`` JSON) of skinned, animated characters.

The container is built with pygltflib: nodes, one skin per character, one animation, the
accessors and one buffer (a binary chunk in ``.glb``, a base64 ``data:`` URI in
``.gltf`` so that the file stands alone). What goes in (docs/export.md):

* per character, one node per joint named as in its BVH, in the rest pose (identity
  rotations, the BVH OFFSETs as translations; the root at its first-frame position),
  a skin over those joints with inverse bind matrices of that rest pose, and, unless
  left out, a mannequin mesh (:mod:`engine.motion.mannequin`) with a plain material,
  on a node of its own at the scene's root (glTF ignores a skinned mesh node's parents);
* one animation: for each character a translation channel for the root (and for any
  other joint whose position channels move) and a rotation channel for every joint,
  keyed on every frame at the clip's rate with linear interpolation; tracker nodes
  (a small box each) with their own translation, rotation (6-DoF sensors) and a
  scale of 0 while a sensor is lost.

Units and axes: glTF is metres, +Y up, +Z forward. The studio is metres, +Z up, -Y
forward, so every position ``p`` is written ``C p`` and every rotation ``q`` as
``c q c^-1`` with :data:`Z_UP_TO_Y_UP` (a -90 degree turn about X): x stays x, the
studio's up becomes +Y and its forward +Z.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygltflib as G

from engine.atomic import atomic_path
from engine.kinematics import quaternion as Q
from engine.motion.mannequin import SkinnedMesh, bones_of, skinned_mannequin

__all__ = ["Character", "TrackerNodes", "Z_UP_TO_Y_UP", "build_gltf", "save_gltf"]

#: Rotation taking the studio's Z-up axes to glTF's Y-up ones (x, y, z) -> (x, z, -y).
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
_C_Q = Q.from_matrix(Z_UP_TO_Y_UP)

#: Half the edge of a tracker's box, metres.
TRACKER_SIZE = 0.035


@dataclass(frozen=True)
class Character:
    """One skeleton and its motion, in the studio's axes (Z up, metres).

    Attributes
    ----------
    name : str
        Node-name prefix of a comparison character ("" for the main one).
    joints : tuple of str, length J
        Joint names in file order; a parent comes before its children.
    parents : tuple of int, length J
        Parent index of each joint (-1 for the root).
    rest : ndarray (J, 3)
        Local translation of each joint in the rest pose (its OFFSET), metres.
    translations : ndarray (F, J, 3)
        Local translation of each joint on each frame, metres.
    rotations : ndarray (F, J, 4)
        Local rotation of each joint on each frame (w, x, y, z).
    fps : float
        Frames per second.
    ends : dict of int to ndarray (3,)
        End-site offsets by owning joint, metres (the mannequin's head, hands, toes).
    radius : dict of int to float
        Known capsule radii (:func:`engine.motion.mannequin.bones_of`).
    colour : tuple of 4 floats
        Base colour of the mannequin (linear RGBA).
    """

    name: str
    joints: tuple[str, ...]
    parents: tuple[int, ...]
    rest: np.ndarray
    translations: np.ndarray
    rotations: np.ndarray
    fps: float
    ends: dict[int, np.ndarray] = field(default_factory=dict)
    radius: dict[int, float] = field(default_factory=dict)
    colour: tuple[float, float, float, float] = (0.8, 0.55, 0.4, 1.0)

    def node_name(self, joint: int) -> str:
        return f"{self.name}:{self.joints[joint]}" if self.name else self.joints[joint]


@dataclass(frozen=True)
class TrackerNodes:
    """Tracker targets as animated boxes, in the studio's axes.

    Attributes
    ----------
    names : tuple of str, length S
    positions : ndarray (F, S, 3)
        World positions, metres.
    rotations : ndarray (F, S, 4) or None
        World rotations; None, or a sensor in ``position_only``, writes no rotation.
    connected : ndarray (F, S) of bool
        False while a sensor is lost (its box is scaled to 0).
    fps : float
    position_only : tuple of bool, length S
    """

    names: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray | None
    connected: np.ndarray
    fps: float
    position_only: tuple[bool, ...] = ()


def _to_y_up(v: np.ndarray) -> np.ndarray:
    return np.asarray(v, float) @ Z_UP_TO_Y_UP.T


def _rot_to_y_up(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, float)
    c = np.broadcast_to(_C_Q, q.shape)
    return Q.mul(Q.mul(c, q), Q.conjugate(c))


def _xyzw(q: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) to glTF's (x, y, z, w) in float32, signs continuous in time."""
    q = Q.unroll(Q.normalize(np.asarray(q, float)), axis=0)
    out = np.ascontiguousarray(q[..., [1, 2, 3, 0]], dtype=np.float32)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


class _Builder:
    """Accumulates accessors in one binary buffer (each in its own 4-byte aligned view)."""

    def __init__(self) -> None:
        self.gltf = G.GLTF2(asset=G.Asset(version="2.0", generator="dragposer-studio"), scene=0)
        self.chunks: list[bytes] = []
        self.size = 0

    def accessor(self, data: np.ndarray, kind: str, target: int | None = None, bounds: bool = False) -> int:
        comp = {np.float32: G.FLOAT, np.uint16: G.UNSIGNED_SHORT, np.uint32: G.UNSIGNED_INT}[data.dtype.type]
        raw = np.ascontiguousarray(data).tobytes()
        pad = (-len(raw)) % 4
        self.gltf.bufferViews.append(G.BufferView(buffer=0, byteOffset=self.size, byteLength=len(raw), target=target))
        self.chunks += [raw, b"\0" * pad]
        self.size += len(raw) + pad
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        flat = data.reshape(-1, width)
        acc = G.Accessor(bufferView=len(self.gltf.bufferViews) - 1, componentType=comp, count=len(flat), type=kind)
        if bounds:
            acc.min = [float(x) for x in flat.min(0)]
            acc.max = [float(x) for x in flat.max(0)]
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def material(self, name: str, colour: tuple[float, ...]) -> int:
        pbr = G.PbrMetallicRoughness(
            baseColorFactor=[float(c) for c in colour], metallicFactor=0.0, roughnessFactor=0.7
        )
        self.gltf.materials.append(G.Material(name=name, pbrMetallicRoughness=pbr))
        return len(self.gltf.materials) - 1

    def node(self, **kw) -> int:
        self.gltf.nodes.append(G.Node(**kw))
        return len(self.gltf.nodes) - 1

    def finish(self) -> G.GLTF2:
        blob = b"".join(self.chunks)
        self.gltf.buffers.append(G.Buffer(byteLength=len(blob)))
        self.gltf.set_binary_blob(blob)
        return self.gltf


class _Animation:
    """Samplers and channels of the one animation, with one time accessor per frame rate."""

    def __init__(self, b: _Builder) -> None:
        self.b = b
        self.times: dict[tuple[int, float], int] = {}  # (frames, fps) -> accessor
        self.anim = G.Animation(name="motion", samplers=[], channels=[])

    def time_accessor(self, frames: int, fps: float) -> int:
        key = (frames, float(fps))
        if key not in self.times:
            t = (np.arange(frames, dtype=np.float64) / fps).astype(np.float32)
            self.times[key] = self.b.accessor(t, "SCALAR", bounds=True)
        return self.times[key]

    def channel(self, node: int, path: str, values: np.ndarray, fps: float) -> None:
        kind = "VEC4" if path == "rotation" else "VEC3"
        inp = self.time_accessor(len(values), fps)
        out = self.b.accessor(np.ascontiguousarray(values, dtype=np.float32), kind)
        self.anim.samplers.append(G.AnimationSampler(input=inp, output=out, interpolation="LINEAR"))
        self.anim.channels.append(
            G.AnimationChannel(
                sampler=len(self.anim.samplers) - 1, target=G.AnimationChannelTarget(node=node, path=path)
            )
        )


def _add_character(b: _Builder, anim: _Animation, ch: Character, mesh: bool) -> list[int]:
    """Joint nodes, skin, mesh and channels of ``ch``; returns the scene's new root nodes."""
    nj = len(ch.joints)
    rest = _to_y_up(ch.rest).copy()
    moving = _to_y_up(ch.translations)
    rest[0] = moving[0, 0]
    first = len(b.gltf.nodes)
    for j in range(nj):
        b.node(name=ch.node_name(j), translation=[float(x) for x in rest[j]])
    for j, p in enumerate(ch.parents):
        if p >= 0:
            b.gltf.nodes[first + p].children.append(first + j)
    roots = [first + j for j, p in enumerate(ch.parents) if p < 0]
    rot = _xyzw(_rot_to_y_up(ch.rotations))
    for j in range(nj):
        if j == 0 or np.ptp(moving[:, j], axis=0).max() > 1e-9:
            anim.channel(first + j, "translation", moving[:, j], ch.fps)
        anim.channel(first + j, "rotation", rot[:, j], ch.fps)
    world = np.zeros((nj, 3))
    for j, p in enumerate(ch.parents):
        world[j] = rest[j] + (world[p] if p >= 0 else 0.0)
    ibm = np.tile(np.eye(4, dtype=np.float32), (nj, 1, 1))
    ibm[:, :3, 3] = -world  # the rest pose turns no joint: its bind matrices are translations
    # glTF matrices are column-major: write each transposed
    ibm_acc = b.accessor(np.ascontiguousarray(ibm.transpose(0, 2, 1)), "MAT4")
    b.gltf.skins.append(
        G.Skin(
            name=f"{ch.name or 'character'} skin",
            joints=list(range(first, first + nj)),
            inverseBindMatrices=ibm_acc,
            skeleton=roots[0],
        )
    )
    if mesh:
        ends = {j: _to_y_up(off) for j, off in ch.ends.items()}
        body = skinned_mannequin(bones_of(world, ch.parents, ends, ch.radius), ch.parents)
        mat = b.material(f"{ch.name or 'character'} body", ch.colour)
        m = _mesh(b, f"{ch.name or 'character'} body", body, mat, skinned=True)
        roots.append(b.node(name=f"{ch.name or 'character'} body", mesh=m, skin=len(b.gltf.skins) - 1))
    return roots


def _mesh(b: _Builder, name: str, body: SkinnedMesh, material: int, skinned: bool) -> int:
    attrs = G.Attributes(
        POSITION=b.accessor(body.positions, "VEC3", G.ARRAY_BUFFER, bounds=True),
        NORMAL=b.accessor(body.normals, "VEC3", G.ARRAY_BUFFER),
    )
    if skinned:
        attrs.JOINTS_0 = b.accessor(body.joints, "VEC4", G.ARRAY_BUFFER)
        attrs.WEIGHTS_0 = b.accessor(body.weights, "VEC4", G.ARRAY_BUFFER)
    prim = G.Primitive(
        attributes=attrs,
        indices=b.accessor(body.indices, "SCALAR", G.ELEMENT_ARRAY_BUFFER),
        material=material,
        mode=G.TRIANGLES,
    )
    b.gltf.meshes.append(G.Mesh(name=name, primitives=[prim]))
    return len(b.gltf.meshes) - 1


def _box() -> SkinnedMesh:
    """A cube of half-edge :data:`TRACKER_SIZE` with flat faces (no skin)."""
    pos: list[np.ndarray] = []
    nrm: list[np.ndarray] = []
    idx: list[int] = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u, v = np.eye(3)[(axis + 1) % 3], np.eye(3)[(axis + 2) % 3]
            corners = [n + a * u + c * v for a, c in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            k = len(pos)
            pos += corners
            nrm += [n] * 4
            idx += [k, k + 1, k + 2, k, k + 2, k + 3] if sign > 0 else [k, k + 2, k + 1, k, k + 3, k + 2]
    none = np.zeros((len(pos), 4))
    return SkinnedMesh(
        np.array(pos, np.float32) * TRACKER_SIZE,
        np.array(nrm, np.float32),
        none.astype(np.uint16),
        none.astype(np.float32),
        np.array(idx, np.uint32),
    )


def _add_trackers(b: _Builder, anim: _Animation, t: TrackerNodes) -> list[int]:
    mesh = _mesh(b, "tracker", _box(), b.material("tracker", (0.1, 0.6, 0.95, 1.0)), skinned=False)
    pos = _to_y_up(t.positions)
    rot = _xyzw(_rot_to_y_up(t.rotations)) if t.rotations is not None else None
    nodes = []
    for s, name in enumerate(t.names):
        n = b.node(name=f"tracker:{name}", mesh=mesh, translation=[float(x) for x in pos[0, s]])
        anim.channel(n, "translation", pos[:, s], t.fps)
        if rot is not None and not (t.position_only and t.position_only[s]):
            anim.channel(n, "rotation", rot[:, s], t.fps)
        if not t.connected[:, s].all():
            scale = np.repeat(t.connected[:, s, None].astype(np.float32), 3, axis=1)
            anim.channel(n, "scale", scale, t.fps)
        nodes.append(n)
    return nodes


def build_gltf(
    characters: list[Character], trackers: TrackerNodes | None = None, mesh: bool = True, name: str = "motion"
) -> G.GLTF2:
    """The glTF document of ``characters`` (the first is the main one) and ``trackers``."""
    b = _Builder()
    anim = _Animation(b)
    anim.anim.name = name or "motion"
    roots: list[int] = []
    for ch in characters:
        roots += _add_character(b, anim, ch, mesh)
    if trackers is not None:
        roots += _add_trackers(b, anim, trackers)
    b.gltf.scenes.append(G.Scene(name=name or "motion", nodes=roots))
    first = characters[0]
    anim.anim.extras = {"fps": float(first.fps), "frames": int(len(first.rotations))}
    b.gltf.animations.append(anim.anim)
    return b.finish()


def save_gltf(
    path: str | Path,
    characters: list[Character],
    trackers: TrackerNodes | None = None,
    mesh: bool = True,
    name: str = "motion",
) -> None:
    """Write ``characters`` (and ``trackers``) to ``path`` atomically: binary glTF for a
    ``.glb`` name, JSON with the buffer embedded for any other (``.gltf``; the extensions
    are checked by :func:`engine.motion.formats.motion_format`); module docs.

    Raises
    ------
    ValueError
        Non-finite values or no frames.
    """
    path = Path(path)
    binary = path.suffix.lower() == ".glb"
    for ch in characters:
        if len(ch.rotations) == 0:
            raise ValueError(f"motion {name!r} has no frames; not writing {path}")
        if not (np.isfinite(ch.rotations).all() and np.isfinite(ch.translations).all()):
            raise ValueError(f"motion {name!r} holds NaN or infinite values; not writing {path}")
    doc = build_gltf(characters, trackers, mesh, name)
    with atomic_path(path) as tmp:
        if binary:
            doc.save_binary(str(tmp))
        else:
            doc.convert_buffers(G.BufferFormat.DATAURI)
            doc.save_json(str(tmp))
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())  # the rename must not land before the data
