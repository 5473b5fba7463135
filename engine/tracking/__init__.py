"""Sensor presets and simulated trackers (noise, faulty sensors, tracking gaps).

``engine.tracking.simulate`` is the function (the module of the same name is
``engine.tracking.simulate`` in ``sys.modules``; import helpers from it with
``from engine.tracking.simulate import ...``).
"""

from engine.tracking.presets import PRESET_SENSORS, PRESETS, parse_sensors
from engine.tracking.simulate import Tracking, simulate

__all__ = ["PRESETS", "PRESET_SENSORS", "Tracking", "parse_sensors", "simulate"]
