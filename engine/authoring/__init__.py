"""Authoring: pose the character by joint targets, key a motion, re-solve a clip's range.

* :mod:`engine.authoring.character`: the canonical character at a height, posed by
  latent-space solves (grounded on the floor).
* :mod:`engine.authoring.targets`: joint targets as solver terms.
* :mod:`engine.authoring.keys`: keys and the in-between interpolation rules.
* :mod:`engine.authoring.document`: authoring scene files (scene format version 2).
* :mod:`engine.authoring.bake`: a scene to a motion; :mod:`engine.authoring.export`
  writes it as BVH (the ``bake`` command and the studio's export).
* :mod:`engine.authoring.pose_mode`: the continuous pose mode (options in
  :mod:`~engine.authoring.pose_options`, a scene's ``pose_options``); it poses the bake's
  keys too, dragging their targets as the pose window does (:mod:`~engine.authoring.pose_drag`).
* :mod:`engine.authoring.session`: the authoring model the pose window shows: every
  edit a command on its history (:mod:`~engine.authoring.history`, the state it records
  in :mod:`~engine.authoring.state`), typed events (:mod:`~engine.authoring.events`),
  joint turns (:mod:`~engine.authoring.turns`).
* :mod:`engine.authoring.range_edit`: re-solve a frame range of a clip.
* :mod:`engine.authoring.jobs`: the bake and range re-solves as jobs a worker thread runs,
  with progress and cancel (:mod:`~engine.progress`).
"""
