"""research/bank_ema.py: the bank's prior latent averaged over time, restarted after
frames the bank did not answer; the predictor's prior untouched."""

from __future__ import annotations

import torch

from .script_loader import load_script


def test_the_bank_latent_is_averaged_and_restarts_after_a_gap():
    ema = load_script("bank_ema")
    answers = iter([torch.tensor([1.0]), torch.tensor([3.0]), None, torch.tensor([5.0]), torch.tensor([7.0])])

    def latent(self, frame, s, readings):
        return next(answers), 0.1, []

    class Source:
        pass

    f = ema.averaged(latent, 0.5)
    src = Source()
    got = [
        f(src, 1, None, "bank"),
        f(src, 2, None, "bank"),
        f(src, 3, None, None),
        f(src, 4, None, "bank"),
        f(src, 5, None, "bank"),
    ]
    assert got[0][0].item() == 1.0 and got[1][0].item() == 2.0  # 0.5 * 1 + 0.5 * 3
    assert got[2][0] is None  # the predictor's turn: nothing averaged
    assert got[3][0].item() == 5.0 and got[4][0].item() == 6.0  # restarted after the gap
