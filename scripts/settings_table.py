"""Rewrite the settings table of docs/optimizer.md from the settings' own metadata.

    PYTHONPATH=. python scripts/settings_table.py

The table sits between two HTML comments; ``tests/engine/test_settings_schema.py``
fails while it differs from :func:`engine.solver.settings.markdown_table`.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from engine.atomic import write_text  # noqa: E402
from engine.solver.settings import markdown_table  # noqa: E402

DOC = ROOT / "docs" / "optimizer.md"
BEGIN, END = "<!-- settings table: generated -->\n", "<!-- end of settings table -->"


def main() -> int:
    text = DOC.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        print(f"{DOC}: the markers {BEGIN.strip()} and {END} are missing", file=sys.stderr)
        return 2
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    write_text(DOC, head + BEGIN + markdown_table() + END + tail)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
