"""research/oracle_prior.py: the oracle answers each predictor step with that step's true latent."""

from __future__ import annotations

import torch

from .script_loader import load_script


def _script():
    return load_script("oracle_prior")


def test_a_run_of_the_schedule_gets_the_true_latents_of_its_own_steps():
    op = _script()
    from engine.solver import temporal

    piece = temporal._Run.piece
    try:
        op._tracking_runs()
        latents = torch.arange(40, dtype=torch.float32)[:, None].repeat(1, 3)  # frame i -> latent (i, i, i)
        oracle = op.OraclePredictor(latents.numpy(), every=4)
        inputs = (torch.zeros(1, 16, 3), torch.zeros(1, 16, 2), torch.zeros(1, 3))
        cache: dict[int, torch.Tensor] = {}
        run = temporal._Run(oracle, inputs, 5, 3)  # steps 5, 6, 7 -> frames 20, 24, 28
        assert run.finish(cache) == ""
        assert sorted(cache) == [5, 6, 7]
        assert [float(cache[k][0]) for k in (5, 6, 7)] == [20.0, 24.0, 28.0]
        # past the clip's end the last frame's latent answers
        cache.clear()
        temporal._Run(oracle, inputs, 9, 2).finish(cache)
        assert [float(cache[k][0]) for k in (9, 10)] == [36.0, 39.0]
    finally:
        temporal._Run.piece = piece
