"""Rewrite the generated tables of docs/optimizer.md: the settings (from the settings'
own metadata) and the constraint kinds (from the registry).

    PYTHONPATH=. python scripts/settings_table.py

Each table sits between two HTML comments; ``tests/engine/test_settings_schema.py`` and
``tests/engine/test_terms.py`` fail while they differ from
:func:`engine.solver.settings.markdown_table` and
:func:`engine.studio.kinds_table.kinds_table`.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from engine.atomic import write_text  # noqa: E402
from engine.solver.settings import markdown_table  # noqa: E402
from engine.studio import kinds_table as K  # noqa: E402

DOC = ROOT / "docs" / "optimizer.md"
BEGIN, END = "<!-- settings table: generated -->\n", "<!-- end of settings table -->"


def main() -> int:
    text = DOC.read_text(encoding="utf-8")
    for begin, end, table in ((BEGIN, END, markdown_table()), (K.BEGIN, K.END, K.kinds_table())):
        if begin not in text or end not in text:
            print(f"{DOC}: the markers {begin.strip()} and {end} are missing", file=sys.stderr)
            return 2
        head, rest = text.split(begin, 1)
        text = head + begin + table + end + rest.split(end, 1)[1]
    write_text(DOC, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
