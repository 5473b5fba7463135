"""Latent-space debugging, Qt-free: where a frame's latent sits and what moves it.

* :mod:`~engine.latent.projection` — the fixed 2D map of the latent space (PCA of the
  pose bank's latents, shipped as ``assets/models/latent_map.npz``) and the training
  density in it; numpy only.
* :mod:`~engine.latent.readouts` — prior readouts per frame (distance to the nearest
  training latent, norm, distance from the prior latent) and the flag rule; numpy only.
* :mod:`~engine.latent.probe` — readouts and map coordinates of a method's frames (and
  of the :class:`~engine.methods.solve_record.SolveRecord` DragPoser keeps of its last solve).
* :mod:`~engine.latent.forces` — each loss term's force on the latent per iteration.
* :mod:`~engine.latent.sweep` — the dimension sweep and per-joint influence.
* :mod:`~engine.latent.trace` — a clip reconstructed frame by frame and probed.
* :mod:`~engine.latent.report` — the ``latent`` command's figure and JSON.

Submodules are imported where used (the package import stays torch-free).
"""
