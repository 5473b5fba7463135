"""The tracker presets a method can run with, known without building it (no torch).

SparsePoser and RPM learnt one tracker set each and refuse any other on the first frame
(:func:`engine.methods.base.check_preset`). Offering such a method where it cannot run
(a ghost of a video, a studio ghost) and failing later, after the user chose a file,
is what :func:`preset_problem` prevents: callers ask it before any work starts.
"""

from __future__ import annotations

from collections.abc import Iterable

from engine.sensors import Sensor
from engine.tracking import PRESET_SENSORS

#: method -> the only tracker preset it runs with; a method not listed takes any trackers.
REQUIRED_PRESET = {"sparseposer": "6", "rpm": "3-head-hands"}


def _layout(sensors: Iterable[Sensor]) -> list[tuple[str, int]]:
    """The trackers' joints and DoF, in one order: what decides whether a method runs."""
    return sorted((s.joint, s.dof) for s in sensors)


def preset_problem(method: str, preset: str | None) -> str | None:
    """Why ``method`` cannot reconstruct from the trackers of ``preset`` (a preset name;
    None: no trackers), or None when it can."""
    if not preset:
        return f"{method} reconstructs from trackers: the motion has none"
    needed = REQUIRED_PRESET.get(method)
    if needed is None:
        return None
    have = PRESET_SENSORS.get(preset)
    want = PRESET_SENSORS[needed]
    if have is not None and _layout(have) == _layout(want):
        return None
    return f"{method} runs only with tracker preset {needed!r} (these trackers: {preset!r})"


def sensors_problem(method: str, sensors: Iterable[Sensor]) -> str | None:
    """Why ``method`` cannot reconstruct from the enabled ``sensors`` (their joints and
    DoF, whatever preset they came from), or None when it can: what the studio's engine
    asks before it switches methods, so that a switch the method would fail on every
    frame is refused and the running method stays."""
    needed = REQUIRED_PRESET.get(method)
    if needed is None:
        return None
    have = _layout(s for s in sensors if s.enabled)
    want = _layout(PRESET_SENSORS[needed])
    if have == want:
        return None
    listed = ", ".join(f"{j} {d}-DoF" for j, d in have) or "none"
    return f"{method} runs only with tracker preset {needed!r} ({', '.join(j for j, _ in want)}); enabled: {listed}"
