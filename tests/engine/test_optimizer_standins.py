"""Stand-in models for the optimizer tests (no tests here): small torch modules with the
interfaces of ``PoseVAE.decode`` and ``TemporalPredictor.predict``."""

from __future__ import annotations

import torch

from engine.kinematics import quaternion as Q


class MLPDecoder(torch.nn.Module):
    """Random MLP latent -> (unit quaternions (B, 22, 4), displacement (B, 3) metres).

    Rotations stay within roughly 40 degrees of identity so decoded poses look human-ish."""

    def __init__(self, latent: int = 24, hidden: int = 64, seed: int = 0) -> None:
        super().__init__()
        g = torch.Generator().manual_seed(seed)
        self.l1 = torch.nn.Linear(latent, hidden)
        self.l2 = torch.nn.Linear(hidden, 22 * 4 + 3)
        with torch.no_grad():
            for p in self.parameters():
                p.copy_(torch.randn(p.shape, generator=g) * 0.3)

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        out = self.l2(torch.tanh(self.l1(z)))
        q = 0.3 * out[:, :88].reshape(-1, 22, 4) + torch.tensor([1.0, 0.0, 0.0, 0.0])
        return Q.canonicalize(Q.normalize(q)), 0.01 * out[:, 88:]


class NaNBeyond(MLPDecoder):
    """Decodes NaN once any latent component leaves [-limit, limit] (to test fallbacks)."""

    def __init__(self, limit: float = 0.5) -> None:
        super().__init__()
        self.limit = limit

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        rot, disp = super().decode(z)
        bad = (z.abs() > self.limit).any()
        return torch.where(bad, torch.full_like(rot, float("nan")), rot), disp


class CountingPredictor:
    """Predicts ``first`` repeated, records every call's frame-independent arguments."""

    def __init__(self) -> None:
        self.calls: list[tuple[tuple[int, ...], tuple[int, ...], int]] = []

    def predict(
        self, past_latents: torch.Tensor, past_cond: torch.Tensor, first: torch.Tensor, steps: int
    ) -> torch.Tensor:
        self.calls.append((tuple(past_latents.shape), tuple(past_cond.shape), steps))
        return first[:, None].expand(first.shape[0], steps, first.shape[1]).clone()
