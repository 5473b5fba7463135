"""tests/app/test_collector.py, run in a subprocess: windows that Python owns and that
became cyclic garbage, each dropped while its first paint is pending.

``python -m tests.app.collector_child between|auto N``: collect as the studio does
(app.collector) or with Python's automatic collection; prints "survived" at the end.
"""

from __future__ import annotations

import contextlib
import sys
import time

import pyqtgraph as pg
from PyQt6.QtWidgets import QApplication, QVBoxLayout, QWidget

from app.collector import collected_between_events


def drop_a_window() -> None:
    """A window holding a plot, shown, then dropped: only the cycle collector frees it."""
    w = QWidget()
    QVBoxLayout(w).addWidget(pg.PlotWidget())
    w.show()
    w.itself = w  # type: ignore[attr-defined]


def main() -> None:
    app = QApplication(sys.argv[:1])
    mode, windows = sys.argv[1], int(sys.argv[2])
    collecting = collected_between_events(0.01) if mode == "between" else contextlib.nullcontext()
    with collecting:
        for _ in range(windows):
            drop_a_window()
            end = time.monotonic() + 0.05
            while time.monotonic() < end:
                app.processEvents()
    print("survived", flush=True)


if __name__ == "__main__":
    main()
