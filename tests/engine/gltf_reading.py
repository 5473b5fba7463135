"""An independent reader of the glTF files the export writes: pygltflib for the container,
numpy for the accessors, the animation sampling and forward kinematics (node matrices
``T R S`` chained through the node tree), and the Khronos validator through node.

Nothing here uses the writer's code, so the tests compare two implementations.
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pygltflib

from tests.conftest import REPO

_COMPONENTS = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def _blob(doc: pygltflib.GLTF2) -> bytes:
    uri = doc.buffers[0].uri
    if uri:  # .gltf: one embedded data: URI
        return base64.b64decode(uri.split(",", 1)[1])
    return doc.binary_blob()


@dataclass
class Read:
    """A file as read: the document and its accessor data."""

    doc: pygltflib.GLTF2
    blob: bytes

    def accessor(self, i: int) -> np.ndarray:
        acc = self.doc.accessors[i]
        view = self.doc.bufferViews[acc.bufferView]
        dtype = np.dtype(_COMPONENTS[acc.componentType])
        width = _WIDTH[acc.type]
        start = (view.byteOffset or 0) + (acc.byteOffset or 0)
        data = np.frombuffer(self.blob, dtype, acc.count * width, start)
        return data.reshape(acc.count, width) if width > 1 else data.copy()

    def node_index(self, name: str) -> int:
        return [n.name for n in self.doc.nodes].index(name)

    def parents(self) -> np.ndarray:
        par = np.full(len(self.doc.nodes), -1)
        for i, n in enumerate(self.doc.nodes):
            for c in n.children:
                par[c] = i
        return par

    def channels(self) -> dict[tuple[int, str], tuple[np.ndarray, np.ndarray]]:
        """``(node, path) -> (times (K,), values (K, 3 or 4))`` of the first animation."""
        anim = self.doc.animations[0]
        out = {}
        for ch in anim.channels:
            s = anim.samplers[ch.sampler]
            out[(ch.target.node, ch.target.path)] = (self.accessor(s.input), self.accessor(s.output))
        return out

    def world_positions(self, nodes: list[int], frames: int) -> np.ndarray:
        """World positions ``(frames, len(nodes), 3)`` of ``nodes`` on the first ``frames``
        keys of the animation (every channel keyed on the same frames), glTF axes."""
        return self.world_matrices(nodes, frames)[..., :3, 3]

    def world_matrices(self, nodes: list[int], frames: int) -> np.ndarray:
        """World matrices ``(frames, len(nodes), 4, 4)`` of ``nodes`` (see :meth:`world_positions`)."""
        chans = self.channels()
        par = self.parents()
        cache: dict[int, np.ndarray] = {}

        def local(i: int) -> np.ndarray:
            n = self.doc.nodes[i]
            t = np.tile(np.asarray(n.translation or [0, 0, 0], float), (frames, 1))
            r = np.tile(np.asarray(n.rotation or [0, 0, 0, 1], float), (frames, 1))
            s = np.tile(np.asarray(n.scale or [1, 1, 1], float), (frames, 1))
            if (i, "translation") in chans:
                t = chans[(i, "translation")][1][:frames].astype(float)
            if (i, "rotation") in chans:
                r = chans[(i, "rotation")][1][:frames].astype(float)
            if (i, "scale") in chans:
                s = chans[(i, "scale")][1][:frames].astype(float)
            m = np.zeros((frames, 4, 4))
            m[:, :3, :3] = quat_xyzw_matrix(r) * s[:, None, :]
            m[:, :3, 3] = t
            m[:, 3, 3] = 1.0
            return m

        def world(i: int) -> np.ndarray:
            if i not in cache:
                cache[i] = local(i) if par[i] < 0 else world(par[i]) @ local(i)
            return cache[i]

        return np.stack([world(i) for i in nodes], axis=1)


def quat_xyzw_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of quaternions ``(N, 4)`` in glTF's (x, y, z, w) order."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q.T
    return np.stack(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - w * z),
            2 * (x * z + w * y),
            2 * (x * y + w * z),
            1 - 2 * (x * x + z * z),
            2 * (y * z - w * x),
            2 * (x * z - w * y),
            2 * (y * z + w * x),
            1 - 2 * (x * x + y * y),
        ],
        -1,
    ).reshape(-1, 3, 3)


def read_gltf(path: str | Path) -> Read:
    doc = pygltflib.GLTF2().load(str(path))
    return Read(doc, _blob(doc))


#: glTF (Y up) -> the studio's axes (Z up): the inverse of the export's change of axes.
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def validator_command() -> tuple[list[str], dict] | None:
    """``node scripts/gltf_validate.js`` and its environment, or None when node or the npm
    package ``gltf-validator`` (scripts/bootstrap.sh installs it in the venv) is absent."""
    node = shutil.which("node")
    modules = Path(os.environ.get("DRAGPOSER_GLTF_VALIDATOR", Path(sys.prefix) / "gltf-validator" / "node_modules"))
    if node is None or not (modules / "gltf-validator").is_dir():
        return None
    env = {**os.environ, "NODE_PATH": str(modules)}
    return [node, str(REPO / "scripts" / "gltf_validate.js")], env


def validate(paths: list[Path]) -> list[dict]:
    """The Khronos validator's summary of each file (errors, warnings, messages)."""
    cmd, env = validator_command()
    out = subprocess.run([*cmd, *map(str, paths)], capture_output=True, text=True, env=env, timeout=300)
    if out.returncode == 2:
        raise RuntimeError(out.stderr)
    return [json.loads(line) for line in out.stdout.splitlines() if line.strip()]


def bvh_world_positions(raw) -> np.ndarray:
    """World joint positions ``(F, J, 3)`` of a loaded BVH (:class:`RawBVH`), file units and
    axes, by numpy matrix FK: local translation = position channels of 6-channel joints,
    else OFFSET; local rotation from the Euler channels in each joint's order."""
    rad = np.radians(raw.rotations_deg)
    f, j = rad.shape[:2]
    mats = np.tile(np.eye(3), (f, j, 1, 1))
    for k in range(3):
        axes = raw.rot_order[:, k]
        a = rad[..., k]
        c, s = np.cos(a), np.sin(a)
        m = np.zeros((f, j, 3, 3))
        for jj, ax in enumerate(axes):
            i = "xyz".index(ax)
            u, v = [x for x in range(3) if x != i]
            m[:, jj, i, i] = 1.0
            m[:, jj, u, u] = c[:, jj]
            m[:, jj, v, v] = c[:, jj]
            sign = 1.0 if i != 1 else -1.0  # the y rotation's sine sits the other way round
            m[:, jj, u, v] = -s[:, jj] * sign
            m[:, jj, v, u] = s[:, jj] * sign
        mats = mats @ m
    moving = np.array([len(c) == 6 for c in raw.channels])
    trans = np.where(moving[None, :, None], raw.positions, raw.offsets[None])
    glob_r = np.zeros_like(mats)
    pos = np.zeros((f, j, 3))
    for jj, p in enumerate(raw.parents):
        if p < 0:
            glob_r[:, jj], pos[:, jj] = mats[:, jj], trans[:, jj]
        else:
            glob_r[:, jj] = glob_r[:, p] @ mats[:, jj]
            pos[:, jj] = pos[:, p] + np.einsum("fij,fj->fi", glob_r[:, p], trans[:, jj])
    return pos


def skinned_points(read: Read, mesh_node: int, frame: int) -> np.ndarray:
    """Vertices ``(V, 3)`` of the skinned mesh on ``mesh_node`` at key ``frame``: linear
    blend skinning, ``sum_k w_k (World_k IBM_k) v``, glTF axes."""
    doc = read.doc
    node = doc.nodes[mesh_node]
    skin = doc.skins[node.skin]
    prim = doc.meshes[node.mesh].primitives[0]
    v = read.accessor(prim.attributes.POSITION).astype(float)
    joints = read.accessor(prim.attributes.JOINTS_0).astype(int)
    weights = read.accessor(prim.attributes.WEIGHTS_0).astype(float)
    ibm = read.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    world = read.world_matrices(list(skin.joints), frame + 1)[frame]  # (J, 4, 4)
    m = world @ ibm
    vh = np.c_[v, np.ones(len(v))]
    out = np.zeros((len(v), 3))
    for k in range(4):
        out += weights[:, k : k + 1] * np.einsum("vij,vj->vi", m[joints[:, k]], vh)[:, :3]
    return out


def vtk_points_at(path: Path, t: float) -> list[np.ndarray]:
    """Deformed mesh vertices as VTK's glTF reader gives them at time ``t`` (seconds), one
    array per mesh in the reader's order: an outside implementation of skinning and
    animation sampling."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    reader = vtk.vtkGLTFReader()
    reader.SetFileName(str(path))
    reader.ApplyDeformationsToGeometryOn()
    reader.UpdateInformation()
    reader.EnableAnimation(0)
    reader.UpdateInformation()
    reader.UpdateTimeStep(t)
    it = reader.GetOutput().NewIterator()
    it.InitTraversal()
    out = []
    while not it.IsDoneWithTraversal():
        data = it.GetCurrentDataObject()
        if data.GetNumberOfPoints():
            out.append(vtk_to_numpy(data.GetPoints().GetData()).astype(float))
        it.GoToNextItem()
    return out
