"""``python -m app [OPTIONS]``: the studio, the same as ``dragposer-studio gui [OPTIONS]``."""

from __future__ import annotations

import sys

from engine.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["gui", *sys.argv[1:]]))
