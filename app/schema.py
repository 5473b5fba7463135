"""Describe the session's constraint kinds and optimizer settings as plain editor schemas."""

from __future__ import annotations

import dataclasses
from typing import Any

from engine.studio.session import Session


def _editor_field(f: Any) -> tuple[Any, ...]:
    """One catalog field as the panel's ``(name, tag, default[, choices])``."""
    if f.tag == "choice":
        return (f.name, "choice", f.default, tuple(f.choices))
    d = f.default
    if f.tag == "other" and "joint" in f.name and isinstance(d, (tuple, list)) and all(isinstance(v, str) for v in d):
        return (f.name, "joints", tuple(d))  # e.g. the floor's feet
    return (f.name, f.tag, d)


def constraint_schema() -> dict[str, list[tuple[Any, ...]]]:
    """kind -> [(field, tag, default[, choices])] for :class:`widgets.constraint_panel.ConstraintPanel`,
    from the session's catalog of user-facing kinds (so ``sensor`` and ``temporal_prior``,
    which methods build themselves, are not offered)."""
    return {kind: [_editor_field(f) for f in spec.fields] for kind, spec in Session.constraint_catalog().items()}


#: Anchors offered for ``root_anchor``: the head tracker, or integrating the decoded root.
ROOT_ANCHORS = ("upperneck", "none")


def optimizer_choices() -> tuple[dict[str, tuple[str, ...]], dict[str, Any]]:
    """Values of the optimizer's choice settings, and every setting's default.

    Only fields :class:`engine.solver.OptimizerSettings` really has are offered, so
    the panel never shows a control the engine would reject.

    Returns
    -------
    choices : dict
        ``mode``, ``optimizer`` (the latent update rule), ``prior`` (where the temporal
        prior's latent comes from) and ``root_anchor`` -> values.
    defaults : dict
        Field name -> default value, shown until the session sets the field.
    """
    from engine import solver as opt

    defaults = dataclasses.asdict(opt.OptimizerSettings())
    choices = {"mode": tuple(opt.MODES)}
    if "optimizer" in defaults and hasattr(opt, "OPTIMIZERS"):
        choices["optimizer"] = tuple(opt.OPTIMIZERS)
    if "prior" in defaults and hasattr(opt, "PRIORS"):
        choices["prior"] = tuple(opt.PRIORS)
    if "root_anchor" in defaults:
        anchor = str(defaults["root_anchor"])
        choices["root_anchor"] = ROOT_ANCHORS if anchor in ROOT_ANCHORS else (anchor, *ROOT_ANCHORS)
    return choices, defaults
