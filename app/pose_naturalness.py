"""The pose window's naturalness readout: how far the pose shown is from the nearest real pose.

The measure is the pose benchmark's (:mod:`engine.authoring.pose_reference`; docs/authoring.md,
"Pose-mode benchmark"): the mean over the 21 joints below the pelvis of each one's distance to
the same joint of the nearest of the validation files' poses shipped in ``assets/reference``
(every 4th frame and its mirror image), both root-relative and turned to one heading, laid out
on the character's skeleton. Whether the pose lies *within the spread of real poses* (closer
than 95 % of the real poses are to the nearest pose of another take) needs that spread, about a
second of work per skeleton: a worker thread computes it and the readout adds the verdict when
it is in. Closing the window (or another skeleton) cancels the worker between two blocks.

The reference can instead be motion files the user chooses (:meth:`NaturalnessReadout.use_files`:
View > Naturalness reference), e.g. a library that holds floor work, which the validation
files lack. They are read on the worker (a frame every few, at most :data:`MAX_POSES` poses
with their mirror images, so a drag stays smooth) and their spread is estimated from
:data:`SPREAD_SAMPLE` of their poses against all of them.
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
from PyQt6.QtCore import pyqtSignal
from PyQt6.QtGui import QAction, QActionGroup
from PyQt6.QtWidgets import QFileDialog, QLabel, QMainWindow, QMenu, QMessageBox, QWidget

from app.file_actions import OPEN_FILTER  # the formats the studio opens
from engine.authoring.pose_reference import ReferenceSet, load_files, load_shipped, take_label
from engine.errors import UserError
from engine.progress import Cancelled

#: Most poses (mirror images included) a reference of chosen files holds: measuring a pose
#: against 30,000 takes a few milliseconds, once per drawn frame.
MAX_POSES = 30_000
#: Poses of a chosen reference whose distance to the other takes estimates its spread (the
#: whole set's would take minutes for a large library).
SPREAD_SAMPLE = 4_000


class NaturalnessReadout(QLabel):
    """``Natural: D cm`` of the pose last given to :meth:`show_pose`, and once known whether
    it is within the spread of real poses; the tooltip says what it measures and the take of
    the nearest real pose."""

    #: The worker's spread, delivered on the GUI thread: (the skeleton it is for, median cm, p95 cm).
    spreadReady = pyqtSignal(bytes, float, float)
    #: The worker's reference of chosen files: (the skeleton it is for, the ReferenceSet).
    referenceReady = pyqtSignal(bytes, object)
    #: Chosen files that could not be read: (the skeleton they were for, the message).
    referenceFailed = pyqtSignal(bytes, str)
    #: The chosen files could not be read (the message names the file); the readout has gone
    #: back to the reference it used before.
    failed = pyqtSignal(str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.reference: ReferenceSet | None = None
        self.files: list[Path] | None = None  # the chosen reference files (None: the shipped poses)
        self._previous: list[Path] | None = None  # the reference before the last choice
        self.distance_cm: float | None = None
        self.take = ""
        self.spread: tuple[float, float] | None = None  # median, p95 cm of the current skeleton
        self._skeleton: bytes | None = None
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # the last pose shown and its offsets
        self._stop = threading.Event()
        self.worker: threading.Thread | None = None
        self.spreadReady.connect(self._on_spread)
        self.referenceReady.connect(self._on_reference)
        self.referenceFailed.connect(self._on_failed)
        self.setText("Natural: -")

    def show_pose(self, positions: np.ndarray, offsets: np.ndarray) -> None:
        """Measure world ``positions (22, 3)`` on the skeleton of ``offsets (22, 3)`` metres."""
        self._last = (np.array(positions, dtype=np.float64), np.array(offsets, dtype=np.float64))
        key = np.ascontiguousarray(offsets, dtype=np.float64).tobytes()
        if key != self._skeleton:
            self._load(offsets, key)
        self._measure()

    def use_files(self, files: list[Path] | None) -> None:
        """Judge against the motion files ``files`` (at least two takes: the spread compares
        each with the others), or with None the shipped validation poses; the pose last
        shown is measured again once the new reference is in."""
        if files is not None and len(files) < 2:
            raise UserError(
                "choose at least two motion files: the spread of real poses compares each take with the others"
            )
        self._previous = self.files  # what a failed read goes back to
        self.files = None if files is None else [Path(f) for f in files]
        self._skeleton = None
        if self._last is not None:
            self.show_pose(*self._last)

    def _measure(self) -> None:
        if self.reference is None or self._last is None:
            return
        d, take = self.reference.closest(self._last[0])
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
        self._skeleton, self.spread, self.distance_cm, self.reference = key, None, None, None
        offsets = np.asarray(offsets, float)
        if self.files is None:
            try:
                self.reference = load_shipped(offsets)
            except UserError as exc:  # a broken installation: say so here, pose on
                self.setText("Natural: -")
                self.setToolTip(f"No naturalness measure: {exc}")
                return
        else:
            self.setText("Natural: reading the reference files...")
            self.setToolTip(f"Reading {len(self.files)} motion files to judge poses against.")
        self._stop = threading.Event()
        self.worker = threading.Thread(
            target=self._work,
            args=(self.reference, self.files, offsets, key, self._stop),
            name="naturalness-spread",
            daemon=True,
        )
        self.worker.start()

    def _work(
        self,
        reference: ReferenceSet | None,
        files: list[Path] | None,
        offsets: np.ndarray,
        key: bytes,
        stop: threading.Event,
    ) -> None:
        sample = None
        try:
            if reference is None:
                assert files is not None
                reference = load_files(files, offsets, kind="files", max_poses=MAX_POSES, cancelled=stop.is_set)
                self.referenceReady.emit(key, reference)
                sample = SPREAD_SAMPLE
            s = reference.spread_summary(stop.is_set, sample)
        except Cancelled:
            return
        except UserError as exc:
            self.referenceFailed.emit(key, str(exc))
            return
        except Exception as exc:  # noqa: BLE001 - a thread's error must reach the window, not vanish
            self.referenceFailed.emit(key, f"could not read the reference files: {type(exc).__name__}: {exc}")
            return
        self.spreadReady.emit(key, s["median_cm"], s["p95_cm"])

    def _on_reference(self, key: bytes, reference: ReferenceSet) -> None:
        if key == self._skeleton:
            self.reference = reference
            self._measure()

    def _on_failed(self, key: bytes, message: str) -> None:
        if key != self._skeleton:
            return
        self.files = self._previous  # back to the reference in use before the choice
        self._skeleton = None
        if self._last is not None:
            self.show_pose(*self._last)
        self.failed.emit(message)

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
            sampled = f" (estimated from {SPREAD_SAMPLE:,} of them)" if self.files and len(ref) > SPREAD_SAMPLE else ""
            tip += (
                f" Each real pose is within {self.spread[1]:.1f} cm of another take's nearest pose in 95 % "
                f"of cases{sampled} (median {self.spread[0]:.1f} cm): a pose closer than that is within real poses."
            )
        else:
            tip += " Whether that is within the spread of real poses is being computed."
        self.setToolTip(tip)


class ReferenceMenu:
    """View > Naturalness reference of the pose window ``w`` (which holds the readout as
    ``w.naturalness``): the shipped validation poses, or motion files chosen in a dialog.
    A choice that is cancelled, too small or unreadable leaves the reference in use before
    it (the shipped poses or the files chosen earlier) and says why."""

    def __init__(self, w: QMainWindow, view: QMenu) -> None:
        self.w, self.readout = w, w.naturalness
        menu = view.addMenu("Naturalness &reference")
        group = QActionGroup(w)
        self.shipped = QAction("&Validation poses (shipped)", w, checkable=True, checked=True)
        self.files = QAction("&Motion files...", w, checkable=True)
        for act in (self.shipped, self.files):
            group.addAction(act)
            menu.addAction(act)
        self.shipped.triggered.connect(lambda _=False: self.use_shipped())
        self.files.triggered.connect(lambda _=False: self.choose_files())
        self.readout.failed.connect(self._failed)

    def use_shipped(self) -> None:
        self.readout.use_files(None)
        self._show_choice()

    def choose_files(self) -> None:
        """Ask for the files (two or more) and judge poses against them."""
        start = str(self.readout.files[0].parent) if self.readout.files else ""
        names, _ = QFileDialog.getOpenFileNames(self.w, "Naturalness reference: motion files", start, OPEN_FILTER)
        try:
            if names:  # cancelled: the reference in use stays
                self.readout.use_files([Path(n) for n in names])
        except UserError as exc:
            QMessageBox.warning(self.w, "Naturalness reference", str(exc))
        self._show_choice()

    def _show_choice(self) -> None:
        """Check the entry of the reference in use and say how many files it holds."""
        kept = self.readout.files
        (self.files if kept else self.shipped).setChecked(True)
        self.files.setText(f"&Motion files... ({len(kept)} in use)" if kept else "&Motion files...")

    def _failed(self, message: str) -> None:
        self._show_choice()
        kept = self.readout.files
        now = f"the {len(kept)} files chosen before" if kept else "the shipped validation poses"
        QMessageBox.warning(self.w, "Naturalness reference", f"{message}\n\nPoses are judged against {now}.")
