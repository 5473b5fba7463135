"""Training SparsePoser's learned IK on the frozen generator's realtime output.

The paper trains the limb networks on the generator's pose with the generator frozen
(sec. 5.3). The joint trainer (:mod:`engine.training.sparseposer`) updates both in
turn, feeding the limb networks the generator's output on the last ``ik_frames`` frames
of each window, which see ``ik_frames - 1`` future frames; the realtime method applies
them to the last frame only, which sees none and is the worst. With ``train_generator
= false`` and ``init = FILE`` the generator of ``FILE`` is kept and only the limb
networks are trained, on exactly what the method gives them: the generator's realtime
output at every training frame, computed once by streaming each clip from its first
frame as the method does (:class:`~engine.models.sparseposer_stream.StreamingGenerator`).
"""

from __future__ import annotations

import torch
from tqdm import tqdm

from engine.errors import UserError
from engine.models.sparseposer import SPARSE_INDEX, SparsePoser
from engine.models.sparseposer_infer import DenseGenerator, context_frames
from engine.models.sparseposer_stream import streaming_generator
from engine.training.common import start_from
from engine.training.data import PoseData

#: Decoder frames per level of the method's step (engine.methods.sparseposer.TAIL).
_TAIL = 8


@torch.no_grad()
def realtime_outputs(model: SparsePoser, data: PoseData, chunk: int = 256, progress: bool = True) -> torch.Tensor:
    """The generator's output ``(N, 22, 8)`` (normalised dq) at every frame of ``data`` as
    the realtime method computes it: each clip streamed from its first frame.

    The clips are cut into ``chunk``-frame pieces streamed side by side (one batch). A
    piece that does not start a clip is streamed from ``context`` frames earlier (its
    first frame repeated before that, as at a clip's start): the last output frame reads
    only the receptive field, shorter than ``context``, so its outputs are the whole
    clip's."""
    context = context_frames(model)
    stream = streaming_generator(model, DenseGenerator(model), context, SPARSE_INDEX, _TAIL)
    if stream is None:
        raise UserError("train_generator = false needs kernel 3 and a window longer than the receptive field + 8")
    sp = list(SPARSE_INDEX)
    x = (data.dq[:, sp] - model.dq_mean[sp]) / model.dq_std[sp]
    pieces = []  # (first streamed frame, first kept frame, end)
    clip = data.clip
    starts = [0] + (torch.nonzero(clip[1:] != clip[:-1])[:, 0] + 1).tolist() + [len(data)]
    for c0, c1 in zip(starts[:-1], starts[1:]):
        pieces += [(max(c0, s - context), s, min(s + chunk, c1)) for s in range(c0, c1, chunk)]
    first = torch.tensor([p[0] for p in pieces])
    ends = torch.tensor([p[2] for p in pieces])
    stream.reset(model.generator.static_features(data.offsets[first]))
    out = torch.empty(len(data), *data.dq.shape[1:])
    steps = int((ends - first).max())
    for t in tqdm(range(steps), desc="generator outputs", unit="step", disable=not progress, leave=False):
        frame = torch.minimum(first + t, ends - 1)  # a finished piece repeats its last frame (not kept)
        y = stream(x[frame])
        keep = [i for i, (f, s, e) in enumerate(pieces) if s <= f + t < e]
        out[frame[keep]] = y[keep]
    return out


def load_init(model: SparsePoser, path: str) -> None:
    """Copy the weights of ``path`` (a SparsePoser file of the same architecture) into ``model``."""
    from engine.models.loading import load_sparseposer

    if not path:
        raise UserError(
            "train_generator = false needs init = a SparsePoser weights file (e.g. assets/models/sparseposer.pt)"
        )
    start_from(model, path, load_sparseposer)
