"""The constraint-kinds table of ``docs/optimizer.md``, generated from the registry.

Each row is read off the kind itself: its parameters with units (field metadata), its
one-line summary (the class docstring) and what its residual is (the docstring of its
``term`` method, else of the term its first example builds: kinds that share a term
class say there what theirs is), so the table cannot fall behind the code.
``scripts/settings_table.py`` rewrites it between its markers and
``tests/engine/test_terms.py`` fails while the page differs.
"""

from __future__ import annotations

import re

import numpy as np

from engine import skeleton as sk
from engine.constraints import REGISTRY
from engine.constraints.base import FRAME_FIELDS
from engine.constraints.residual import FrameInputs
from engine.editing.catalog import COMMON_FIELDS, describe

BEGIN, END = "<!-- kinds table: generated -->\n", "<!-- end of kinds table -->"


def _first_sentence(doc: str | None) -> str:
    """The docstring's first sentence as Markdown (inline code, no Sphinx roles)."""
    text = " ".join((doc or "").split("\n\n")[0].split())
    text = text.split(". ")[0].rstrip(".") if text else ""
    text = re.sub(r":(?:class|func|attr|meth):`~?(?:[\w.]+\.)?(\w+)`", r"`\1`", text)
    return text.replace("``", "`").replace(" (module doc)", "").replace(", see the module doc", "")


def kinds_table() -> str:
    """Markdown table: kind, who builds it, parameters, summary and residual."""
    rows = [
        "| kind | added by | parameters | what it asks | residual (loss = its squared norm) |",
        "|---|---|---|---|---|",
    ]
    for kind, cls in sorted(REGISTRY.items()):
        spec = describe(cls)
        params = [
            f"`{f.name}`" + (f" ({f.unit})" if f.unit else "")
            for f in spec.fields
            if f.name not in COMMON_FIELDS and f.name not in FRAME_FIELDS
        ]
        example = cls.examples(_rest())[0]
        term = type(example).terms([example], FrameInputs())[0]
        who = "the user" if cls.user_facing else "the method"
        cell = lambda s: s.replace("|", "\\|")  # noqa: E731
        rows.append(
            f"| `{kind}` | {who} | {', '.join(params) or 'none'} | {cell(_first_sentence(spec.summary))} | "
            f"{cell(_first_sentence(cls.term.__doc__ or type(term).__doc__))} |"
        )
    return "\n".join(rows) + "\n"


def _rest() -> np.ndarray:
    """World positions ``(22, 3)`` of the canonical rest pose standing on the floor."""
    return sk.Skeleton.canonical().rest_positions() + np.array([0.0, 0.0, 0.95])
