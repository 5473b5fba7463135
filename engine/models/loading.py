"""Load model weights files, checking what they are before trusting them.

A weights file is a dict saved with ``torch.save``: ``format_version``, ``kind``
("vae", "predictor", "sparseposer" or "rpm"), ``config``, ``state_dict`` and ``meta`` (training data hash,
epochs, validation figures). Anything else is a :class:`ModelFileError` naming the file.
"""

from __future__ import annotations

import pickle
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from engine.errors import ModelFileError, UserError
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.vae import PoseVAE, VAEConfig
from engine.validation import (PREDICTOR_CONFIG, VAE_CHANNEL, VAE_CONFIG, check_fields, check_input_file,
                               check_value, one_line, shown)  # fmt: skip

try:
    from numpy._core.multiarray import scalar as _np_scalar
except ImportError:  # numpy 1.x
    from numpy.core.multiarray import scalar as _np_scalar

FORMAT_VERSION = 1
ASSETS = Path(__file__).resolve().parents[2] / "assets" / "models"
DEFAULT_VAE = ASSETS / "vae.pt"
DEFAULT_PREDICTOR = ASSETS / "predictor.pt"
DEFAULT_SPARSEPOSER = ASSETS / "sparseposer.pt"
DEFAULT_RPM = ASSETS / "rpm.pt"
#: The only non-builtin types a checkpoint may hold besides tensors: numpy scalars that
#: end up in loss curves and metadata.
SAFE_GLOBALS = [np.dtype, np.float64, np.float32, np.int64, np.int32, np.bool_, type(np.dtype(np.float64)),
                type(np.dtype(np.float32)), type(np.dtype(np.int64)), _np_scalar]  # fmt: skip


@dataclass
class ModelBundle:
    """The models a latent-space method needs, frozen and in eval mode."""

    vae: PoseVAE
    predictor: TemporalPredictor | None
    vae_meta: dict
    predictor_meta: dict


def load_checkpoint(path: Path | str, what: str = "weights file") -> Any:
    """``torch.load`` that can never run code: ``weights_only=True``, so only tensors and
    plain values (dict, list, tuple, str, int, float, bool, None, and the numpy scalars
    of :data:`SAFE_GLOBALS`) are rebuilt; anything else is refused.

    The file is checked first (regular file, size limit: :mod:`engine.validation`).
    Every failure is one :class:`ModelFileError` line naming the file, without torch's
    advice to turn the protection off."""
    path = Path(path)
    try:
        check_input_file(path, what)
    except UserError as exc:
        raise ModelFileError(str(exc)) from None
    try:
        with torch.serialization.safe_globals(SAFE_GLOBALS):
            return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        hint = _refused_global(str(exc))
        raise ModelFileError(
            f"{path}: refused: the {what} holds {hint} (only tensors and plain values are loaded)"
        ) from None
    except (zipfile.BadZipFile, RuntimeError, EOFError, ValueError, OSError, AttributeError, TypeError) as exc:
        first = one_line(str(exc).split(". ")[0], 160)
        raise ModelFileError(f"{path}: not a readable torch {what} ({type(exc).__name__}: {first})") from None


def _refused_global(message: str) -> str:
    """What torch refused to unpickle, from its message (``GLOBAL os.system``...)."""
    m = re.search(r"GLOBAL ([\w.]+)|Unsupported global: ([\w.]+)|unsupported ([\w.]+)", message)
    if m:
        return f"a Python object ({next(g for g in m.groups() if g)})"
    return "something other than tensors and plain values"


def _read(path: Path, kind: str) -> dict:
    payload = load_checkpoint(path)
    if not isinstance(payload, dict) or "kind" not in payload or "state_dict" not in payload:
        raise ModelFileError(f"{path}: not a dragposer-studio weights file (no 'kind'/'state_dict')")
    if payload["kind"] != kind:
        raise ModelFileError(f"{path}: holds a {shown(payload['kind'])} model, expected {kind!r}")
    version = payload.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(f"{path}: format_version {shown(version)}, this program reads {FORMAT_VERSION}")
    if not isinstance(payload.get("config"), dict):
        raise ModelFileError(f"{path}: field 'config' must be a dict of model sizes")
    return payload


def _load_state(model: torch.nn.Module, payload: dict, path: Path) -> None:
    state = payload["state_dict"]
    if not isinstance(state, dict):
        raise ModelFileError(f"{path}: field 'state_dict' must be a dict of tensors")
    try:
        model.load_state_dict(state)
    except (RuntimeError, TypeError, AttributeError) as exc:
        first = str(exc).splitlines()[1:3]
        raise ModelFileError(f"{path}: weights do not fit the model ({'; '.join(s.strip() for s in first)})") from None
    bad = [name for name, t in model.state_dict().items() if t.is_floating_point() and not bool(torch.isfinite(t).all())]
    if bad:
        more = f" and {len(bad) - 1} more" if len(bad) > 1 else ""
        raise ModelFileError(f"{path}: weights hold NaN or infinite values (in {bad[0]}{more}); the file is damaged")


def load_vae(path: Path | str) -> tuple[PoseVAE, dict]:
    payload = _read(Path(path), "vae")
    try:
        config = check_fields(VAE_CONFIG, payload["config"], f"{path}: config")
        for i, c in enumerate(config.get("channels") or ()):
            check_value(VAE_CHANNEL, c, f"{path}: config", f"channels[{i}]")
        cfg = VAEConfig.from_dict(config)
    except (TypeError, KeyError, ValueError) as exc:
        raise ModelFileError(f"{path}: bad VAE config ({shown(str(exc), 120)})") from None
    vae = PoseVAE(cfg)
    _load_state(vae, payload, Path(path))
    vae.eval().requires_grad_(False)
    return vae, dict(payload.get("meta", {}))


def load_predictor(path: Path | str) -> tuple[TemporalPredictor, dict]:
    payload = _read(Path(path), "predictor")
    try:
        cfg = PredictorConfig(**check_fields(PREDICTOR_CONFIG, payload["config"], f"{path}: config"))
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{path}: bad predictor config ({shown(str(exc), 120)})") from None
    model = TemporalPredictor(cfg)
    _load_state(model, payload, Path(path))
    model.eval().requires_grad_(False)
    return model, dict(payload.get("meta", {}))


def load_sparseposer(path: Path | str | None = None):
    """SparsePoser (generator + learned IK) from ``path`` (default: the shipped file)."""
    from engine.models.sparseposer import SparsePoser, SparsePoserConfig

    path = Path(path or DEFAULT_SPARSEPOSER)
    payload = _read(path, "sparseposer")
    try:
        cfg = SparsePoserConfig.from_dict(payload["config"])
    except (TypeError, KeyError) as exc:
        raise ModelFileError(f"{path}: bad SparsePoser config ({exc})") from exc
    model = SparsePoser(cfg)
    _load_state(model, payload, path)
    model.eval().requires_grad_(False)
    return model, dict(payload.get("meta", {}))


def load_rpm(path: Path | str | None = None):
    """The Rolling Prediction Model from ``path`` (default: the shipped file)."""
    from engine.models.rpm import RPM, RPMConfig

    path = Path(path or DEFAULT_RPM)
    payload = _read(path, "rpm")
    try:
        cfg = RPMConfig(**payload["config"])
    except TypeError as exc:
        raise ModelFileError(f"{path}: bad RPM config ({exc})") from exc
    model = RPM(cfg)
    _load_state(model, payload, path)
    model.eval().requires_grad_(False)
    return model, dict(payload.get("meta", {}))


def load_models(vae_path: Path | str, predictor_path: Path | str | None = None) -> ModelBundle:
    """Load a VAE and optionally a predictor trained on its latents."""
    vae, vmeta = load_vae(vae_path)
    pred, pmeta = (None, {})
    if predictor_path is not None:
        pred, pmeta = load_predictor(predictor_path)
        if pred.config.latent != vae.config.latent:
            raise ModelFileError(
                f"{predictor_path}: predictor latent size {pred.config.latent} != VAE's {vae.config.latent}"
            )
    return ModelBundle(vae, pred, vmeta, pmeta)


def load_default_models(require_predictor: bool = False) -> ModelBundle:
    """The shipped models in ``assets/models`` (the predictor only if present, unless required)."""
    pred = DEFAULT_PREDICTOR if (DEFAULT_PREDICTOR.is_file() or require_predictor) else None
    return load_models(DEFAULT_VAE, pred)
