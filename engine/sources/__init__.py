"""Where tracker readings come from besides clip simulation: live VMC/OSC streams,
recorded tracker files, and calibration to the wearer.

* :mod:`~engine.sources.coords` - explicit axis conventions (Unity/VMC, OpenXR) to the
  project's frame;
* :mod:`~engine.sources.trackers` - tracker samples, the tracker -> body-slot mapping,
  :class:`TrackerState` (samples in, :class:`~engine.methods.SensorFrame` out);
* :mod:`~engine.sources.vmc` - the VMC messages, encoded and decoded with python-osc;
* :mod:`~engine.sources.receiver` - the UDP receiver thread, tolerant of bad input;
* :mod:`~engine.sources.recording` - the JSON Lines recording format: atomic streaming
  writer, reader, replay into a :class:`~engine.tracking.Tracking`;
* :mod:`~engine.sources.calibration` - height, arm span and tracker-to-joint offsets;
* :mod:`~engine.sources.sender` - a clip's trackers streamed as VMC (tests, demos);
* :mod:`~engine.sources.live` - realtime solving of a stream, latency and error figures.

``docs/trackers.md`` is the user's guide. Submodules are imported where used (the
package itself stays light).
"""
