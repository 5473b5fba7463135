"""Load model weights files, checking what they are before trusting them.

A weights file is a dict saved with ``torch.save``: ``format_version``, ``kind``
("vae", "predictor", "sparseposer" or "rpm"), ``config``, ``state_dict`` and ``meta`` (training data hash,
epochs, validation figures). Anything else is a :class:`ModelFileError` naming the file.
"""

from __future__ import annotations

import pickle
import zipfile
from dataclasses import dataclass
from pathlib import Path

import torch

from engine.errors import ModelFileError
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.vae import PoseVAE, VAEConfig

FORMAT_VERSION = 1
ASSETS = Path(__file__).resolve().parents[2] / "assets" / "models"
DEFAULT_VAE = ASSETS / "vae.pt"
DEFAULT_PREDICTOR = ASSETS / "predictor.pt"
DEFAULT_SPARSEPOSER = ASSETS / "sparseposer.pt"
DEFAULT_RPM = ASSETS / "rpm.pt"


@dataclass
class ModelBundle:
    """The models a latent-space method needs, frozen and in eval mode."""

    vae: PoseVAE
    predictor: TemporalPredictor | None
    vae_meta: dict
    predictor_meta: dict


def _read(path: Path, kind: str) -> dict:
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: weights file not found")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except (pickle.UnpicklingError, zipfile.BadZipFile, RuntimeError, EOFError, ValueError) as exc:
        raise ModelFileError(f"{path}: not a readable torch weights file ({type(exc).__name__}: {exc})") from exc
    if not isinstance(payload, dict) or "kind" not in payload or "state_dict" not in payload:
        raise ModelFileError(f"{path}: not a dragposer-studio weights file (no 'kind'/'state_dict')")
    if payload["kind"] != kind:
        raise ModelFileError(f"{path}: holds a {payload['kind']!r} model, expected {kind!r}")
    version = payload.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(f"{path}: format_version {version!r}, this program reads {FORMAT_VERSION}")
    return payload


def _load_state(model: torch.nn.Module, payload: dict, path: Path) -> None:
    try:
        model.load_state_dict(payload["state_dict"])
    except RuntimeError as exc:
        first = str(exc).splitlines()[1:3]
        raise ModelFileError(f"{path}: weights do not fit the model ({'; '.join(s.strip() for s in first)})") from exc


def load_vae(path: Path | str) -> tuple[PoseVAE, dict]:
    payload = _read(Path(path), "vae")
    try:
        cfg = VAEConfig.from_dict(payload["config"])
    except (TypeError, KeyError) as exc:
        raise ModelFileError(f"{path}: bad VAE config ({exc})") from exc
    vae = PoseVAE(cfg)
    _load_state(vae, payload, Path(path))
    vae.eval().requires_grad_(False)
    return vae, dict(payload.get("meta", {}))


def load_predictor(path: Path | str) -> tuple[TemporalPredictor, dict]:
    payload = _read(Path(path), "predictor")
    try:
        cfg = PredictorConfig(**payload["config"])
    except TypeError as exc:
        raise ModelFileError(f"{path}: bad predictor config ({exc})") from exc
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
