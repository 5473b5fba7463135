"""Constraint frame ranges in a window: the range offered when a constraint is limited
to frames, and the selected constraint's range drawn on the window's timeline.

Both windows (the studio, the pose window) wire their constraint panel to their timeline
here, so a pin made on a paused frame is limited with one tick to the frames around it
(or to the frames selected on the timeline) and its span is seen under the scrub bar.
Edits of the range go through the panel's ``changed`` like any other field, so each is
one undo step of the window's model.
"""

from __future__ import annotations

from collections.abc import Callable

from widgets.constraint_panel import ConstraintPanel

#: Frames either side of the current one offered when a constraint is limited to frames
#: and the timeline has no selection (half a second at 60 fps).
AROUND_FRAMES = 30


def offered_range(frame: int, frames: int, selection: tuple[int, int] | None) -> tuple[int, int]:
    """The timeline's selection, else :data:`AROUND_FRAMES` either side of ``frame``,
    within the ``frames`` of the clip or animation."""
    if selection is not None:
        return int(selection[0]), int(selection[1])
    last = max(0, int(frames) - 1)
    return max(0, int(frame) - AROUND_FRAMES), min(last, int(frame) + AROUND_FRAMES)


def link_ranges(
    panel: ConstraintPanel,
    show_span: Callable[[tuple[int, int, int, int] | None], None],
    frame: Callable[[], int],
    frames: Callable[[], int],
    selection: Callable[[], tuple[int, int] | None] = lambda: None,
) -> None:
    """Offer ranges from the window's ``frame``, ``frames`` and timeline ``selection``, and
    draw the selected constraint's range with ``show_span`` whenever it or the selection
    in the panel changes."""
    panel.frame_count = frames
    panel.default_range = lambda: offered_range(frame(), frames(), selection())
    panel.selected.connect(lambda _name: show_span(panel.span()))
