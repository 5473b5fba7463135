"""Load model weights files, checking what they are before trusting them.

A weights file is a dict saved with ``torch.save``: ``format_version``, ``kind``
("vae", "predictor", "sparseposer" or "rpm"), ``config``, ``state_dict`` and ``meta`` (training data hash,
epochs, validation figures). Anything else is a :class:`ModelFileError` naming the file.
"""

from __future__ import annotations

import copy
import pickle
import pickletools
import re
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from engine.errors import ModelFileError, UserError
from engine.models.config import ModelConfig
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.vae import PoseVAE, VAEConfig
from engine.models.weights_check import check_config, check_fits, check_state, shape_only
from engine.validation import check_input_file, one_line, shown

try:
    from numpy._core.multiarray import scalar as _np_scalar
except ImportError:  # numpy 1.x
    from numpy.core.multiarray import scalar as _np_scalar  # type: ignore[no-redef]  # the same function

FORMAT_VERSION = 1
#: First bytes of a zip archive, the container ``torch.save`` writes.
ZIP_MAGIC = b"PK\x03\x04"
ASSETS = Path(__file__).resolve().parents[2] / "assets" / "models"
DEFAULT_VAE = ASSETS / "vae.pt"
DEFAULT_PREDICTOR = ASSETS / "predictor.pt"
DEFAULT_SPARSEPOSER = ASSETS / "sparseposer.pt"
DEFAULT_RPM = ASSETS / "rpm.pt"
#: The only non-builtin types a checkpoint may hold besides tensors: numpy scalars that
#: end up in loss curves and metadata.
SAFE_GLOBALS: list[Any] = [
    np.dtype,
    np.float64,
    np.float32,
    np.int64,
    np.int32,
    np.bool_,
    type(np.dtype(np.float64)),
    type(np.dtype(np.float32)),
    type(np.dtype(np.int64)),
    _np_scalar,
]


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

    The file is checked first (regular file, size limit: :mod:`engine.validation`) and
    must be the zip archive ``torch.save`` writes. Every failure is one
    :class:`ModelFileError` line naming the file, without torch's warnings or its advice
    to turn the protection off."""
    path = Path(path)
    try:
        check_input_file(path, what)
        with open(path, "rb") as fh:
            head = fh.read(64)
    except UserError as exc:
        raise ModelFileError(str(exc)) from None
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    if not head.startswith(ZIP_MAGIC):
        raise ModelFileError(f"{path}: not a torch {what}: {_looks_like(head)}, not the zip archive torch.save writes")
    try:
        with torch.serialization.safe_globals(SAFE_GLOBALS), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. "Detected pickle protocol 4": the errors below say what matters
            return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        op = re.search(r"Unsupported operand (\d+)", str(exc))
        if op:
            # code2op: pickletools' table of opcodes by code, public but absent from typeshed
            code = pickletools.code2op.get(chr(int(op.group(1))))  # type: ignore[attr-defined]
            name = f" ({code.name})" if code else ""
            raise ModelFileError(
                f"{path}: refused: the {what} uses pickle instruction {op.group(1)}{name}, which the "
                f"safe loader does not read (save it with torch.save's default pickle protocol)"
            ) from None
        hint = _refused_global(str(exc))
        raise ModelFileError(
            f"{path}: refused: the {what} holds {hint} (only tensors and plain values are loaded)"
        ) from None
    except MemoryError:
        raise ModelFileError(f"{path}: not a readable torch {what} (out of memory while reading it)") from None
    except Exception as exc:  # a damaged archive fails anywhere in the unpickler, with any type
        first = one_line(str(exc).split(". ")[0], 160)
        raise ModelFileError(f"{path}: not a readable torch {what} ({type(exc).__name__}: {first})") from None


def _looks_like(head: bytes) -> str:
    """What the first bytes of a file that is not a zip archive suggest, for the message."""
    if not head:
        return "the file is empty"
    if head[:1] == b"\x80":
        return "it is a plain pickle"
    text = head.decode("utf-8", errors="replace").rstrip("\ufffd")  # the 64 bytes may cut a character
    if text and all(c.isprintable() or c in "\t\r\n" for c in text):
        return "it is a text file"
    return "its format is unknown"


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
    meta = payload.get("meta", {})
    if not isinstance(meta, dict):
        raise ModelFileError(f"{path}: field 'meta' must be a dict, got {type(meta).__name__} {shown(meta)}")
    return payload


def _build(path: Path | str, kind: str, config_cls: type[ModelConfig], model_cls: type) -> tuple[Any, dict]:
    """The model of ``kind`` in ``path``, frozen, and its ``meta``.

    The config is checked and the model's shapes compared with the file's before any
    model memory is allocated (:mod:`engine.models.weights_check`)."""
    path = Path(path)
    payload = _read(path, kind)
    where = f"{path}: config"
    config = check_config(kind, payload["config"], config_cls, where)
    try:
        cfg = config_cls.from_dict(config)
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{where}: {shown(str(exc), 120)}") from None
    skeleton = shape_only(lambda: model_cls(cfg), where)
    check_state(skeleton, payload["state_dict"], config, path)
    check_fits(skeleton, config, path)
    model = model_cls(cfg)
    model.load_state_dict(payload["state_dict"])
    bad = [
        name for name, t in model.state_dict().items() if t.is_floating_point() and not bool(torch.isfinite(t).all())
    ]
    if bad:
        more = f" and {len(bad) - 1} more" if len(bad) > 1 else ""
        raise ModelFileError(f"{path}: weights hold NaN or infinite values (in {bad[0]}{more}); the file is damaged")
    model.eval().requires_grad_(False)
    return model, dict(payload.get("meta", {}))


def load_vae(path: Path | str) -> tuple[PoseVAE, dict]:
    """The pose VAE of the weights file ``path`` and its ``meta``."""
    return _build(path, "vae", VAEConfig, PoseVAE)


def load_predictor(path: Path | str) -> tuple[TemporalPredictor, dict]:
    """The temporal predictor of the weights file ``path`` and its ``meta``."""
    return _build(path, "predictor", PredictorConfig, TemporalPredictor)


def load_sparseposer(path: Path | str | None = None):
    """SparsePoser (generator + learned IK) from ``path`` (default: the shipped file)."""
    from engine.models.sparseposer import SparsePoser, SparsePoserConfig

    return _build(path or DEFAULT_SPARSEPOSER, "sparseposer", SparsePoserConfig, SparsePoser)


def load_rpm(path: Path | str | None = None):
    """The Rolling Prediction Model from ``path`` (default: the shipped file)."""
    from engine.models.rpm import RPM, RPMConfig

    return _build(path or DEFAULT_RPM, "rpm", RPMConfig, RPM)


def load_models(vae_path: Path | str, predictor_path: Path | str | None = None) -> ModelBundle:
    """Load a VAE and optionally a predictor trained on its latents."""
    vae, vmeta = load_vae(vae_path)
    pred: TemporalPredictor | None = None
    pmeta: dict = {}
    if predictor_path is not None:
        pred, pmeta = load_predictor(predictor_path)
        if pred.config.latent != vae.config.latent:
            raise ModelFileError(
                f"{predictor_path}: predictor latent size {pred.config.latent} != VAE's {vae.config.latent}"
            )
    return ModelBundle(vae, pred, vmeta, pmeta)


def _file_key(path: Path) -> tuple[str, int, int, int]:
    """Which file ``path`` is now (inode, size, modification time in ns): a file replaced
    on disk, written in place or renamed over, gets another key."""
    st = path.stat()
    return str(path), st.st_ino, st.st_size, st.st_mtime_ns


#: The shipped models as last loaded, by :func:`_file_key` of their files.
_SHIPPED: dict[tuple, ModelBundle] = {}
_SHIPPED_LOCK = threading.Lock()


def load_default_models(require_predictor: bool = False) -> ModelBundle:
    """The shipped models in ``assets/models`` (the predictor only if present, unless required).

    They are read once per process and shared: each call returns a new bundle that holds
    the same frozen modules (eval mode, ``requires_grad`` off; nothing may change them)
    and copies of their ``meta``. Building DragPoser again (the studio's export and
    ghosts, a method switch, the pose window) then reads and checks no file (about
    0.5 CPU s) and reuses the fused decoder made for the model
    (:func:`engine.solver.optimizer.dense_decoder`, about 0.8 CPU s). A file replaced on
    disk is read again."""
    pred = DEFAULT_PREDICTOR if (DEFAULT_PREDICTOR.is_file() or require_predictor) else None
    try:
        key = tuple(_file_key(p) for p in (DEFAULT_VAE, pred) if p is not None)
    except OSError:  # missing: load_models says so, naming the file
        return load_models(DEFAULT_VAE, pred)
    with _SHIPPED_LOCK:
        if key not in _SHIPPED:
            _SHIPPED.clear()  # a replaced file: the old models are not kept alive
            _SHIPPED[key] = load_models(DEFAULT_VAE, pred)
        shared = _SHIPPED[key]
    return ModelBundle(
        shared.vae, shared.predictor, copy.deepcopy(shared.vae_meta), copy.deepcopy(shared.predictor_meta)
    )
