"""Where tracker readings come from besides clip simulation: live VMC/OSC streams,
recorded tracker files, and calibration to the wearer.

* :mod:`~engine.tracker_io.coords` - explicit axis conventions (Unity/VMC, OpenXR) to the
  project's frame;
* :mod:`~engine.tracker_io.trackers` - tracker samples, the tracker -> body-slot mapping,
  :class:`TrackerState` (samples in, :class:`~engine.methods.SensorFrame` out);
* :mod:`~engine.tracker_io.vmc` - the VMC messages, encoded and decoded with python-osc;
* :mod:`~engine.tracker_io.framing` - which datagrams make up a frame (bundles, or one
  message per datagram with the time first, last or absent);
* :mod:`~engine.tracker_io.receiver` - the UDP receiver thread, tolerant of bad input;
* :mod:`~engine.tracker_io.recording` - the JSON Lines recording format: atomic streaming
  writer, reader, replay into a :class:`~engine.tracking.Tracking`;
* :mod:`~engine.tracker_io.calibration` - height, arm span and tracker-to-joint offsets;
* :mod:`~engine.tracker_io.sender` - a clip's trackers streamed as VMC (tests, demos);
* :mod:`~engine.tracker_io.live` - realtime solving of a stream, latency and error figures;
* :mod:`~engine.tracker_io.live_source`, :mod:`~engine.tracker_io.recording_source` - a
  stream and a recording as the studio's :class:`~engine.sensor_source.SensorSource`.

``docs/trackers.md`` is the user's guide. Submodules are imported where used (the
package itself stays light).
"""
