"""Choosing a method in the Optimizer tab builds it (loads its models) once."""

from __future__ import annotations

from collections import Counter

import pytest

pytestmark = pytest.mark.gui


def test_choosing_a_method_and_a_ghost_builds_each_once(studio, qtbot):
    """The real path: the panel's combo and ghost box -> window -> session -> engine
    thread -> :class:`engine.studio.method_set.MethodSet` -> the method factory.

    A choice builds the method once (``select`` builds it; the reset after it reuses it),
    and ticking a ghost builds that ghost alone, not the shown method and every ghost anew.
    """
    built: Counter[str] = Counter()
    inner = studio.engine._factory  # looked up at each build (see EngineThread)

    def counting(name):
        built[name] += 1
        return inner(name)

    studio.engine._factory = counting
    panel = studio.optimizer_panel
    assert panel.method.currentText() == "ik"
    panel.method.setCurrentText("dragposer")
    qtbot.waitUntil(
        lambda: studio.session.latest.method == "dragposer" and bool(studio.session.latest.losses), timeout=30000
    )
    assert built == {"dragposer": 1}

    seq = studio.session.latest.seq
    panel.ghost_boxes["ik"].click()  # as a user ticks it
    assert studio.session.ghosts == ("ik",)
    qtbot.waitUntil(lambda: studio.session.latest.seq > seq and "ik" in studio.session.latest.ghosts, timeout=30000)
    assert built == {"dragposer": 1, "ik": 1}, "a ghost edit keeps the shown method"
    assert not studio.session.latest.method_error


def test_a_method_without_settings_says_so_and_a_ghost_keeps_the_history(studio, qtbot):
    panel, s = studio.optimizer_panel, studio.session
    assert s.method == "ik"
    qtbot.waitUntil(lambda: not panel.settings_note.isHidden(), timeout=10000)
    assert "ik takes no optimizer settings" in panel.settings_note.text()
    assert all(w.isEnabled() for w in panel.editors.values())  # still set here, for the switch
    panel.method.setCurrentText("dragposer")
    qtbot.waitUntil(lambda: s.latest.method == "dragposer" and bool(s.latest.losses), timeout=30000)
    qtbot.waitUntil(lambda: panel.settings_note.isHidden(), timeout=10000)
    s.seek(20)
    qtbot.waitUntil(lambda: s.latest.frame == 20 and s.latest.method == "dragposer", timeout=30000)
    run, iterations, opened = s.latest.history_run, s.latest.iterations, s.latest.opened
    panel.ghost_boxes["ik"].click()
    qtbot.waitUntil(lambda: "ik" in s.latest.ghosts, timeout=30000)
    # the paused frame is solved again from its kept state, not from a reset
    assert s.latest.history_run == run and s.latest.opened == opened and s.latest.iterations <= iterations
