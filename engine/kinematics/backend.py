"""Which array kit a value belongs to, without importing torch.

The kinematics functions take numpy arrays or torch tensors. Numpy-only callers (the
studio's window, the file tools) must not pay for importing torch (about a CPU second),
so the check looks torch up in :data:`sys.modules` instead of importing it: a tensor can
only exist once torch has been imported, so a value is a tensor exactly when torch is
loaded and the value is an instance of its ``Tensor``.
"""

from __future__ import annotations

import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import torch
    from typing_extensions import TypeIs


def torch_of(x: Any) -> ModuleType | None:
    """The torch module when ``x`` is a torch tensor, else None (numpy arrays, lists,
    numbers); never imports torch."""
    tensor = getattr(sys.modules.get("torch"), "Tensor", None)  # None while torch is not (fully) loaded
    if tensor is not None and isinstance(x, tensor):
        return sys.modules["torch"]
    return None


def is_tensor(x: object) -> TypeIs[torch.Tensor]:
    """Whether ``x`` is a torch tensor, never importing torch; a type checker narrows
    ``x`` to ``torch.Tensor`` where it returns True (and away from it where False)."""
    tensor = getattr(sys.modules.get("torch"), "Tensor", None)
    return tensor is not None and isinstance(x, tensor)
