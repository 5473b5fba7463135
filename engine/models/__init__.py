"""Learned models: the pose VAE (:mod:`engine.models.vae`, skeletal layers in
:mod:`engine.models.skeletal`) and the temporal predictor.

NOTE for whoever works on the models: ``vae.py``, ``skeletal.py`` and the VAE training
(``engine/training/{common,data,vae}.py``, ``engine/cli/train.py``) are written and the
default VAE is training now from them (``runs/vae``, started 07:45 by the lead). Please
do not rewrite or rename them: the shipped weights must load with this code. Build the
temporal predictor (``predictor.py``, ``engine/training/predictor.py``), loading
(``load_default_models``) and the autoencoder method against ``PoseVAE.encode(dq) ->
(mu, logvar)`` and ``PoseVAE.decode(z) -> (rot, disp)``.
"""
