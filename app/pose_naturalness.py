"""The pose window's naturalness readout: how far the pose shown is from the nearest real pose.

The measure is the pose benchmark's (:mod:`engine.authoring.pose_reference`; docs/authoring.md,
"Pose-mode benchmark"): the mean over the 21 joints below the pelvis of each one's distance to
the same joint of the nearest of the validation files' poses shipped in ``assets/reference``
(every 4th frame and its mirror image), both root-relative and turned to one heading, laid out
on the character's skeleton. Whether the pose lies *within the spread of real poses* (closer
than 95 % of the real poses are to the nearest pose of another take) needs that spread, about a
second of work per skeleton: a worker thread computes it and the readout adds the verdict when
it is in. Closing the window (or another skeleton) cancels the worker between two blocks.
"""

from __future__ import annotations

import threading

import numpy as np
from PyQt6.QtCore import pyqtSignal
from PyQt6.QtWidgets import QLabel, QWidget

from engine.authoring.pose_reference import ReferenceSet, load_shipped, take_label
from engine.errors import UserError
from engine.progress import Cancelled


class NaturalnessReadout(QLabel):
    """``Natural: D cm`` of the pose last given to :meth:`show_pose`, and once known whether
    it is within the spread of real poses; the tooltip says what it measures and the take of
    the nearest real pose."""

    #: The worker's spread, delivered on the GUI thread: (the skeleton it is for, median cm, p95 cm).
    spreadReady = pyqtSignal(bytes, float, float)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.reference: ReferenceSet | None = None
        self.distance_cm: float | None = None
        self.take = ""
        self.spread: tuple[float, float] | None = None  # median, p95 cm of the current skeleton
        self._skeleton: bytes | None = None
        self._stop = threading.Event()
        self.worker: threading.Thread | None = None
        self.spreadReady.connect(self._on_spread)
        self.setText("Natural: -")

    def show_pose(self, positions: np.ndarray, offsets: np.ndarray) -> None:
        """Measure world ``positions (22, 3)`` on the skeleton of ``offsets (22, 3)`` metres."""
        key = np.ascontiguousarray(offsets, dtype=np.float64).tobytes()
        if key != self._skeleton:
            self._load(offsets, key)
        if self.reference is None:
            return
        d, take = self.reference.closest(positions)
        self.distance_cm, self.take = 100.0 * d, take
        self._show()

    def stop(self) -> None:
        """Cancel the spread's worker and wait for it (it stops within one block)."""
        self._stop.set()
        if self.worker is not None:
            self.worker.join()
            self.worker = None

    def _load(self, offsets: np.ndarray, key: bytes) -> None:
        self.stop()
        self._skeleton, self.spread, self.distance_cm = key, None, None
        try:
            self.reference = load_shipped(np.asarray(offsets, float))
        except UserError as exc:  # a broken installation: say so here, pose on
            self.reference = None
            self.setText("Natural: -")
            self.setToolTip(f"No naturalness measure: {exc}")
            return
        self._stop = threading.Event()
        self.worker = threading.Thread(
            target=self._work, args=(self.reference, key, self._stop), name="naturalness-spread", daemon=True
        )
        self.worker.start()

    def _work(self, reference: ReferenceSet, key: bytes, stop: threading.Event) -> None:
        try:
            s = reference.spread_summary(stop.is_set)
        except Cancelled:
            return
        self.spreadReady.emit(key, s["median_cm"], s["p95_cm"])

    def _on_spread(self, key: bytes, median: float, p95: float) -> None:
        if key == self._skeleton:  # not a skeleton replaced meanwhile
            self.spread = (median, p95)
            self._show()

    @property
    def within(self) -> bool | None:
        """Whether the last pose is within the spread of real poses (None: not known yet)."""
        if self.spread is None or self.distance_cm is None:
            return None
        return self.distance_cm <= self.spread[1]

    def _show(self) -> None:
        if self.distance_cm is None:
            return
        verdict = {None: "", True: ", within real poses", False: ", beyond real poses"}[self.within]
        self.setText(f"Natural: {self.distance_cm:.1f} cm{verdict}")
        ref = self.reference
        assert ref is not None
        tip = (
            f"Distance from this pose to the nearest real pose, {self.distance_cm:.1f} cm: the mean over "
            f"the joints of their distances, both poses root-relative and facing one way, on this "
            f"character's skeleton. Real poses: {ref.description}, {len(ref)} poses; the nearest is "
            f"from {take_label(self.take)}."
        )
        if self.spread is not None:
            tip += (
                f" Each real pose is within {self.spread[1]:.1f} cm of another take's nearest pose in 95 % "
                f"of cases (median {self.spread[0]:.1f} cm): a pose closer than that is within real poses."
            )
        else:
            tip += " Whether that is within the spread of real poses is being computed."
        self.setToolTip(tip)
