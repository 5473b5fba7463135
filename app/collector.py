"""Cyclic garbage collection on the GUI thread, between events.

Python's cycle collector runs whenever allocations pass its threshold: in whichever
thread allocates, at whatever moment. A window or widget that Python owns (one with no
Qt parent) and that has become cyclic garbage is then deleted there. Inside a Qt paint
that deletes the paint device under its painter (Qt prints "QPaintDevice: Cannot destroy
paint device that is being painted", and the next draw call jumps through the freed
paint engine: the segfault in ``QPainter::drawImage`` under pyqtgraph's
``ImageItem.paint`` of docs/reliability.md); in an export or job thread it deletes a
Qt object from a thread that does not own it.

pyqtgraph ships the remedy, :class:`pyqtgraph.util.garbage_collector.GarbageCollector`:
automatic collection off, and the collector's own generational thresholds checked by a
timer on the GUI thread, so a collection only ever runs between two events.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

from pyqtgraph.util.garbage_collector import GarbageCollector

#: Seconds between two checks of the collector's thresholds. A second of playback makes
#: a few 10^4 container objects, so each check finds the youngest generation due.
INTERVAL_S = 0.5


@contextmanager
def collected_between_events(interval_s: float = INTERVAL_S) -> Iterator[GarbageCollector]:
    """Within the block, collect cycles only from a GUI-thread timer (needs a
    ``QApplication``); afterwards automatic collection is as it was before."""
    was_enabled = gc.isenabled()
    collector = GarbageCollector(interval=interval_s)  # turns automatic collection off
    try:
        yield collector
    finally:
        collector.timer.stop()
        if was_enabled:
            gc.enable()
