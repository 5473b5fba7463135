"""Learned models: the pose VAE (:mod:`engine.models.vae`, skeletal layers in
:mod:`engine.models.skeletal`), the temporal predictor (:mod:`engine.models.predictor`)
and the checked loading of weights files (:mod:`engine.models.loading`).

The shipped weights in ``assets/models`` must keep loading with this code: changing a
layer's name or shape in ``vae.py``/``skeletal.py``/``predictor.py`` means retraining.
``PoseVAE.encode(dq) -> (mu, logvar)``, ``PoseVAE.decode(z) -> (rot, disp)`` and
``TemporalPredictor.predict(past, cond, first, steps)`` are the interfaces the rest of
the engine uses.
"""

from engine.models.loading import (
    DEFAULT_PREDICTOR,
    DEFAULT_VAE,
    ModelBundle,
    load_default_models,
    load_models,
    load_predictor,
    load_vae,
)
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.vae import PoseVAE, VAEConfig

__all__ = [
    "DEFAULT_PREDICTOR",
    "DEFAULT_VAE",
    "ModelBundle",
    "PoseVAE",
    "PredictorConfig",
    "TemporalPredictor",
    "VAEConfig",
    "load_default_models",
    "load_models",
    "load_predictor",
    "load_vae",
]
