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
``defer=True`` keeps the run's inputs as they are then and leaves the run for later. A
run is done in pieces (with a predictor that offers ``encode_past`` and ``next_latent``,
as :class:`engine.models.predictor.TemporalPredictor` does): the encoder, then one
decoder step at a time. :meth:`TemporalSchedule.run_pending`, which a live loop calls
once a frame's pose is out, does one piece; a :meth:`~TemporalSchedule.prediction` call
does whatever its frame still needs. The encoder only reads the history, which is fixed
from the frame it was last recorded at, so ``run_pending`` with no run in progress
encodes the current history ahead of the block that will need it. The pieces are the
operations :meth:`~engine.models.predictor.TemporalPredictor.predict` performs, on the
same inputs, so the latents are the same as when the whole run happens at once; only
the time at which it happens changes (a test compares them). With six trackers (``W_f =
1``) the predictor then costs at most one piece (encoder or one decoder step) between
two frames instead of the whole run inside every fourth frame; with fewer trackers
(``W_f = 16``) the sixteen decoder steps spread over the frames that need them.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from typing import Protocol, runtime_checkable

import torch


class LatentPredictor(Protocol):
    """What the optimizer needs from the temporal predictor."""

    def predict(
        self, past_latents: torch.Tensor, past_cond: torch.Tensor, first: torch.Tensor, steps: int
    ) -> torch.Tensor:
        """``past_latents (B, W_p, L)``, ``past_cond (B, W_p, C)``, ``first (B, L)`` ->
        the next ``steps`` latents ``(B, steps, L)``."""
        ...


@runtime_checkable
class SteppedPredictor(LatentPredictor, Protocol):
    """A predictor that can also run in pieces between frames: its encoder on the past
    once, then one latent at a time (:class:`engine.models.predictor.TemporalPredictor`)."""

    def encode_past(self, past: torch.Tensor, cond: torch.Tensor) -> torch.Tensor:
        """``past (B, W_p, L)``, ``cond (B, W_p, C)`` -> the encoder's memory."""
        ...

    def next_latent(self, tokens: torch.Tensor, memory: torch.Tensor) -> torch.Tensor:
        """The latents so far ``tokens (B, T, L)`` and ``memory`` -> the next latent ``(B, L)``."""
        ...


def _join(*warnings: str) -> str:
    return "; ".join(w for w in warnings if w)


class _Run:
    """One predictor run (a block of ``steps`` latents from ``first_step``), in pieces."""

    def __init__(
        self, predictor: LatentPredictor, inputs: tuple, first_step: int, steps: int, memory: torch.Tensor | None = None
    ) -> None:
        self.predictor, self.inputs, self.first_step, self.steps = predictor, inputs, first_step, steps
        self.stepped = predictor if isinstance(predictor, SteppedPredictor) else None
        self.split = self.stepped is not None
        self.memory = memory if self.split else None
        self.tokens: torch.Tensor | None = None
        self.done = 0
        self.failed = False

    @property
    def finished(self) -> bool:
        return self.failed or self.done >= self.steps

    def covers(self, step: int) -> bool:
        return self.first_step <= step < self.first_step + self.steps

    def piece(self, cache: dict[int, torch.Tensor]) -> str:
        """Do the next piece (the whole run for a predictor without pieces), put finished
        latents into ``cache``; a warning ('' if none)."""
        past, cond, first = self.inputs
        try:
            with torch.no_grad():
                stepped = self.stepped
                if stepped is None:
                    out = self.predictor.predict(past, cond, first, self.steps)
                elif self.memory is None:
                    self.memory = stepped.encode_past(past, cond)
                    return ""
                else:
                    tokens = first[:, None] if self.tokens is None else self.tokens
                    nxt = stepped.next_latent(tokens, self.memory)
                    self.tokens = torch.cat((tokens, nxt[:, None]), dim=1)
                    out = nxt[:, None]
        except Exception as exc:  # a broken predictor must not stop the reconstruction
            self.failed = True
            return f"temporal predictor failed ({exc}); no prior this frame"
        # a predictor trained for a shorter horizon may return fewer than ``steps`` latents
        if out.ndim != 3 or out.shape[1] < 1 or out.shape[2] != past.shape[-1] or not bool(torch.isfinite(out).all()):
            self.failed = True
            return "temporal predictor returned an unusable prediction; no prior this frame"
        for s in range(min(self.steps - self.done, out.shape[1])):
            cache[self.first_step + self.done] = out[0, s].detach()
            self.done += 1
        if not self.split:
            self.done = self.steps
        return ""

    def finish(self, cache: dict[int, torch.Tensor]) -> str:
        warning = ""
        while not self.finished and not warning:
            warning = self.piece(cache)
        return warning


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
        self.history: deque[tuple[torch.Tensor, torch.Tensor | Callable[[], torch.Tensor]]] = deque(maxlen=self.past)
        self.cache: dict[int, torch.Tensor] = {}
        self.last: torch.Tensor | None = None
        self.run: _Run | None = None  # the block in progress
        self.version = 0  # changes with the history
        self.memory: tuple[int, torch.Tensor] | None = None  # the encoder's output for a history version
        self.predictor: LatentPredictor | None = None
        self.pending_warning = ""

    def configure(self, every: int, past: int) -> None:
        """Apply new ``n`` / ``W_p``; history is kept when only its length changes."""
        if every != self.every:
            self.every = every
            self.cache.clear()
            self.run = None  # its latents would go where the cache was cleared
        if past != self.past:
            self.past = past
            self.history = deque(self.history, maxlen=past)
            self.version += 1

    def record(self, frame: int, latent: torch.Tensor, cond: torch.Tensor | Callable[[], torch.Tensor]) -> None:
        """Remember frame ``frame``'s solved ``latent (L,)`` and conditioning ``cond (C,)``,
        or a function returning it, called only when the predictor needs it."""
        self.last = latent.detach()
        if frame % self.every == 0:
            self.history.append((latent.detach(), cond.detach() if isinstance(cond, torch.Tensor) else cond))
            self.version += 1

    @property
    def pending(self) -> bool:
        """Whether a block is still (partly) to be run."""
        return self.run is not None and not self.run.finished

    def prediction(
        self, frame: int, predictor: LatentPredictor | None, future: int, defer: bool = False
    ) -> tuple[torch.Tensor | None, str]:
        """Latent guiding ``frame`` and a warning ('' if none); runs the predictor if due.

        Call once per frame, before solving it and after recording the previous frame.
        With ``defer``, a block due now for later frames is left to :meth:`run_pending`
        and to the frames that need it.
        """
        carried, self.pending_warning = self.pending_warning, ""  # from pieces run between frames
        self.predictor = predictor
        if predictor is None or not self.history or self.last is None:
            return None, carried
        j = math.ceil(frame / self.every)  # the frame's predictor step (module doc)
        for k in [k for k in self.cache if k < j]:
            del self.cache[k]
        warning = ""
        run = self.run
        if run is not None and run.covers(j) and j not in self.cache:  # this frame's latent, if still due
            while not run.finished and j not in self.cache and not warning:
                warning = run.piece(self.cache)
        if frame % self.every == 0 and j % future == 0:
            if run is not None:  # (normally done by now)
                warning = _join(warning, run.finish(self.cache))
            self.run = _Run(predictor, self._inputs(), j + 1, future, self._memory())
            if not defer:
                warning = _join(warning, self.run.finish(self.cache))
        if j not in self.cache and not warning:
            warning = _Run(predictor, self._inputs(), j, future, self._memory()).finish(self.cache)
        return self.cache.get(j), _join(carried, warning)

    def run_pending(self) -> None:
        """One piece of work that can wait (between frames): the next piece of the block
        in progress, else the encoder on the current history for the next block (its
        warning, if any, comes with the next :meth:`prediction`)."""
        if self.pending:
            assert self.run is not None
            self.pending_warning = _join(self.pending_warning, self.run.piece(self.cache))
        elif (
            isinstance(self.predictor, SteppedPredictor)
            and self.history
            and self.last is not None
            and (self.memory is None or self.memory[0] != self.version)
        ):
            past, cond, _ = self._inputs()
            try:
                with torch.no_grad():
                    self.memory = (self.version, self.predictor.encode_past(past, cond))
            except Exception:  # the run itself will try again and warn
                self.memory = None

    def _memory(self) -> torch.Tensor | None:
        """The encoder's output for the current history, if it was computed ahead."""
        return self.memory[1] if self.memory is not None and self.memory[0] == self.version else None

    def _inputs(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """The predictor's inputs now: past latents ``(1, W_p, L)``, their conditioning
        ``(1, W_p, C)`` and the latest latent ``(1, L)``."""
        hist = list(self.history)
        hist = [hist[0]] * (self.past - len(hist)) + hist
        past = torch.stack([h[0] for h in hist])[None]
        cond = torch.stack([h[1] if isinstance(h[1], torch.Tensor) else h[1]().detach() for h in hist])[None]
        assert self.last is not None
        return past, cond, self.last[None]
