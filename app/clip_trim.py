"""Edit ▸ Trim clip to selection: keep only the frames selected on the timeline, undoably.

The entry names the frames it keeps ("Trim clip to frames 89-120", frames counted from
0 as the timeline shows them) and is enabled only when a motion file is loaded (a
tracker recording or live stream has no clip to cut; its tooltip says so) and the
timeline's selection (Shift-drag) is not the whole clip. Trimming is
:func:`engine.studio.clip_trim.trim_clip`: the clip becomes the selected frames, the
constraints acting on "only frames" and the trackers' simulated failures move with
them (a constraint wholly outside them is turned off, named in the status bar), and the
frame shown moves with its frame (f -> f - first, clamped). It replaces the clip the way
a range re-solve does (:func:`app.range_actions.replace_clip`): one step on the window's
undo stack, so Ctrl+Z gives the whole clip, the scene, the selection and the frame back;
File ▸ Save edited clip then writes the trimmed clip.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QMenu

from app.range_actions import ClipState, replace_clip
from engine.errors import UserError

if TYPE_CHECKING:
    from app.shell import StudioShell
    from engine.studio.clip_trim import ClipTrim

#: The entry's text when it cannot trim.
ENTRY = "&Trim clip to selection"


def trim_range(window: StudioShell) -> tuple[int, int] | None:
    """The frames a trim would keep (the timeline's selection), or None when the entry is
    off; :func:`why_not` says why."""
    return None if why_not(window) else window.timeline.selection()


def why_not(window: StudioShell) -> str:
    """Why the clip cannot be trimmed now ("" when it can)."""
    session = window.session
    if session.source is not None:
        return "Tracker input (a recording or live stream) has no clip to trim: open a motion file"
    if session.motion is None:
        return "Open a motion file first"
    sel = window.timeline.selection()
    if sel is None:
        return "Select the frames to keep: Shift-drag on the timeline"
    if sel[0] <= 0 and sel[1] >= len(session.motion) - 1:
        return "The whole clip is selected: Shift-drag on the timeline to select fewer frames"
    return ""


def trim_to(window: StudioShell, first: int, last: int) -> ClipTrim:
    """Keep frames ``first..last`` (inclusive) of the window's clip, one undo step; returns
    the trim (its ``turned_off`` names the constraints turned off).

    Raises
    ------
    UserError
        With no motion file loaded, or a range outside the clip.
    """
    from engine.studio.clip_trim import trim_clip

    session = window.session
    if session.motion is None or session.source is not None:
        raise UserError("open a motion file first: tracker input has no clip to trim")
    constraints, sensors = tuple(session.constraints), tuple(session.sensors.values())
    cut = trim_clip(session.motion, constraints, sensors, first, last)
    moved_c = any(a is not b for a, b in zip(cut.constraints, constraints))
    moved_s = any(a is not b for a, b in zip(cut.sensors, sensors))
    frame, preset = session.frame, session.preset
    before = ClipState(
        session.motion,
        frame,
        constraints if moved_c else None,
        sensors if moved_s else None,
        preset,
        window.timeline.selection(),
    )
    after = ClipState(
        cut.motion,
        min(max(frame - first, 0), last - first),
        cut.constraints if moved_c else None,
        cut.sensors if moved_s else None,
        preset,
        None,  # the selection was the whole trimmed clip
    )
    replace_clip(window, f"trim clip to frames {first}-{last}", before, after)
    return cut


def trim_to_selection(window: StudioShell) -> None:
    """The menu entry: trim to the timeline's selection and say what was done."""
    sel = trim_range(window)
    if sel is None:
        window.statusBar().showMessage(why_not(window), 5000)
        return
    try:
        cut = trim_to(window, *sel)
    except UserError as exc:
        window.show_error("Trim clip", str(exc))
        return
    note = f"Trimmed the clip to frames {sel[0]}-{sel[1]} ({len(cut.motion)} frames; Ctrl+Z gives the whole clip back)"
    if cut.turned_off:
        names = ", ".join(cut.turned_off)
        note += f". Turned off (their frames were cut): {names}"
    window.statusBar().showMessage(note, 15000)


def update_entry(window: StudioShell, act: QAction) -> None:
    """Name the frames the entry keeps, or disable it with the reason as its tooltip."""
    reason = why_not(window)
    act.setEnabled(not reason)
    if reason:
        act.setText(ENTRY)
        act.setToolTip(reason)
        return
    first, last = window.timeline.selection() or (0, 0)
    act.setText(f"&Trim clip to frames {first}-{last}")
    act.setToolTip(f"Keep frames {first}-{last} ({last - first + 1} frames) only; Ctrl+Z gives the whole clip back")


class TrimEntry:
    """Edit ▸ Trim clip to selection, kept in step with the timeline's selection and the
    loaded clip or source; :meth:`close` drops its subscriptions to the session's events
    (the window closes it with its other views)."""

    def __init__(self, window: StudioShell, edit_menu: QMenu, action: Callable[..., QAction]) -> None:
        self.window = window
        self.act = action(window, edit_menu, ENTRY, lambda: trim_to_selection(window))
        edit_menu.setToolTipsVisible(True)  # the reason it is off
        window.timeline.selectionChanged.connect(self.refresh)
        window.session.events.motion.connect(self.refresh)
        window.session.events.source.connect(self.refresh)
        self.refresh()

    def refresh(self, *_: object) -> None:
        update_entry(self.window, self.act)

    def close(self) -> None:
        self.window.session.events.motion.disconnect(self.refresh)
        self.window.session.events.source.disconnect(self.refresh)


def add_edit_entries(window: StudioShell, edit_menu: QMenu, action: Callable[..., QAction]) -> dict[str, QAction]:
    """Add Trim clip to selection to ``edit_menu`` (``window.trim_entry``, closed with the
    window)."""
    window.trim_entry = TrimEntry(window, edit_menu, action)
    return {"trim_clip": window.trim_entry.act}
