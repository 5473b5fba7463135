"""The tracker prior's network: a latent guessed from the trackers' last half second.

The pose bank (:mod:`engine.solver.tracker_prior`) answers a frame's readings with the mean
latent of the training frames whose readings look most alike; it sees one instant, and an
average of neighbours is a crude regressor. This network reads the same tracker features
(:func:`engine.solver.tracker_prior.features`) at :data:`HISTORY` instants :data:`LAG`
frames apart (the current frame and 28 frames before it, about half a second at 60 fps),
so it sees how the head and hands have been moving, and maps them to the VAE latent of the
pose with a multilayer perceptron trained on the CMU training takes (``dragposer-studio
train tracker-net``, :mod:`engine.training.tracker_net`). One network per combination of
tracked bank joints (:func:`engine.solver.tracker_prior.combination`): the shipped file
holds those of the sensor presets. It is evaluated in numpy, a few tens of microseconds a
frame, and it reads only this frame's and earlier readings, so it works live.

Its latent belongs to the VAE whose encoder made the training latents: the file records
that VAE's hash, and a different VAE goes without it (as with the pose bank).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine.input_files import file_sha256
from engine.models.perceptron import relu_layers
from engine.solver.tracker_prior import LAG, anchor_index, features

#: Instants of readings one latent reads, :data:`LAG` frames apart, the current one first.
HISTORY = 8
#: Frames of readings one latent reads, the current one included (:func:`window_features`).
WINDOW = LAG * HISTORY + 1


def window_features(pos: np.ndarray, rot: np.ndarray, joints: Sequence[str]) -> np.ndarray:
    """Inputs ``(F, HISTORY D)`` of ``F`` windows of readings of ``joints``.

    Parameters
    ----------
    pos : ndarray (F, WINDOW, S, 3)
        World positions of the ``S`` tracked joints over each window, oldest first, metres
        (the window's first frame repeated before a clip's start).
    rot : ndarray (F, WINDOW, S, 4)
        Their world rotations (w, x, y, z).
    joints : sequence of str
        The tracked bank joints, an anchor among them.

    Returns
    -------
    ndarray (F, HISTORY D)
        The :func:`features` of the last frame, then of the frame :data:`LAG` before it,
        ..., each with the anchor's displacement over the :data:`LAG` frames before it.
    """
    a, f, s = anchor_index(joints), pos.shape[0], pos.shape[2]
    t = pos.shape[1] - 1 - LAG * np.arange(HISTORY)  # the instants, newest first
    # the F windows' instants as one batch of F * HISTORY frames: one call, not HISTORY
    x = features(pos[:, t].reshape(-1, s, 3), rot[:, t].reshape(-1, s, 4), a, pos[:, t - LAG, a].reshape(-1, 3))
    return x.reshape(f, -1)


@dataclass(frozen=True)
class TrackerNet:
    """One combination's network: input standardisation and the perceptron's layers
    (ReLU between them)."""

    joints: tuple[str, ...]
    mean: np.ndarray
    std: np.ndarray
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]

    def latents(self, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """Latents ``(F, L)`` of windows ``pos (F, WINDOW, S, 3)``, ``rot (F, WINDOW, S, 4)``."""
        return self.forward(window_features(pos, rot, self.joints))

    def forward(self, x: np.ndarray) -> np.ndarray:
        """Latents ``(F, L)`` of inputs ``(F, D)`` (:func:`window_features`)."""
        return relu_layers(((x - self.mean) / self.std).astype(np.float32), self.weights, self.biases)


@dataclass(frozen=True)
class TrackerNets:
    """The networks of several combinations and the VAE their latents belong to."""

    nets: dict[tuple[str, ...], TrackerNet]
    vae_sha256: str = ""

    def get(self, joints: Sequence[str]) -> TrackerNet | None:
        return self.nets.get(tuple(joints))

    def save(self, path: str | Path) -> None:
        """Write every network as plain arrays in one ``.npz``, atomically."""
        from engine.atomic import atomic_path

        arrays: dict[str, np.ndarray] = {"vae_sha256": np.array(self.vae_sha256)}
        for n, (joints, net) in enumerate(self.nets.items()):
            arrays[f"{n}/joints"] = np.array(",".join(joints))
            arrays[f"{n}/mean"], arrays[f"{n}/std"] = net.mean, net.std
            for i, (w, b) in enumerate(zip(net.weights, net.biases, strict=True)):
                arrays[f"{n}/w{i}"], arrays[f"{n}/b{i}"] = w.astype(np.float32), b.astype(np.float32)
        with atomic_path(path, suffix=".npz") as tmp:
            np.savez_compressed(tmp, **arrays)  # type: ignore[arg-type]  # numpy's stubs: **arrays could name allow_pickle

    @classmethod
    def load(cls, path: str | Path) -> TrackerNets:
        """Read a file written by :meth:`save` (plain arrays only, no pickles)."""
        from engine.errors import UserError

        try:
            with np.load(Path(path), allow_pickle=False) as z:
                nets = {}
                for n in range(len({k.split("/")[0] for k in z.files if "/" in k})):
                    joints = tuple(str(z[f"{n}/joints"]).split(","))
                    layers = sum(1 for k in z.files if k.startswith(f"{n}/w"))
                    nets[joints] = TrackerNet(
                        joints,
                        z[f"{n}/mean"].astype(np.float64),
                        z[f"{n}/std"].astype(np.float64),
                        tuple(z[f"{n}/w{i}"].astype(np.float32) for i in range(layers)),
                        tuple(z[f"{n}/b{i}"].astype(np.float32) for i in range(layers)),
                    )
                return cls(nets, str(z["vae_sha256"]))
        except (OSError, KeyError, ValueError) as exc:
            raise UserError(f"{path}: not a tracker network file ({exc})") from exc


#: The shipped networks (model card, "Tracker networks").
DEFAULT_TRACKER_NETS = Path(__file__).resolve().parents[2] / "assets" / "models" / "tracker_nets.npz"


@functools.cache
def default_tracker_nets(vae_path: str | Path | None = None) -> TrackerNets | None:
    """The shipped networks (read once per process), or None when the file is missing or
    was trained on the latents of another VAE than the one at ``vae_path`` (default: the
    shipped VAE)."""
    from engine.models.loading import DEFAULT_VAE

    vae = Path(vae_path) if vae_path is not None else DEFAULT_VAE
    if not (DEFAULT_TRACKER_NETS.is_file() and vae.is_file()):
        return None
    nets = TrackerNets.load(DEFAULT_TRACKER_NETS)
    return nets if nets.vae_sha256 == file_sha256(vae) else None
