"""What the parts of an authoring session (:class:`~engine.authoring.session_pose.PoseEditing`,
:class:`~engine.authoring.session_keys.KeyEditing`) call on the session itself: its frame,
its state and its one edit machinery, declared once for the type checker;
:class:`engine.authoring.session.AuthoringSession` implements them."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable

    from engine.authoring.state import AuthoringState


class SessionCore:
    """The session's own members its parts use (declarations only)."""

    if TYPE_CHECKING:
        frame: int

        def state(self) -> AuthoringState: ...

        def edit(
            self,
            text: str,
            change: Callable[[], Any],
            key: tuple | None = None,
            solve: bool = False,
            framed: bool = False,
        ) -> None: ...
