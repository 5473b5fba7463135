"""The temporal predictor of DragPoser (Ponton et al. 2024, sec. 4.3, Algorithm 1).

A Transformer encoder-decoder that runs every ``n = 4`` frames. The encoder reads the
``Wp = 16`` past latents (one every n frames, the newest last), each concatenated with a
conditioning vector: the root displacement summed over those n frames (metres, in the
heading frame of each frame) and the heights above the floor of the root, head, hands and
feet (:data:`engine.skeleton.HEIGHT_JOINTS`). The decoder starts from the latent of the
current step and predicts the following latents autoregressively (causal mask).
Latents are standardised with dataset statistics stored as buffers.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from engine.models.config import ModelConfig


@dataclass
class PredictorConfig(ModelConfig):
    latent: int = 24
    cond: int = 9
    d_model: int = 48
    heads: int = 4
    encoder_layers: int = 3
    decoder_layers: int = 3
    feedforward: int = 2048
    dropout: float = 0.1
    past: int = 16  # Wp
    future: int = 16  # Wf used in training (max decoder length)
    stride: int = 4  # n


class TemporalPredictor(nn.Module):
    """Predicts future latents from past latents and root/heights conditioning."""

    # buffers (register_buffer in __init__), declared for the type checker
    z_mean: torch.Tensor
    z_std: torch.Tensor
    c_mean: torch.Tensor
    c_std: torch.Tensor

    def __init__(self, config: PredictorConfig | None = None):
        super().__init__()
        self.config = cfg = config or PredictorConfig()
        self.enc_in = nn.Linear(cfg.latent + cfg.cond, cfg.d_model)
        self.dec_in = nn.Linear(cfg.latent, cfg.d_model)
        self.enc_pos = nn.Parameter(torch.zeros(cfg.past, cfg.d_model))
        self.dec_pos = nn.Parameter(torch.zeros(cfg.future + 1, cfg.d_model))
        nn.init.normal_(self.enc_pos, std=0.02)
        nn.init.normal_(self.dec_pos, std=0.02)
        self.transformer = nn.Transformer(
            d_model=cfg.d_model,
            nhead=cfg.heads,
            num_encoder_layers=cfg.encoder_layers,
            num_decoder_layers=cfg.decoder_layers,
            dim_feedforward=cfg.feedforward,
            dropout=cfg.dropout,
            batch_first=True,
        )
        self.out = nn.Linear(cfg.d_model, cfg.latent)
        self.register_buffer("z_mean", torch.zeros(cfg.latent))
        self.register_buffer("z_std", torch.ones(cfg.latent))
        self.register_buffer("c_mean", torch.zeros(cfg.cond))
        self.register_buffer("c_std", torch.ones(cfg.cond))

    def set_stats(self, z_mean, z_std, c_mean, c_std) -> None:
        for name, v in (("z_mean", z_mean), ("z_std", z_std), ("c_mean", c_mean), ("c_std", c_std)):
            getattr(self, name).copy_(
                torch.as_tensor(v, dtype=torch.float32).clamp_min(1e-6)
                if "std" in name
                else torch.as_tensor(v, dtype=torch.float32)
            )

    def encode_past(self, past: torch.Tensor, cond: torch.Tensor) -> torch.Tensor:
        """Memory ``(B, Wp, d)`` from past latents ``(B, Wp, L)`` and conditioning ``(B, Wp, C)``."""
        x = torch.cat(((past - self.z_mean) / self.z_std, (cond - self.c_mean) / self.c_std), dim=-1)
        h = self.enc_in(x) + self.enc_pos[-past.shape[1] :]
        return self.transformer.encoder(h)

    def decode_steps(self, tokens: torch.Tensor, memory: torch.Tensor) -> torch.Tensor:
        """Next latent after each decoder input token: ``tokens (B, T, L)`` -> ``(B, T, L)``.

        The prediction is a residual on the token it follows, in standardised units."""
        t = tokens.shape[1]
        zn = (tokens - self.z_mean) / self.z_std
        h = self.dec_in(zn) + self.dec_pos[:t]
        mask = nn.Transformer.generate_square_subsequent_mask(t, device=tokens.device)
        y = self.transformer.decoder(h, memory, tgt_mask=mask, tgt_is_causal=True)
        return (zn + self.out(y)) * self.z_std + self.z_mean

    @torch.no_grad()
    def predict(self, past: torch.Tensor, cond: torch.Tensor, first: torch.Tensor, steps: int) -> torch.Tensor:
        """Autoregressive prediction of ``steps`` latents ``(B, steps, L)`` after ``first (B, L)``.

        Horizons beyond the trained decoder length (``config.future``; DragPoser runs up
        to 60 steps with sparse sets) continue with a sliding window: the decoder sees
        the last ``future`` tokens, at the positions it was trained on."""
        memory = self.encode_past(past, cond)
        tokens = first[:, None]
        outs = []
        for _ in range(steps):
            nxt = self.next_latent(tokens, memory)
            outs.append(nxt)
            tokens = torch.cat((tokens, nxt[:, None]), dim=1)
        return torch.stack(outs, dim=1)

    @torch.no_grad()
    def next_latent(self, tokens: torch.Tensor, memory: torch.Tensor) -> torch.Tensor:
        """One step of :meth:`predict`: the latent ``(B, L)`` after ``tokens (B, T, L)``
        (the first latent, then the predicted ones) given the encoder's ``memory``.
        The solver's schedule calls :meth:`encode_past` and this step by step to spread a
        run over the time between frames; the latents are those of :meth:`predict`."""
        return self.decode_steps(tokens[:, -self.config.future :], memory)[:, -1]
