"""A copy of a method's temporal state, to solve the frame on screen again from it.

While playback is paused every edit (a constraint added, dragged or removed, a sensor
toggled) solves the shown frame again. Solving it from the state the previous solve left
would pile the edits up: a knee dragged 20 cm and then unpinned stays where the drag left
it, because each solve starts from the last. :func:`copy_state` keeps the state the frame
had before the first edit, and every later solve of that frame starts from a copy of it.

Network weights and large arrays (decoders, pose banks) are shared, never copied: they
do not change between frames, and a copy of DragPoser then costs about 2 ms.
"""

from __future__ import annotations

import copy
import sys
from typing import Any

import numpy as np

#: Arrays (numpy or torch) with more elements than this are shared, not copied.
SHARED_SIZE = 4096
#: How deep the walk for shared objects goes (method -> optimizer -> its model ...).
DEPTH = 4


def _collect_shared(obj: Any, memo: dict[int, Any], depth: int) -> None:
    """Put modules and large arrays reachable from ``obj`` into ``memo`` (shared)."""
    if id(obj) in memo:
        return
    torch = sys.modules.get("torch")  # only when a method brought it in
    if torch is not None and isinstance(obj, torch.nn.Module):
        memo[id(obj)] = obj
        return
    if isinstance(obj, np.ndarray):
        if obj.size > SHARED_SIZE:
            memo[id(obj)] = obj
        return
    if torch is not None and isinstance(obj, torch.Tensor):
        if obj.numel() > SHARED_SIZE:
            memo[id(obj)] = obj
        return
    if depth == 0:
        return
    if isinstance(obj, dict):
        values: Any = obj.values()
    elif isinstance(obj, (list, tuple)):
        values = obj
    elif hasattr(obj, "__dict__"):
        values = vars(obj).values()
    else:
        return
    for value in values:
        _collect_shared(value, memo, depth - 1)


def copy_state(method: Any) -> Any:
    """A copy of ``method`` whose temporal state (latents, optimizer moments, histories)
    is its own; its networks and large arrays are the original's."""
    memo: dict[int, Any] = {}
    _collect_shared(method, memo, DEPTH)
    memo.pop(id(method), None)
    return copy.deepcopy(method, memo)
