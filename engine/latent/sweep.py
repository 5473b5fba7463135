"""What each latent dimension does to the body.

* :func:`dimension_sweep`: the current latent decoded with one dimension at ``-2 sigma``,
  unchanged and ``+2 sigma`` (sigma: that dimension's standard deviation over the pose
  bank, :attr:`engine.latent.projection.LatentMap.sigma`), and which joints move most;
* :func:`joint_influence`: for one joint, the norm of the Jacobian of its world position
  with respect to each latent dimension (metres per latent unit): the dimensions that
  move it most, right at the current latent.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch

from engine import skeleton as sk
from engine.latent.forces import single_thread
from engine.progress import CancelCheck, check

if TYPE_CHECKING:
    from engine.solver.frame import FrameContext
    from engine.solver.optimizer import PoseOptimizer

#: Sweep offsets in units of the dimension's sigma.
OFFSETS = (-2.0, 0.0, 2.0)


@dataclass(frozen=True)
class Sweep:
    """Poses of a latent with each dimension swept.

    Attributes
    ----------
    offsets : ndarray (3,)
        Offsets in sigma units (:data:`OFFSETS`).
    poses : ndarray (L, 3, 22, 3)
        World joint positions, metres, of dimension ``d`` at each offset.
    motion : ndarray (L, 22)
        Largest distance, metres, a joint moves relative to the root between the
        unchanged pose and either swept one (a dimension that only shifts the body is
        not counted as moving the joints).
    """

    offsets: np.ndarray
    poses: np.ndarray
    motion: np.ndarray

    def top_joints(self, d: int, n: int = 3) -> list[str]:
        """Names of the ``n`` joints dimension ``d`` moves most, most first."""
        return [sk.JOINT_NAMES[i] for i in np.argsort(self.motion[d])[::-1][:n]]


def dimension_sweep(
    optimizer: "PoseOptimizer",
    ctx: "FrameContext",
    latent: np.ndarray,
    sigma: np.ndarray,
    offsets: tuple[float, ...] = OFFSETS,
    cancelled: CancelCheck | None = None,
) -> Sweep:
    """Decode ``latent (L,)`` with each dimension at ``offsets`` times ``sigma (L,)``.

    Parameters
    ----------
    optimizer : PoseOptimizer
        Decodes a latent in the frame's context.
    ctx : FrameContext
    latent : ndarray (L,)
    sigma : ndarray (L,)
        Each dimension's spread (standard deviation over the training latents).
    offsets : tuple of float
    cancelled : callable, optional
        Asked before each dimension; True raises :class:`engine.progress.Cancelled`.
    """
    z0 = np.asarray(latent, dtype=np.float32).ravel()
    sig = np.asarray(sigma, dtype=np.float32).ravel()
    L = z0.shape[0]
    poses = np.zeros((L, len(offsets), sk.NUM_JOINTS, 3))
    cache: dict[float, np.ndarray] = {}
    with torch.no_grad(), single_thread():
        for d in range(L):
            check(cancelled)
            for i, o in enumerate(offsets):
                if o == 0.0 and 0.0 in cache:
                    poses[d, i] = cache[0.0]
                    continue
                z = z0.copy()
                z[d] += o * sig[d]
                poses[d, i] = optimizer.decode(torch.from_numpy(z), ctx).positions.double().numpy()
                if o == 0.0:
                    cache[0.0] = poses[d, i]
    rel = poses - poses[:, :, :1]
    centre = list(offsets).index(0.0) if 0.0 in offsets else 0
    motion = np.linalg.norm(rel - rel[:, centre : centre + 1], axis=-1).max(axis=1)
    return Sweep(np.asarray(offsets, float), poses, motion)


def joint_influence(optimizer: "PoseOptimizer", ctx: "FrameContext", latent: np.ndarray, joint: str) -> np.ndarray:
    """Norm of ``d position(joint) / d z_d`` for each dimension ``d``, ``(L,)`` metres per
    latent unit, at ``latent (L,)``.

    Raises
    ------
    KeyError
        For a joint name outside the canonical skeleton.
    """
    j = sk.JOINT_INDEX[joint]
    z = torch.as_tensor(np.asarray(latent, dtype=np.float32).ravel())
    with torch.enable_grad(), single_thread():
        jac = torch.autograd.functional.jacobian(lambda v: optimizer.decode(v, ctx).positions[j], z)
    return np.linalg.norm(jac.double().numpy(), axis=0)


def most_influential(influence: np.ndarray, n: int = 5) -> list[int]:
    """The ``n`` dimensions of largest ``influence (L,)``, largest first."""
    return [int(i) for i in np.argsort(np.asarray(influence))[::-1][:n]]
