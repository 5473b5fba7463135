"""When the temporal predictor runs and which of its latents guides which frame.

DragPoser (Ponton et al. 2024, sec. 4.3 and Algorithm 1) runs the predictor every
``n`` frames (n = 4). With the predictor index ``j = ceil(i / n)`` of frame ``i``, a new
prediction block starts at every frame ``i = n * p`` with ``p % W_f == 0``: the encoder
sees the latents of the past ``W_p`` predictor steps (frames ``n * k``, ``p - W_p <= k
< p``) with their conditioning, and the decoder, started from the latest solved latent,
rolls out ``W_f`` latents for steps ``p + 1 .. p + W_f``. Frame ``i`` is guided by the
latent of step ``j``, so the frames ``n(j-1)+1 .. n*j`` share one target.

Two practical details the paper leaves open:

* the block's first latent should be ``z(n * p)``, which is the frame being solved;
  we use the latest solved latent ``z(n * p - 1)`` instead;
* at the start of a clip (or after a failed prediction) there is no block covering
  step ``j``; one is started at once from whatever history exists (the oldest entry is
  repeated to fill ``W_p``). Frame 0 has no history and hence no prediction.

The block started at frame ``n * p`` guides frames ``n * p + 1`` onwards, not frame
``n * p`` itself (its step ``j = p`` was predicted by the block before). So its run can
wait until frame ``n * p`` is solved: :meth:`TemporalSchedule.prediction` called with
``defer=True`` keeps the run's inputs as they are then and leaves the run to
:meth:`TemporalSchedule.run_pending`, which a live loop calls once the frame's pose is
out (the predictor then costs no latency), or to the next :meth:`prediction` call,
which runs it first. Either way the predictor sees the same inputs and gives the same
latents as when it runs at once.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Protocol

import torch


class LatentPredictor(Protocol):
    """What the optimizer needs from the temporal predictor."""

    def predict(self, past_latents: torch.Tensor, past_cond: torch.Tensor, first: torch.Tensor,
                steps: int) -> torch.Tensor:  # fmt: skip
        """``past_latents (B, W_p, L)``, ``past_cond (B, W_p, C)``, ``first (B, L)`` ->
        the next ``steps`` latents ``(B, steps, L)``."""
        ...


class TemporalSchedule:
    """Predictor bookkeeping for one clip (see the module doc).

    Parameters
    ----------
    every : int
        ``n``: frames between predictor steps.
    past : int
        ``W_p``: past predictor steps given to the encoder.
    """

    def __init__(self, every: int = 4, past: int = 16) -> None:
        self.every = every
        self.past = past
        self.reset()

    def reset(self) -> None:
        self.history: deque[tuple[torch.Tensor, torch.Tensor]] = deque(maxlen=self.past)
        self.cache: dict[int, torch.Tensor] = {}
        self.last: torch.Tensor | None = None
        self.pending: tuple | None = None  # a deferred run: (predictor, inputs, first step, steps)
        self.pending_warning = ""

    def configure(self, every: int, past: int) -> None:
        """Apply new ``n`` / ``W_p``; history is kept when only its length changes."""
        if every != self.every:
            self.every = every
            self.cache.clear()
            self.pending = None  # its latents would have been cleared with the cache
        if past != self.past:
            self.past = past
            self.history = deque(self.history, maxlen=past)

    def record(self, frame: int, latent: torch.Tensor, cond: torch.Tensor) -> None:
        """Remember frame ``frame``'s solved ``latent (L,)`` and conditioning ``cond (C,)``."""
        self.last = latent.detach()
        if frame % self.every == 0:
            self.history.append((latent.detach(), cond.detach()))

    def step_of(self, frame: int) -> int:
        return math.ceil(frame / self.every)

    def prediction(self, frame: int, predictor: LatentPredictor | None, future: int,
                   defer: bool = False) -> tuple[torch.Tensor | None, str]:  # fmt: skip
        """Latent guiding ``frame`` and a warning ('' if none); runs the predictor if due.

        Call once per frame, before solving it and after recording the previous frame.
        With ``defer``, a due run for later frames is kept for :meth:`run_pending`.
        """
        self.run_pending()
        carried, self.pending_warning = self.pending_warning, ""  # a deferred run's, reported now
        if predictor is None or not self.history or self.last is None:
            return None, carried
        j = self.step_of(frame)
        warning = ""
        for k in [k for k in self.cache if k < j]:
            del self.cache[k]
        if frame % self.every == 0 and j % future == 0:
            if defer:
                self.pending = (predictor, self._inputs(), j + 1, future)
            else:
                warning = self._run(predictor, self._inputs(), j + 1, future)
        if j not in self.cache and not warning:
            warning = self._run(predictor, self._inputs(), j, future)
        return self.cache.get(j), "; ".join(w for w in (carried, warning) if w)

    def run_pending(self) -> None:
        """Run a deferred prediction now, if there is one (its warning, if any, comes
        with the next :meth:`prediction`)."""
        if self.pending is not None:
            predictor, inputs, first_step, future = self.pending
            self.pending = None
            self.pending_warning = self._run(predictor, inputs, first_step, future)

    def _inputs(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """The predictor's inputs now: past latents ``(1, W_p, L)``, their conditioning
        ``(1, W_p, C)`` and the latest latent ``(1, L)``."""
        hist = list(self.history)
        hist = [hist[0]] * (self.past - len(hist)) + hist
        past = torch.stack([h[0] for h in hist])[None]
        cond = torch.stack([h[1] for h in hist])[None]
        assert self.last is not None
        return past, cond, self.last[None]

    def _run(self, predictor: LatentPredictor, inputs: tuple, first_step: int, future: int) -> str:
        past, cond, first = inputs
        try:
            with torch.no_grad():
                out = predictor.predict(past, cond, first, future)
        except Exception as exc:  # a broken predictor must not stop the reconstruction
            return f"temporal predictor failed ({exc}); no prior this frame"
        # a predictor trained for a shorter horizon may return fewer than ``future`` steps
        if out.ndim != 3 or out.shape[1] < 1 or out.shape[2] != past.shape[-1] or not bool(torch.isfinite(out).all()):
            return "temporal predictor returned an unusable prediction; no prior this frame"
        for s in range(min(future, out.shape[1])):
            self.cache[first_step + s] = out[0, s].detach()
        return ""
