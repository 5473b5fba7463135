"""Reconstruction methods behind one interface, and a registry to build them by name.

Every module of this package that defines ``create(**kwargs) -> Method`` is registered
under its file name (:func:`method_modules`); ``register_method(name, factory)`` adds
others (tests, plugins). ``get_method(name, **kwargs)`` builds one (keyword arguments
such as ``mode`` or ``iterations`` go to the factory, which may ignore them).
:func:`run_method` runs a method over a whole simulated clip.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.methods import driver
from engine.methods.base import (
    Configurable,
    Constrainable,
    DecodesLatents,
    FrameResult,
    Method,
    SensorWeighted,
    SolvesClips,
)
from engine.sensors import Sensor, SensorFrame

if TYPE_CHECKING:
    from engine.motion.clip import Motion
    from engine.tracking.simulate import Tracking

__all__ = [
    "Configurable",
    "Constrainable",
    "DecodesLatents",
    "FrameResult",
    "Method",
    "SensorWeighted",
    "SolvesClips",
    "SensorFrame",
    "Sensor",
    "available_methods",
    "get_method",
    "method_modules",
    "register_method",
    "run_method",
]

_FACTORIES: dict[str, Callable[..., Method]] = {}


def register_method(name: str, factory: Callable[..., Method]) -> None:
    """Make ``factory(**kwargs) -> Method`` available as ``name`` (replaces an old entry)."""
    _FACTORIES[name] = factory


def available_methods() -> tuple[str, ...]:
    """Registered method names, sorted."""
    return tuple(sorted(_FACTORIES))


def get_method(name: str, **kwargs: Any) -> Method:
    """Build the method registered as ``name``.

    Raises
    ------
    UserError
        For an unknown name; the message lists the registered ones.
    """
    if name not in _FACTORIES:
        raise UserError(f"unknown method {name!r}; available: {', '.join(available_methods())}")
    return _FACTORIES[name](**kwargs)


def run_method(
    method: Method,
    tracking: Tracking,
    skeleton: sk.Skeleton,
    progress: bool = True,
    reference: Motion | None = None,
    desc: str | None = None,
    light: bool = False,
) -> tuple[Motion, Sequence[FrameResult]]:
    """Reconstruct a whole clip, frame by frame, as a realtime caller would.

    Parameters
    ----------
    method : Method
        Reset here for the clip.
    tracking : Tracking
        Simulated sensor stream (F frames).
    skeleton : Skeleton
        The subject's skeleton (the ground truth's, as in RPM's calibrated setup).
    progress : bool
        Show a tqdm progress bar (on stderr).
    reference : Motion, optional
        Ground truth, passed to ``reset`` only if ``method.needs_ground_truth``
        (:func:`engine.methods.driver.reset`).
    desc : str, optional
        Progress-bar label.
    light : bool
        Keep the results in arrays allocated (and written) up front
        (:class:`~engine.methods.records.ResultArrays`: the frames' ``FrameResult`` are
        built when read, their pose fields views into those arrays, their ``losses``
        only the final total), so memory stays flat over long clips (``reconstruct``,
        ``evaluate``).

    Returns
    -------
    motion : Motion
        The reconstruction (F frames, ``tracking.fps``).
    results : list of FrameResult (a ResultArrays sequence when ``light``)
        One per frame; ``ms`` is filled with the measured step time when the method
        left it at 0.

    Raises
    ------
    UserError
        When the method needs the ground truth and ``reference`` is None.
    FloatingPointError
        When the method returns a non-finite pose.
    """
    from tqdm import tqdm

    from engine.motion.clip import Motion

    driver.reset(method, skeleton, tracking.fps, reference)
    n = len(tracking)
    if light:
        from engine.methods.records import ResultArrays

        records = ResultArrays(n)
        local, root = records.local_rot, records.root_pos
    else:
        results: list[FrameResult] = []
        local, root = np.full((n, sk.NUM_JOINTS, 4), np.nan), np.full((n, 3), np.nan)
    # a method may solve the whole clip at once (DragPoser's batched offline mode)
    whole = isinstance(method, SolvesClips)
    solved = driver.solve_clip(method, [tracking.frame(i) for i in range(n)]) if whole else None
    for i in tqdm(
        range(n), desc=desc or method.name, unit="frame", disable=not progress or solved is not None, leave=False
    ):
        t0 = time.perf_counter()
        res = solved[i] if solved is not None else driver.step(method, tracking.frame(i))
        if not res.ms:
            res.ms = 1000.0 * (time.perf_counter() - t0)
        if light:
            records.store(i, res)
        else:
            local[i], root[i] = res.local_rot, res.root_pos
            results.append(res)
    name = reference.name if reference is not None else ""
    return Motion(local, root, skeleton, tracking.fps, name), records if light else results


#: A module of this package is a method when it defines a top-level ``create``.
_CREATE = re.compile(r"^def create\(", re.MULTILINE)


def method_modules(folder: Path) -> list[str]:
    """Names of the modules in ``folder`` that define a top-level ``create(**kwargs)``
    (found by reading them, not importing them), sorted."""
    return sorted(
        info.name
        for info in pkgutil.iter_modules([str(folder)])
        if not info.ispkg and _CREATE.search((folder / f"{info.name}.py").read_text(encoding="utf-8"))
    )


def _lazy(module: str) -> Callable[..., Method]:
    """A factory that imports ``engine.methods.<module>`` only when a method is built:
    DragPoser pulls in torch and the models, which the CLI's other commands should not
    pay for at start-up."""

    def build(**kwargs: Any) -> Method:
        return importlib.import_module(f"{__name__}.{module}").create(**kwargs)

    return build


def _register_builtin() -> None:
    """Register every method module of this package under its module name
    (docs/architecture.md, "Add a method")."""
    for name in method_modules(Path(__file__).parent):
        register_method(name, _lazy(name))


_register_builtin()
