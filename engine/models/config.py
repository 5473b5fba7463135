"""What every model-architecture dataclass shares: a JSON-safe dict form for checkpoints."""

from __future__ import annotations

from dataclasses import asdict, fields
from typing import Any, TypeVar

T = TypeVar("T", bound="ModelConfig")


class ModelConfig:
    """Mixin for architecture dataclasses: tuples are stored as lists (JSON and
    ``weights_only`` checkpoints keep plain lists) and come back as tuples."""

    def to_dict(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}  # type: ignore[call-overload]

    @classmethod
    def from_dict(cls: type[T], d: dict[str, Any]) -> T:
        tuples = {f.name for f in fields(cls) if isinstance(f.default, tuple)}  # type: ignore[arg-type]
        return cls(**{k: tuple(v) if k in tuples else v for k, v in d.items()})
