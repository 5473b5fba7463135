"""Smooth hand-over when a tracker reconnects (borrowed from RPM's idea that a
returning signal should be blended in, not snapped to).

For one tracker, :class:`SensorBlend` turns the raw stream (reading, connected) into
what the solver should use this frame:

* **Lost**: the tracker's term ends at once; the pose runs on the method's own
  prediction from that frame on.
* **Blend in** (the tracker returned): the target starts where the solved joint was on
  the frame before it returned and glides onto the tracker over ``seconds``: the
  target is ``tracker + (1 - s) * offset`` with ``offset`` the gap at reconnection and
  ``s`` a smoothstep from 0 to 1, so it follows the tracker's own motion meanwhile. The
  rotation term's weight rises with ``s``.

Why no blend *out* (holding a lost tracker's last target while its weight falls to 0
over ``seconds``): DragPoser's limb reach (``engine/solver/limb_ik.py``) places a
tracked wrist exactly on its target whatever the weight, so the wrist would stay pinned
to the held point while the body moves on and be let go at the end of the fade: a jump
inside the second after the loss. On 3-head-hands with ``--gaps`` (9 validation
files, 300 frames, FlowMDM's PJ / AUJ, docs/metrics.md) that fade made the losses worse
than no blending (PJ T-S 832 against 346, AUJ T-S 3927 against 2433); ending the term at
once keeps the no-blend figures for losses and the blend-in's gain for returns
(ablation in docs/optimizer.md, "Trackers that are lost and found").

``seconds <= 0`` passes the stream through unchanged (the jump).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def smoothstep(x: float) -> float:
    """``3x^2 - 2x^3`` on [0, 1], clamped."""
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x)


@dataclass
class BlendedTarget:
    """What the solver uses for one tracker this frame.

    Attributes
    ----------
    active : bool
        Whether the tracker's term is used at all.
    position : ndarray (3,)
        Target position, metres.
    weight : float
        Multiplier of the term's weight (0..1).
    rotation_weight : float
        Multiplier of the rotation term's weight (0..1).
    """

    active: bool
    position: np.ndarray
    weight: float = 1.0
    rotation_weight: float = 1.0


class SensorBlend:
    """Blend state of one tracker (frames counted at the clip's frame rate)."""

    def __init__(self) -> None:
        self.connected: bool | None = None
        self.frames = 0  # since the last change of state
        self.offset = np.zeros(3)

    def update(
        self, position: np.ndarray | None, connected: bool, solved: np.ndarray | None, seconds: float, fps: float
    ) -> BlendedTarget:
        """Advance one frame.

        Parameters
        ----------
        position : ndarray (3,) or None
            This frame's reading (ignored when not ``connected``, and may be None then).
        connected : bool
        solved : ndarray (3,) or None
            Where the solved joint was on the previous frame (None on the first frame).
        seconds : float
            Blend-in time; <= 0 disables blending.
        fps : float
            Frames per second of the stream.
        """
        position = np.asarray(position, dtype=np.float64)
        changed = self.connected is not None and connected != self.connected
        if self.connected is None:
            self.connected, self.frames = connected, 10**9  # no transition before the first frame
        elif changed:
            self.connected, self.frames = connected, 0
            if connected:
                self.offset = (solved - position) if solved is not None else np.zeros(3)
        self.frames += 1
        n = max(1.0, seconds * fps)
        s = smoothstep(self.frames / n) if seconds > 0 else 1.0
        if connected:
            return BlendedTarget(True, position + (1.0 - s) * self.offset, 1.0, s)
        return BlendedTarget(False, position, 0.0, 0.0)
