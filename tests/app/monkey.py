"""A monkey for the studio and the pose window: seeded random, valid UI events (mouse
drags and clicks on the 3D views, wheel turns, keys, menu entries, clicks and value
changes of the panels' widgets, drags along the timelines), in the real windows under
a display (Xvfb); and on the studio's latent map dock (brought to the front, a tab picked,
clicks, hovers and wheel turns on the map, a trajectory point clicked, the tabs' widgets).

    PYTHONPATH=. xvfb-run -a python -m tests.app.monkey --seed 3 --events 3000 [--method dragposer] [--minutes 20]

Exit status 0 when every event ran; 1 when an exception escaped a slot (its traceback
on stderr) or one event did not return within ``--step-timeout`` seconds (a frozen
event loop: faulthandler prints ``Timeout`` and every thread's stack); a crash ends the
process with its signal (faulthandler prints the stacks). Every dialog answers "cancel", so nothing waits for a
person and nothing is written. The last line says what ran: ``monkey seed=S events=N ...``.
"""

from __future__ import annotations

import argparse
import faulthandler
import sys
import tempfile
import threading
import time
import traceback
from collections import Counter
from pathlib import Path

import numpy as np
from PyQt6.QtCore import QEvent, QPoint, QPointF, QSettings, Qt, QTimer
from PyQt6.QtGui import QWheelEvent
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import (
    QAbstractButton,
    QAbstractSpinBox,
    QApplication,
    QComboBox,
    QDialog,
    QFileDialog,
    QInputDialog,
    QMenu,
    QMessageBox,
    QSlider,
    QTabBar,
    QWidget,
)

from tests.app.gui_helpers import mouse_drag

#: An open popup menu or modal dialog is closed after this long, milliseconds.
POPUP_MS = 300
#: Menu entries that end a window (the run would lose its windows) or leave the process.
LEAVING = ("Quit", "Close")
#: Keys a user presses in these windows (with the modifiers that make them edits).
KEYS = [
    (k, Qt.KeyboardModifier.NoModifier)
    for k in (
        Qt.Key.Key_1,
        Qt.Key.Key_3,
        Qt.Key.Key_7,
        Qt.Key.Key_Home,
        Qt.Key.Key_F,
        Qt.Key.Key_S,
        Qt.Key.Key_B,
        Qt.Key.Key_G,
        Qt.Key.Key_H,
        Qt.Key.Key_K,
        Qt.Key.Key_L,
        Qt.Key.Key_Space,
        Qt.Key.Key_Left,
        Qt.Key.Key_Right,
        Qt.Key.Key_Escape,
        Qt.Key.Key_W,
        Qt.Key.Key_R,
        Qt.Key.Key_Q,
        Qt.Key.Key_E,
        Qt.Key.Key_P,
        Qt.Key.Key_J,
    )
] + [
    (Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier),
    (Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier),
    (Qt.Key.Key_Return, Qt.KeyboardModifier.ControlModifier),
]


def answer_every_dialog_cancel() -> None:
    """Message boxes, file, option and input dialogs return at once, as if cancelled."""
    for name in ("critical", "warning", "information", "question"):
        setattr(QMessageBox, name, staticmethod(lambda *a, **k: QMessageBox.StandardButton.Cancel))
    for name in ("getOpenFileName", "getSaveFileName"):
        setattr(QFileDialog, name, staticmethod(lambda *a, **k: ("", "")))
    QDialog.exec = lambda self: QDialog.DialogCode.Rejected  # type: ignore[method-assign]
    for name in ("getText", "getInt", "getDouble", "getItem"):
        setattr(QInputDialog, name, staticmethod(lambda *a, **k: (None, False)))


def close_popups() -> None:
    """Close an open popup menu or modal dialog (a button's menu runs its own event loop
    until a person picks an entry; the monkey is not that person)."""
    for widget in (QApplication.activePopupWidget(), QApplication.activeModalWidget()):
        if widget is not None:
            widget.close()


def on_screen(widget: QWidget) -> bool:
    """Whether a user could see ``widget``: a dock tabbed behind another keeps its children
    ``isVisible()`` (its title bar's buttons too) but shows none of them."""
    return not widget.visibleRegion().isEmpty()


def menu_actions(window: QWidget) -> list:
    out = []

    def walk(menu: QMenu) -> None:
        for act in menu.actions():
            if act.menu() is not None:
                walk(act.menu())
            elif not act.isSeparator() and act.text().replace("&", "").rstrip(".") not in LEAVING:
                out.append(act)

    for top in window.menuBar().actions():
        walk(top.menu())
    return out


class Monkey:
    """Random events on ``windows`` from ``rng`` (see the module doc)."""

    def __init__(self, windows: list, rng: np.random.Generator) -> None:
        self.windows, self.rng = windows, rng
        self.counts: Counter = Counter()
        self.slowest = (0.0, "")

    def step(self) -> str:
        """One random event; what it was (kind, window and detail)."""
        w = self.windows[int(self.rng.integers(len(self.windows)))]
        kind = str(
            self.rng.choice(
                ["drag", "drag", "click", "wheel", "key", "key", "menu", "widget", "widget", "strip", "latent"]
            )
        )
        if kind == "latent":  # the studio's dock: the pose window has no latent map
            w = self.windows[0]
        detail = getattr(self, f"_{kind}")(w)
        self.counts[kind] += 1
        return f"{kind} {type(w).__name__}" + (f" {detail}" if detail else "")

    def _point(self, w) -> tuple[float, float]:
        """A pixel of the 3D view: on a joint half of the time, else anywhere."""
        p = w.viewport.plotter
        joints = w.viewport.joints.positions
        if joints is not None and self.rng.random() < 0.5:
            x, y = w.viewport.joints._to_display(np.asarray(joints)[[int(self.rng.integers(len(joints)))]])[0]
            return float(x), float(y)
        return float(self.rng.uniform(2, p.width() - 2)), float(self.rng.uniform(2, p.height() - 2))

    def _drag(self, w) -> None:
        x, y = self._point(w)
        dx, dy = self.rng.normal(0, 40, 2)
        mouse_drag(
            w.viewport, (x, y), (x + dx, y + dy), ctrl=bool(self.rng.random() < 0.3), steps=int(self.rng.integers(1, 8))
        )

    def _click(self, w) -> None:
        x, y = self._point(w)
        mouse_drag(w.viewport, (x, y), (x, y), ctrl=bool(self.rng.random() < 0.3), steps=1)

    def _wheel(self, w) -> None:
        p = w.viewport.plotter
        pos = QPointF(self.rng.uniform(0, p.width()), self.rng.uniform(0, p.height()))
        delta = QPoint(0, int(self.rng.choice([-120, 120])))
        event = QWheelEvent(
            pos,
            p.mapToGlobal(pos),
            QPoint(),
            delta,
            Qt.MouseButton.NoButton,
            Qt.KeyboardModifier.NoModifier,
            Qt.ScrollPhase.NoScrollPhase,
            False,
        )
        QApplication.sendEvent(p, event)

    def _key(self, w) -> str:
        key, mods = KEYS[int(self.rng.integers(len(KEYS)))]
        w.activateWindow()
        target = QApplication.focusWidget() if self.rng.random() < 0.3 else None
        QTest.keyClick(target if target is not None and target.window() is w else w.viewport, key, mods)
        return f"{key.name}{'+' + str(mods.value) if mods.value else ''}"

    def _menu(self, w) -> str:
        acts = [a for a in menu_actions(w) if a.isEnabled()]
        if acts:
            act = acts[int(self.rng.integers(len(acts)))]
            act.trigger()
            return act.text().replace("&", "")
        return ""

    def _widget(self, w) -> str:
        kinds = (QAbstractButton, QAbstractSpinBox, QComboBox, QSlider)
        found = [
            c
            for c in w.findChildren(QWidget)
            if isinstance(c, kinds) and c.isVisible() and c.isEnabled() and c.window() is w and on_screen(c)
        ]
        if not found:
            return ""
        c = found[int(self.rng.integers(len(found)))]
        what = f"{type(c).__name__}({getattr(c, 'text', lambda: '')() or c.objectName()})"
        self._widget_act(c)
        return what

    def _widget_act(self, c: QWidget) -> None:
        if isinstance(c, QAbstractButton):
            c.click()
        elif isinstance(c, QAbstractSpinBox):
            c.stepBy(int(self.rng.integers(-5, 6)))  # small steps: a 36000-frame bake is not a test of the GUI
        elif isinstance(c, QComboBox) and c.count():
            c.setCurrentIndex(int(self.rng.integers(c.count())))
        elif isinstance(c, QSlider):
            QTest.mouseClick(
                c, Qt.MouseButton.LeftButton, pos=QPoint(int(self.rng.uniform(0, c.width())), c.height() // 2)
            )

    def _latent(self, w) -> str:
        """The latent map dock in front, a random tab, and on it: a click, a hover or a wheel
        turn on the map (a trajectory point a third of the time: a seek), or a widget's act."""
        views = w.latent_views
        bar = next(
            (b for b in w.findChildren(QTabBar) if "Latent map" in [b.tabText(i) for i in range(b.count())]), None
        )
        if bar is not None and bar.isVisible():  # tabbed beside the Latent dock: its tab, as a user would
            index = [bar.tabText(i) for i in range(bar.count())].index("Latent map")
            QTest.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(index).center())
        else:  # floated, or alone in its area
            views.dock.raise_()
        QApplication.processEvents()  # its first showing builds the tabs
        if views.tabs is None:
            return "raised"
        bar = views.tabs.tabBar()
        tab = int(self.rng.integers(views.tabs.count()))
        QTest.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(tab).center())
        QApplication.processEvents()
        if tab != 0 or self.rng.random() < 0.2:
            found = [
                c
                for c in views.tabs.currentWidget().findChildren(QWidget)
                if isinstance(c, (QAbstractButton, QAbstractSpinBox, QComboBox))
                and c.isVisible()
                and c.isEnabled()
                and on_screen(c)
            ]
            if not found:
                return f"tab {tab}"
            c = found[int(self.rng.integers(len(found)))]
            self._widget_act(c)
            return f"tab {tab} {type(c).__name__}({getattr(c, 'text', lambda: '')() or c.objectName()})"
        plot = views.map.plot.viewport()
        if len(views.map.xy) and self.rng.random() < 0.33:
            x, y = views.map.xy[int(self.rng.integers(len(views.map.xy)))]
            pos = views.map.to_widget(float(x), float(y)).toPoint()
        else:
            pos = QPoint(int(self.rng.uniform(0, plot.width())), int(self.rng.uniform(0, plot.height())))
        act = str(self.rng.choice(["click", "hover", "wheel"]))
        if act == "click":
            QTest.mouseClick(plot, Qt.MouseButton.LeftButton, pos=pos)
        elif act == "hover":
            QTest.mouseMove(plot, pos)
        else:
            event = QWheelEvent(
                QPointF(pos),
                QPointF(plot.mapToGlobal(pos)),
                QPoint(),
                QPoint(0, int(self.rng.choice([-120, 120]))),
                Qt.MouseButton.NoButton,
                Qt.KeyboardModifier.NoModifier,
                Qt.ScrollPhase.NoScrollPhase,
                False,
            )
            QApplication.sendEvent(plot, event)
        return f"map {act}"

    def _strip(self, w) -> None:
        """A drag along the pose window's key timeline, or a click on the studio's."""
        strip = getattr(getattr(w, "keys", None), "strip", None)
        if strip is None:
            slider = w.timeline.slider
            QTest.mouseClick(
                slider,
                Qt.MouseButton.LeftButton,
                pos=QPoint(int(self.rng.uniform(0, slider.width())), slider.height() // 2),
            )
            return
        from tests.widgets.test_authoring_widgets import drag_on

        x0 = float(self.rng.uniform(0, strip.width()))
        drag_on(strip, x0, x0 + float(self.rng.normal(0, 60)), steps=int(self.rng.integers(1, 5)))


def run(seed: int, events: int, step_timeout: float, method: str = "ik", minutes: float = 0.0) -> int:
    """Build the studio (solving with ``method``) and a pose window, run ``events`` random
    events (or fewer: as many as ``minutes`` of wall time allow, when positive); the exit
    status."""
    from app.authoring_actions import open_pose_window
    from app.demo import demo_walk
    from app.main_window import MainWindow

    app = QApplication.instance() or QApplication(sys.argv[:1])
    answer_every_dialog_cancel()
    errors: list[str] = []

    def hook(kind, value, tb) -> None:
        text = "".join(traceback.format_exception(kind, value, tb))
        errors.append(text)
        sys.stderr.write(text)

    sys.excepthook = hook
    folder = Path(tempfile.mkdtemp(prefix="monkey-"))
    studio = MainWindow(
        method=method, settings=QSettings(str(folder / "studio.ini"), QSettings.Format.IniFormat), engine="thread"
    )
    studio.session.set_motion(demo_walk(4.0))
    studio.resize(1400, 900)
    studio.show()
    pose = open_pose_window(studio, 1.75, from_clip=False)
    pose.resize(1200, 800)
    for _ in range(20):
        app.processEvents()
    monkey = Monkey([studio, pose], np.random.default_rng(seed))
    start = time.monotonic()
    done = 0
    for done in range(1, events + 1):
        faulthandler.dump_traceback_later(step_timeout, exit=True)  # a frozen step: stacks, exit 1
        t0 = time.monotonic()
        closer = QTimer(singleShot=True, interval=POPUP_MS)
        closer.timeout.connect(close_popups)
        closer.start()
        what = monkey.step()
        app.processEvents()
        closer.stop()
        # what the event loop does between events: widgets deleted later are deleted now
        QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
        took = time.monotonic() - t0
        faulthandler.cancel_dump_traceback_later()
        if took > monkey.slowest[0]:
            monkey.slowest = (took, what)
        if errors:
            break
        if not pose.isVisible():  # a window may only close through the entries left out
            errors.append(f"the pose window closed at event {done} ({what})")
            break
        if minutes > 0 and time.monotonic() - start > 60.0 * minutes:
            break
    for w in (pose, studio):
        if hasattr(w, "session") and hasattr(w.session, "history"):
            w.session.history.set_clean()
    pose.close()
    studio.undo.set_clean()
    studio.close()
    app.processEvents()
    left = [t for t in threading.enumerate() if t is not threading.main_thread() and t.is_alive()]
    if left:  # one still in torch when the interpreter ends aborts the process (std::terminate)
        frames = sys._current_frames()
        for t in left:
            stack = "".join(traceback.format_stack(frames[t.ident])) if t.ident in frames else ""
            errors.append(f"thread {t.name!r} still running after both windows closed:\n{stack}")
    counts = " ".join(f"{k}={v}" for k, v in sorted(monkey.counts.items()))
    print(
        f"monkey seed={seed} events={done} seconds={time.monotonic() - start:.0f} "
        f"slowest={monkey.slowest[0]:.2f}s ({monkey.slowest[1]}) errors={len(errors)} {counts}",
        flush=True,
    )
    for e in errors[:1]:
        print(e, file=sys.stderr)
    return 1 if errors else 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--events", type=int, default=2000)
    p.add_argument("--step-timeout", type=float, default=60.0, help="seconds one event may take (frozen beyond)")
    p.add_argument("--method", default="ik", help="the studio's method at the start (dragposer fills the latent map)")
    p.add_argument("--minutes", type=float, default=0.0, help="stop after this much wall time (0: run every event)")
    a = p.parse_args(argv)
    faulthandler.enable(all_threads=True)
    return run(a.seed, a.events, a.step_timeout, a.method, a.minutes)


if __name__ == "__main__":
    sys.exit(main())
