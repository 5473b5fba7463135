"""SparsePoser's generator fed one frame at a time: each step encodes only the new frame.

**Encoder.** The three stride-2 skeletal convolutions have no padding on the right for
the last output of an even window, so the last output of level ``l`` at frame ``t``
reads its input at frames ``t - 2 s``, ``t - s``, ``t`` (kernel 3, ``s = 2**l``) and
nothing else. Sliding the window by one frame never changes an encoder output computed
before, only which ones the window holds (the window's outputs alternate between the
parities of ``t`` at level 0, four phases at level 1, eight at level 2). A step keeps
each level's recent outputs and computes one new output per level: a 1-row matrix
product instead of 16, 8 and 4 rows, and at level 0 only the rows of the six tracked
nodes (the others are zero).

**Decoder.** Temporal upsampling, the realtime tail and the convolution taps (with their
zero padding) act on time only, so for each level they are one small matrix over the
previous level's frames, built at load by running those same operations on an identity.
Working back from the last output frame, only the rows it reads are kept: two frames per
level, and the deepest level's last two outputs. The rows of each convolution matrix are
reordered (tap, node, channel) so a level is ``time matrix @ frames``, a reshape and one
product.

Before the first frame the history is that frame repeated, as the method's window is
at a clip's start; outputs near the window's left edge (zero padding there) are
outside the last frame's receptive field, so the pose equals the windowed decode
(tests check it to 1e-5 with the shipped weights).
"""

from __future__ import annotations

from collections import deque

import torch
from torch.nn import functional as F

from engine.models.sparseposer_infer import MARGIN, DenseGenerator, receptive_field, unfold_frames, upsample_frames


def streaming_generator(model, dense: DenseGenerator, context: int, sparse_index, tail: int):
    """A :class:`StreamingGenerator` for ``model``, or None where it would not give the
    windowed step's output: a kernel other than 3, or a trained window so short that
    the last frame reads its left zero padding (``receptive_field + MARGIN > window``)."""
    if dense.kernel != 3 or receptive_field(model) + MARGIN > model.config.window:
        return None
    return StreamingGenerator(dense, context, sparse_index, tail)


def _tap_major(d: torch.Tensor, n_in: int, k: int) -> torch.Tensor:
    """Rows of a dense convolution matrix from (node, tap, channel) to (tap, node, channel)."""
    return d.reshape(n_in, k, -1, d.shape[1]).transpose(0, 1).reshape(-1, d.shape[1]).contiguous()


def _time_map(frames: int, kernel: int, tail: int | None) -> torch.Tensor:
    """``(T', K, frames)``: the taps of each output frame of a decoder level (``tail``:
    upsampled by two and its last ``tail`` frames; ``None``: the output layer's last
    frame) as weights of the previous level's ``frames`` frames."""
    eye = torch.eye(frames, dtype=torch.float64)[:, None]  # (frames, 1 node, frames channels)
    if tail is None:
        taps = unfold_frames(eye[-(kernel // 2 + 1) :], kernel, 1)[-1:]
    else:
        taps = unfold_frames(upsample_frames(eye)[-tail:], kernel, 1)
    return taps.reshape(taps.shape[0], kernel, frames)


class StreamingGenerator:
    """The last output frame of ``dense``'s generator for a stream of sparse frames.

    Parameters
    ----------
    dense : DenseGenerator
        The generator's matrices.
    context : int
        Frames of the window it stands for (a multiple of 8): the decoder's first level
        sees the deepest level's last ``context / 8`` outputs.
    sparse_index : sequence of int
        The tracked nodes; a frame is given on these nodes only (zero elsewhere).
    tail : int
        Frames each decoder level decodes in the windowed step (8 in the method).
    """

    def __init__(self, dense: DenseGenerator, context: int, sparse_index, tail: int) -> None:
        k = dense.kernel
        if k != 3:  # with more taps an older output would read a newer frame
            raise ValueError(f"streaming needs kernel 3 (no padding read on the right), got {k}")
        self.slope = dense.slope
        self.enc = []
        for level, (d, b) in enumerate(dense.enc):
            n_in = 22 if level == 0 else dense.enc_nodes[level - 1]  # pooling is folded into d
            rows = d.reshape(n_in, k, -1, d.shape[1])
            if level == 0:
                rows = rows[list(sparse_index)]
            self.enc.append((_tap_major(rows.reshape(-1, d.shape[1]), rows.shape[0], k), b, 2**level))
        # decoder, from the output back: which frames of each level the last frame reads
        n_frames = [context // 8]
        for _ in dense.dec:
            n_frames.append(min(tail, 2 * n_frames[-1]))
        k = dense.dec_kernel
        maps = [_time_map(n_frames[i], k, tail) for i in range(len(dense.dec))] + [_time_map(n_frames[-1], k, None)]
        convs = list(dense.dec) + [dense.out]
        n_in = [dense.enc_nodes[-1]] + dense.dec_nodes
        need_out = [0]  # the output layer's single frame
        self.dec: list[tuple[torch.Tensor, torch.Tensor, torch.Tensor, int]] = []  # (w, d, b, rows) per level
        for i in range(len(maps) - 1, -1, -1):
            w = maps[i][need_out]  # (outputs, K, frames of the level below)
            need_in = torch.nonzero(w.abs().sum(dim=(0, 1)) > 0)[:, 0].tolist()
            taps = torch.nonzero(w.abs().sum(dim=(0, 2)) > 0)[:, 0].tolist()  # not only zero padding
            d, b = convs[i]
            d = _tap_major(d, n_in[i], k).reshape(k, -1, d.shape[1])[taps].reshape(-1, d.shape[1]).contiguous()
            w = w[:, taps][:, :, need_in].reshape(-1, len(need_in)).float()
            self.dec.insert(0, (w, d, b, len(need_out)))
            need_out = need_in
        self.deep = [n_frames[0] - 1 - j for j in need_out]  # deepest outputs read, frames before the newest
        self.lengths = [2 * 2**level + 1 for level in range(len(self.enc))] + [8 * max(self.deep) + 1]
        self._adds: list = []
        self.reset()

    def reset(self, static: list[torch.Tensor] | None = None) -> None:
        """Forget the stream (a new clip starts); ``static``: the generator's static
        features of the new skeletons (``(B, 22 | 14 | 9, C)``; kept when not given)."""
        self._hist: list[deque] | None = None
        if static is not None:
            self._adds = [s.reshape(s.shape[0], 1, -1) for s in static[::-1]] + [None]

    def _encode(self, level: int) -> torch.Tensor:
        d, b, s = self.enc[level]
        assert self._hist is not None  # the stream has started (__call__)
        h = self._hist[level]
        return F.leaky_relu(torch.addmm(b, torch.cat((h[-1 - 2 * s], h[-1 - s], h[-1]), dim=1), d), self.slope)

    def __call__(self, x: torch.Tensor) -> torch.Tensor:
        """Push frame ``x (B, len(sparse_index), 8)`` (normalised; B streams at once, as
        many as the static features given to :meth:`reset`) and return the last output
        frame ``(B, 22, 8)`` (normalised dq)."""
        x = x.reshape(x.shape[0], -1)
        if self._hist is None:  # the first frame stands for the whole past
            self._hist = [deque([x] * self.lengths[0], maxlen=self.lengths[0])]
            for level in range(len(self.enc)):
                out = self._encode(level)
                self._hist.append(deque([out] * self.lengths[level + 1], maxlen=self.lengths[level + 1]))
        else:
            self._hist[0].append(x)
            for level in range(len(self.enc)):
                self._hist[level + 1].append(self._encode(level))
        deep = self._hist[-1]
        h = torch.stack([deep[-1 - 8 * j] for j in self.deep], dim=1)  # (B, frames, nodes * C)
        batch = h.shape[0]
        for (w, d, b, rows), s in zip(self.dec, self._adds):
            y = torch.addmm(b, torch.matmul(w, h).reshape(batch * rows, -1), d).reshape(batch, rows, -1)
            h = y if s is None else F.leaky_relu(y, self.slope) + s
        return h.reshape(batch, 22, -1)
