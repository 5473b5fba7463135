"""The autoencoder ceiling: ground truth -> VAE encoder (mean) -> decoder -> pose.

No sensor-driven method built on the pose VAE can be more accurate than the VAE's own
reconstruction of the true pose, so this method measures that ceiling. It cheats on
purpose (``needs_ground_truth``): :meth:`AutoencoderMethod.reset` receives the reference
clip and encodes all of it at once. The root follows the ground truth's world position
and rotation, as a perfect hip sensor would; every other joint takes the decoded local
rotation. The decoded root displacement is not used (integrating it would drift and
measure something else).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import torch

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics.features import encoder_input, pose_from_motion
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult, Method, SensorFrame
from engine.motion.clip import Motion


class AutoencoderMethod(Method):
    """Reconstruct each frame of a reference clip through the pose VAE.

    Parameters
    ----------
    vae : PoseVAE, optional
        The model (``engine.models.PoseVAE``); default: the shipped one.
    vae_path : path, optional
        Load the model from this weights file instead.
    batch : int
        Frames encoded per forward pass in :meth:`reset`.
    **_unused
        Settings meant for optimising methods (``mode``, ``iterations``...), ignored so
        the registry can pass every method the same keywords.
    """

    name = "autoencoder"
    needs_ground_truth = True

    def __init__(self, vae: Any = None, batch: int = 4096, vae_path: Any = None, **_unused: Any) -> None:
        if vae is None and vae_path is not None:
            from engine.models import load_models

            vae = load_models(vae_path).vae
        if vae is None:
            from engine.models import load_default_models

            vae = load_default_models().vae
        self.vae = vae.eval().requires_grad_(False)
        self.batch = batch
        self._local: np.ndarray | None = None
        self._root: np.ndarray | None = None
        self._latent: np.ndarray | None = None
        self._ms = 0.0
        self._frame = 0
        self.skeleton = sk.Skeleton.canonical()

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        """Encode and decode the whole ``reference`` clip (required) for ``skeleton``.

        Raises
        ------
        UserError
            Without a reference clip.
        """
        if reference is None:
            raise UserError("the autoencoder method needs the ground-truth clip (reference=...)")
        t0 = time.perf_counter()
        self.skeleton = skeleton
        local = torch.as_tensor(reference.local_rot, dtype=torch.float64)
        root = torch.as_tensor(reference.root_pos, dtype=torch.float64)
        offsets = torch.as_tensor(skeleton.offsets, dtype=torch.float64)
        rot, disp = pose_from_motion(local, root)
        dq = encoder_input(rot, disp, offsets.expand(rot.shape[0], -1, -1)).float()
        decoded, latents = [], []
        with torch.no_grad():
            for s in range(0, dq.shape[0], self.batch):
                mu, _ = self.vae.encode(dq[s : s + self.batch])
                r, _ = self.vae.decode(mu)
                decoded.append(r.double())
                latents.append(mu.double())
        out = torch.cat(decoded).numpy() if decoded else np.zeros((0, sk.NUM_JOINTS, 4))
        # the root keeps its true world rotation (a hip sensor's), the rest is decoded
        out[:, 0] = reference.local_rot[:, 0]
        self._local = out
        self._root = np.asarray(reference.root_pos, dtype=np.float64)
        self._latent = torch.cat(latents).numpy() if latents else None
        self._ms = 1000.0 * (time.perf_counter() - t0) / max(1, len(reference))
        self._frame = 0

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        """The reconstruction of frame ``sensors.frame`` (the sensors themselves are unused)."""
        if self._local is None or self._root is None:
            raise UserError("autoencoder method: reset(..., reference=clip) must be called first")
        i = min(int(sensors.frame), len(self._local) - 1)
        local, root = self._local[i], self._root[i]
        pos, _ = fk(local, root, self.skeleton.offsets)
        latent = self._latent[i] if self._latent is not None else None
        return FrameResult(local.copy(), root.copy(), pos, latent=latent, ms=self._ms)


def create(**kwargs: Any) -> AutoencoderMethod:
    """Registry factory: the autoencoder ceiling with the shipped VAE.

    Optimizer settings (``mode``, ``iterations``, ...) mean nothing here and are ignored."""
    return AutoencoderMethod(**kwargs)
