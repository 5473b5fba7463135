"""Options that choose the models and tune the method, shared by ``evaluate``,
``reconstruct`` and ``live``: ``--vae``, ``--predictor`` and ``--set KEY=VALUE``, and
:func:`build_method`, which also applies a ``--scene``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from engine.errors import UserError
from engine.solver.settings import SETTINGS

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.methods.base import Method


def add_model_options(p: argparse.ArgumentParser) -> None:
    """Add ``--vae``, ``--predictor`` and the repeatable ``--set`` to a subcommand."""
    p.add_argument("--vae", type=Path, metavar="VAE.pt", help="user-trained VAE weights (default: the shipped model)")
    p.add_argument("--predictor", type=Path, metavar="PRED.pt", help="its temporal predictor (with --vae)")
    p.add_argument(
        "--sparseposer-model",
        type=Path,
        dest="sparseposer_path",
        metavar="SP.pt",
        help="SparsePoser weights for --method sparseposer (default: the shipped model)",
    )
    p.add_argument(
        "--rpm-model",
        type=Path,
        dest="rpm_path",
        metavar="RPM.pt",
        help="RPM weights for --method rpm (default: the shipped model)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="optimizer setting of a latent-space method, repeatable, e.g. root_anchor=none; KEY is "
        f"one of {', '.join(SETTINGS)} (ranges and meanings: docs/optimizer.md)",
    )


#: Model-file keywords and the methods that take them (others must not receive them).
_MODEL_KEYS = {
    "vae_path": ("dragposer", "autoencoder"),
    "predictor_path": ("dragposer", "autoencoder"),
    "sparseposer_path": ("sparseposer",),
    "rpm_path": ("rpm",),
}


def method_kwargs(args: argparse.Namespace, mode: str, name: str | None = None) -> dict[str, Any]:
    """Keywords for ``engine.methods.get_method`` from ``--iterations``, ``--lr``,
    ``--vae``, ``--predictor``, ``--sparseposer-model`` and ``--rpm-model`` (only those
    given; with ``name``, only the model files that method reads)."""
    kw: dict[str, Any] = {"mode": mode}
    given = {
        "iterations": args.iterations,
        "lr": args.lr,
        "vae_path": args.vae,
        "predictor_path": args.predictor,
        "sparseposer_path": getattr(args, "sparseposer_path", None),
        "rpm_path": getattr(args, "rpm_path", None),
    }
    kw.update({k: v for k, v in given.items() if v is not None})
    if name is not None:
        kw = {k: v for k, v in kw.items() if k not in _MODEL_KEYS or name in _MODEL_KEYS[k]}
    return kw


def apply_settings(method: Method, name: str, items: list[str]) -> dict[str, Any]:
    """Apply ``--set key=value`` optimizer settings to ``method``; returns them."""
    if not items:
        return {}
    from engine.config import parse_overrides
    from engine.methods import driver
    from engine.solver import OptimizerSettings

    values = parse_overrides(OptimizerSettings, items)
    if not driver.configure(method, values):
        raise UserError(f"method {name!r} has no optimizer settings; --set applies to latent-space methods")
    return values


def build_method(args: argparse.Namespace) -> Method:
    """The method of ``--method`` with ``--scene`` constraints and settings, ``--mode``,
    ``--iterations``, ``--lr``, the models and ``--set`` applied (command line wins)."""
    import dataclasses

    from engine.methods import driver, get_method

    constraints: list[Constraint] = []
    scene_settings: dict[str, Any] = {}
    if getattr(args, "scene", None):
        from engine.scene import load_scene
        from engine.solver import OptimizerSettings

        constraints, settings = load_scene(args.scene)
        defaults = dataclasses.asdict(OptimizerSettings())
        scene_settings = {k: v for k, v in dataclasses.asdict(settings).items() if v != defaults[k]}
    kwargs = method_kwargs(args, args.mode or scene_settings.get("mode", "realtime"), args.method)
    method = get_method(args.method, **kwargs)
    if scene_settings:
        given = {"mode"} if args.mode else set()
        given |= {"iterations", "max_iterations"} if args.iterations is not None else set()
        given |= {"lr"} if args.lr is not None else set()
        if not driver.configure(method, {k: v for k, v in scene_settings.items() if k not in given}):
            raise UserError(f"method {args.method!r} takes no scene settings")
    apply_settings(method, args.method, args.set)
    if constraints and not driver.set_constraints(method, constraints):
        raise UserError(f"method {args.method!r} takes no constraints (--scene); they apply to latent-space methods")
    return method
