"""What a weights file must hold before a model is built from it.

:mod:`engine.models.loading` reads a file into plain values; this module checks them in
an order that costs no memory until the file has earned it:

1. every field of ``config`` against the schema of its model kind (:data:`CONFIGS`), by
   name, plus the rules that tie fields together (``d_model`` a multiple of ``heads``);
2. the model the config describes is built on PyTorch's ``meta`` device (shapes, no
   storage) and the ``state_dict`` entries are compared with it: names, shapes, dtypes.
   A 1 kB file whose config says ``channels = 4000`` (16 billion values) is refused
   here, not after allocating them;
3. that model must fit in the file (tensors sharing one storage could pass step 2).

Only then does the loader build the model for real, so its memory is bounded by the
file's size (itself bounded by :data:`engine.validation.MAX_BYTES`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import fields
from pathlib import Path
from typing import Any

import torch

from engine.errors import ModelFileError
from engine.validation import Num, Schema, ValidationError, check_fields, check_value, one_line, shown

_CHANNEL = Num(1, 4096, integer=True)

#: ``config`` of a VAE weights file.
VAE_CONFIG: Schema = {
    "latent": Num(1, 1024, integer=True),
    "neighbour_distance": Num(0, 22, integer=True),
    "negative_slope": Num(0, 1),
}
#: ``config`` of a temporal predictor weights file.
PREDICTOR_CONFIG: Schema = {
    "latent": Num(1, 1024, integer=True),
    "cond": Num(1, 1024, integer=True),
    "d_model": Num(1, 4096, integer=True),
    "heads": Num(1, 64, integer=True),
    "encoder_layers": Num(1, 64, integer=True),
    "decoder_layers": Num(1, 64, integer=True),
    "feedforward": Num(1, 65_536, integer=True),
    "dropout": Num(0, 1),
    "past": Num(1, 1024, integer=True),
    "future": Num(1, 1024, integer=True),
    "stride": Num(1, 1024, integer=True),
}
#: ``config`` of a SparsePoser weights file.
SPARSEPOSER_CONFIG: Schema = {
    "window": Num(8, 1024, integer=True, unit="frames, a multiple of 8"),
    "kernel": Num(1, 31, integer=True, unit="frames, odd"),
    "ik_hidden": Num(1, 16_384, integer=True),
    "neighbour_distance": Num(0, 22, integer=True),
    "negative_slope": Num(0, 1),
}
#: ``config`` of an RPM weights file.
RPM_CONFIG: Schema = {
    "past_inputs": Num(0, 1024, integer=True, unit="frames"),
    "past_poses": Num(1, 1024, integer=True, unit="frames"),
    "window": Num(1, 1024, integer=True, unit="frames"),
    "hidden": Num(1, 16_384, integer=True),
    "blocks": Num(0, 64, integer=True),
}
#: Per kind: the scalar fields' schema and the length of the ``channels`` list (0: none).
CONFIGS: dict[str, tuple[Schema, int]] = {
    "vae": (VAE_CONFIG, 4),
    "predictor": (PREDICTOR_CONFIG, 0),
    "sparseposer": (SPARSEPOSER_CONFIG, 3),
    "rpm": (RPM_CONFIG, 0),
}
#: Rules between fields, per kind: (fields named, holds(config), what must hold).
_RULES: dict[str, list[tuple[str, Callable[[dict], bool], str]]] = {
    "predictor": [("d_model, heads", lambda c: c["d_model"] % c["heads"] == 0, "d_model a multiple of heads")],
    "sparseposer": [
        ("window", lambda c: c["window"] % 8 == 0, "a multiple of 8 (three halvings in time)"),
        ("kernel", lambda c: c["kernel"] % 2 == 1, "odd (centred windows)"),
    ],
}


def check_config(kind: str, config: Mapping[str, Any], config_cls: type, where: str) -> dict[str, Any]:
    """``config`` checked field by field against the schema of ``kind``.

    Fields the file leaves out take the dataclass defaults of ``config_cls``; a field
    that is not one of its dataclass fields is an error naming it.

    Raises
    ------
    ModelFileError
        One line naming ``where``, the field, its value and the allowed range.
    """
    schema, channels = CONFIGS[kind]
    known = [f.name for f in fields(config_cls)]
    for key in config:
        if key not in known:
            raise ModelFileError(f"{where}: unknown field {shown(key)}; known: {', '.join(known)}")
    full = {f.name: f.default for f in fields(config_cls)} | dict(config)
    try:
        out = check_fields(schema, full, where)
        if channels:
            value = full["channels"]
            if not isinstance(value, (list, tuple)) or len(value) != channels:
                raise ModelFileError(
                    f"{where}: channels = {shown(value)} is not a list of {channels} numbers; "
                    f"allowed: {channels} x {_CHANNEL.describe()}"
                )
            out["channels"] = [check_value(_CHANNEL, c, where, f"channels[{i}]") for i, c in enumerate(value)]
    except ValidationError as exc:
        raise ModelFileError(str(exc)) from None
    for names, holds, reason in _RULES.get(kind, []):
        if not holds(out):
            values = ", ".join(f"{n} = {out[n]}" for n in names.split(", "))
            raise ModelFileError(f"{where}: {values}: must be {reason}")
    return out


class _SkipMetaInPlace(torch.overrides.TorchFunctionMode):
    """In-place operations on ``meta`` tensors (weight initialisers, buffer copies) return
    their tensor untouched: there are no values to change, and torch runs a meta tensor's
    ``normal_`` through its reference implementation, whose first use imports the whole
    compiler stack (``torch._dynamo``, ~2 s of a model load)."""

    def __torch_function__(self, func: Any, types: Any, args: tuple = (), kwargs: dict | None = None) -> Any:
        kwargs = kwargs or {}
        name = getattr(func, "__name__", "")
        target = args[0] if args else kwargs.get("tensor")  # nn.init's functions name it ``tensor``
        if name.endswith("_") and not name.startswith("_") and isinstance(target, torch.Tensor) and target.is_meta:
            return target
        return func(*args, **kwargs)


def shape_only(build: Callable[[], torch.nn.Module], where: str) -> torch.nn.Module:
    """``build()`` on the ``meta`` device: the model's tensors have shapes, no storage
    (its initialisers skipped: :class:`_SkipMetaInPlace`)."""
    try:
        with torch.device("meta"), _SkipMetaInPlace(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return build()
    except Exception as exc:  # a config the checks let through but the model code refuses
        raise ModelFileError(f"{where}: does not describe a model ({one_line(str(exc), 160)})") from None


def check_fits(skeleton: torch.nn.Module, config: Mapping[str, Any], path: Path) -> None:
    """Refuse a config whose model holds more bytes than the weights file ``path``:
    every tensor of a model's state is stored in its file, so such a config cannot
    match the weights, and building the model would allocate memory for nothing."""
    need = sum(t.numel() * t.element_size() for t in skeleton.state_dict().values())
    size = path.stat().st_size
    if need > size:
        raise ModelFileError(
            f"{path}: config ({_summary(config)}) describes a model of {need:,} bytes, more than "
            f"the file's {size:,}; config and weights do not match"
        )


def _summary(config: Mapping[str, Any]) -> str:
    return one_line(", ".join(f"{k} = {v}" for k, v in config.items()), 200)


def check_state(skeleton: torch.nn.Module, state: Any, config: Mapping[str, Any], path: Path) -> None:
    """Compare ``state`` (a file's ``state_dict``) with the shape-only model ``skeleton``:
    same entry names and shapes (PyTorch's own comparison, with the models' hooks for
    renamed entries) and the same dtypes. Nothing is allocated."""
    if not isinstance(state, dict):
        raise ModelFileError(f"{path}: field 'state_dict' must be a dict of tensors, got {type(state).__name__}")
    for key, value in state.items():
        if not isinstance(key, str) or not isinstance(value, torch.Tensor):
            raise ModelFileError(f"{path}: state_dict[{shown(key)}] is a {type(value).__name__}, expected a tensor")
    try:
        with warnings.catch_warnings():  # copying into meta tensors is a no-op, which is the point
            warnings.simplefilter("ignore")
            skeleton.load_state_dict(state)
    except RuntimeError as exc:
        first = one_line("; ".join(s.strip() for s in str(exc).splitlines()[1:3]), 300)
        raise ModelFileError(f"{path}: weights do not fit the model of config ({_summary(config)}): {first}") from None
    expected = skeleton.state_dict()
    for key, value in state.items():
        want = expected.get(key)
        if want is not None and value.dtype != want.dtype:
            raise ModelFileError(f"{path}: state_dict[{shown(key)}] is {value.dtype}, the model needs {want.dtype}")
