"""The methods the engine thread runs on each frame: the one the studio shows and its ghosts.

:class:`MethodSet` builds them by name, resets them for a clip (or for a tracker
stream's skeleton) and gives them the studio's settings, constraints and sensor weights
(:mod:`engine.studio.method_edits`), re-applying only the aspect an edit changed. It never
raises: a method that cannot be built, reset or configured is reported through the
``report`` callback as one readable line, and the others keep running.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from engine.methods import driver
from engine.methods.base import FrameResult, Method
from engine.methods.presets import sensors_problem
from engine.sensor_source import SensorSource
from engine.sensors import Sensor, SensorFrame
from engine.solver.settings_edit import SettingsEdit
from engine.studio.method_edits import apply_constraints, apply_sensor_weights, apply_settings
from engine.studio.method_state import copy_state


class MethodSet:
    """The shown method and its ghosts, with the studio's edits they were given.

    Parameters
    ----------
    factory : callable
        ``factory(name) -> Method``.
    report : callable
        ``report(message)``, called with each problem (one line).

    Attributes
    ----------
    name : str
        Requested method ("" = none); ``method`` the built one (None if it failed).
    ghost_names : tuple of str
        Requested ghosts; ``ghosts`` the built ones by name.
    sensors, constraints, settings
        The studio's current edits, pushed into every method.
    skeleton_version : int
        The source's ``skeleton_version`` at the last reset (a live source's
        calibration makes a new skeleton).
    """

    def __init__(self, factory: Callable[[str], Method], report: Callable[[str], None]) -> None:
        self._factory = factory
        self._report = report
        self.name = ""
        self.ghost_names: tuple[str, ...] = ()
        self.method: Method | None = None
        self.ghosts: dict[str, Method] = {}
        self.sensors: tuple[Sensor, ...] = ()
        self.constraints: tuple[Any, ...] = ()
        self.settings = SettingsEdit()
        self.skeleton_version = 0
        # select() built (or tried to build) the shown method since the last reset
        self._selected = False
        # the methods' state before the first edit of a paused frame (see keep_state)
        self._kept: dict[str, Method] | None = None
        self._prepared: dict[str, Method] = {}  # built ahead of their selection (prepare)

    def running(self) -> list[tuple[str, Method]]:
        """``(name, method)`` of every built method, the shown one first."""
        pairs = [(self.name, self.method), *self.ghosts.items()]
        return [(name, m) for name, m in pairs if m is not None]

    def prepare(self, name: str) -> None:
        """Build method ``name`` now, before any command asks for it, so that its first
        :meth:`build` (the studio's first selection) finds it ready: the engine process
        loads the models while the window is still being built. A failure is not
        reported here: the selection's own build tries again and reports it."""
        try:
            self._prepared[name] = self._factory(name)
        except Exception:
            pass

    def build(self, name: str) -> Method | None:
        """A new method ``name`` (the one :meth:`prepare` built, the first time), or None
        (reported) when the factory fails."""
        ready = self._prepared.pop(name, None)
        if ready is not None:
            return ready
        try:
            return self._factory(name)
        except Exception as exc:
            self._report(f"method {name!r}: {exc}")
            return None

    def select(self, name: str, ghosts: tuple[str, ...]) -> bool:
        """Show method ``name`` with ``ghosts`` (those not built yet are built at the
        next :meth:`reset`).

        ``name`` is built now unless it is already the shown method (a ghost edit);
        ghosts that stay are kept. Every method is built once per selection: building
        one loads its models, seconds for DragPoser.

        Returns False, changing nothing, when ``name`` cannot be built or cannot run from
        the sensors while another method runs: a broken weights file, or RPM asked for
        on six trackers, leaves the session as it was.
        """
        keep = name == self.name and self.method is not None
        if name and not keep and self.method is not None and self.sensors:
            why = sensors_problem(name, self.sensors)
            if why is not None:  # it would fail on every frame: the running method stays
                self._report(why)  # it names the method
                return False
        new = self.method if keep else self.build(name) if name else None
        if name and new is None and self.method is not None:
            return False
        self.name, self.ghost_names = name, tuple(ghosts)
        self.method = new
        self.ghosts = {g: m for g, m in self.ghosts.items() if g in self.ghost_names}
        self._selected = not keep
        return True

    def set_ghosts(self, ghosts: tuple[str, ...], source: SensorSource | None) -> None:
        """Draw ``ghosts`` beside the shown method, which keeps its state: ghosts that stay
        keep theirs, new ones are built, reset for ``source`` and given the studio's edits
        (a ghost that fails is reported and left out)."""
        self.ghost_names = tuple(g for g in ghosts if g != self.name)
        self.ghosts = {g: m for g, m in self.ghosts.items() if g in self.ghost_names}
        for g in self.ghost_names:
            if g in self.ghosts or (m := self.build(g)) is None:
                continue
            try:
                if source is not None:
                    driver.reset(m, source.skeleton, source.fps, reference=source.motion)
            except Exception as exc:
                self._report(f"{g}.reset: {exc}")
                continue
            self._apply(g, m)
            self.ghosts[g] = m
            if self._kept is not None:  # a paused frame solved again restores it too
                self._kept[g] = copy_state(m)

    def reset(self, source: SensorSource | None) -> None:
        """Reset every method for ``source``'s clip or skeleton, then configure them.

        A shown method that is missing (its build failed at an earlier selection) is
        tried again, but not right after :meth:`select` tried it; ghosts not built yet
        are built. The settings problems of freshly built methods are reported (a known
        method's were reported when they were edited).
        """
        fresh, self._selected = self._selected, False
        self._kept = None
        if not fresh and self.method is None and self.name:
            self.method = self.build(self.name)
            fresh = True
        for g in self.ghost_names:
            if g not in self.ghosts and (m := self.build(g)) is not None:
                self.ghosts[g] = m
                fresh = True
        self.skeleton_version = source.skeleton_version if source is not None else 0
        if source is not None:
            for _, m in self.running():
                try:
                    # a tracker source has no clip, only the wearer's (perhaps calibrated)
                    # skeleton; a clip is the ground truth of a method that needs one
                    driver.reset(m, source.skeleton, source.fps, reference=source.motion)
                except Exception as exc:
                    self._report(f"{m.name}.reset: {exc}")
        self.configure(report=fresh)  # methods may drop their settings on reset

    def keep_state(self, again: bool = True) -> None:
        """Before a solve: with ``again`` (the paused frame solved again after an edit)
        the first call keeps a copy of every method's state and each later one puts a
        fresh copy of it back, with the current edits applied; without, the kept state
        is dropped (:meth:`drop_state`; another frame, playback). See
        :mod:`engine.studio.method_state`."""
        if not again:
            self._kept = None
            return
        if self._kept is None:
            self._kept = {name: copy_state(m) for name, m in self.running()}
            return
        kept = self._kept
        if self.method is not None and self.name in kept:
            self.method = copy_state(kept[self.name])
        self.ghosts = {g: copy_state(kept[g]) if g in kept else m for g, m in self.ghosts.items()}
        self.configure(report=False)

    def drop_state(self) -> None:
        """Forget the state kept by :meth:`keep_state` (another frame, play, a reset)."""
        self._kept = None

    def set_settings(self, values: Mapping[str, Any], replace: bool = False) -> None:
        """Merge ``values`` into the settings (``replace``: take them instead) and push them."""
        self.settings = SettingsEdit(values) if replace else self.settings | values
        self.configure("settings")

    def set_constraints(self, constraints: tuple[Any, ...]) -> None:
        """Replace the constraint list and push it."""
        self.constraints = constraints
        self.configure("constraints")

    def set_sensors(self, sensors: tuple[Sensor, ...]) -> None:
        """Replace the sensor set and push its weights."""
        self.sensors = sensors
        self.configure("sensors")

    def configure(self, what: str = "all", report: bool = True) -> None:
        """Push the studio's edits into the methods: ``settings``, ``constraints``,
        ``sensors`` or ``all``. Only the changed aspect is re-applied, so a problem (such
        as a method that ignores constraints) is reported once per edit."""
        for name, m in self.running():
            self._apply(name, m, what, report)

    def _apply(self, name: str, m: Method, what: str = "all", report: bool = True) -> None:
        """:meth:`configure` of the one method ``m`` named ``name``."""
        problems = []
        if what in ("all", "settings"):
            problems += apply_settings(m, self.settings)
        if what in ("all", "constraints"):
            problems += apply_constraints(m, self.constraints)
        if what in ("all", "sensors"):
            problems += apply_sensor_weights(m, self.sensors)
        # a method that cannot run from these trackers says that instead, once per frame
        for problem in problems if report and self._can_run(name) else ():
            self._report(problem)

    def _can_run(self, name: str) -> bool:
        """Whether method ``name`` can reconstruct from the sensors (an edit problem of a
        ghost that cannot would only hide why it shows nothing)."""
        return not self.sensors or sensors_problem(name, self.sensors) is None

    @staticmethod
    def step(method: Method, sf: SensorFrame) -> FrameResult:
        """``method.step(sf)``; a non-finite pose raises :class:`FloatingPointError`."""
        return driver.step(method, sf)

    def between_frames(self) -> None:
        """Let every method do the work it deferred until the pose was out (DragPoser's
        predictor pieces); a failure is reported like a failing step, never fatal."""
        for name, m in self.running():
            try:
                m.between_frames()
            except Exception as exc:
                self._report(f"{name} between frames: {type(exc).__name__}: {exc}")
