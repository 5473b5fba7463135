"""The studio's Qt-free core: one contract between the window and the engine thread.

* :mod:`engine.studio.session`: :class:`~engine.studio.session.Session`, the model. The GUI
  changes the scene only through its methods; each change fires a typed event
  (:mod:`engine.studio.events`) and becomes a command for the engine thread. Its
  sensor set and constraint list are sub-models with their own events,
  :mod:`engine.studio.session_sensors` and :mod:`engine.editing.constraint_list`
  (shared with the pose window).
* :mod:`engine.studio.commands`: those commands (frozen dataclasses), with the table of
  their handlers the engine thread dispatches on.
* :mod:`engine.studio.snapshot`: what the engine thread publishes, numpy only.
* :mod:`engine.studio.thread`: the engine thread (commands in, snapshots out), with
  its playback clock (:mod:`engine.studio.playback`) and the methods it runs on each
  frame (:mod:`engine.studio.method_set`); :mod:`engine.studio.process` runs the same
  loop in a child process.
* :mod:`engine.studio.clip_source`: a clip's simulated trackers, one
  :class:`~engine.sensor_source.SensorSource` (recordings and live streams are others).
* :mod:`engine.studio.method_edits`: building methods and pushing the scene into them.

Layering (no loops): ``sensors`` < ``commands``, ``snapshot``, ``source``,
``methods``, ``playback`` < ``method_set`` < ``thread`` < ``process``; ``events`` <
``session_sensors``; all < ``session``. :mod:`engine.editing` (the constraint list and
its catalog) and :mod:`engine.authoring` (the pose window's scene format, which
:mod:`engine.studio.scenes` reads) sit below the whole package.
"""
