"""Numbers in a BVH file are ASCII decimals: every plain spelling loads, and a frame count
in other digits (which Python's ``int`` and ``str.isdigit`` treat unevenly) ends in one
line naming the file and line in every command that reads BVH. The parser's cases are in
``test_bvh.BAD_CASES``."""

from __future__ import annotations

from pathlib import Path

import pytest

from engine.cli.main import main
from engine.motion.bvh import load_bvh
from tests.engine.test_bvh import edited, write

REPO = Path(__file__).resolve().parents[2]
EX = REPO / "assets" / "clips" / "example.bvh"
SUPERSCRIPT_TWO = "\u00b2"  # str.isdigit() says yes, int() refuses
ARABIC_INDIC = "\u0665\u0665\u0667"  # int() reads 557


def test_plain_decimals_in_every_spelling_still_load(tmp_path):
    """Signs, exponents and a missing leading or trailing digit are BVH numbers."""
    row = "+0.0 1. .5e1 1E1 2e+1 3.0e-1 -5.0 5 45.0 1.0 2.0 3.0"
    text = edited({8: "\t\tOFFSET -0.0 +0.1 1e-1", 23: "Frame Time: 3.33333E-2", 24: row})
    raw = load_bvh(write(tmp_path, text))
    assert raw.file_frames == 3 and raw.rotations_deg.shape[0] == 3
    assert raw.frame_time == pytest.approx(1 / 30, rel=1e-5)


def run(argv: list[str], capsys) -> tuple[int, str]:
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:
        rc = exc.code
    return rc, capsys.readouterr().err


@pytest.mark.parametrize("digits", [SUPERSCRIPT_TWO, ARABIC_INDIC])
def test_every_command_gives_one_line_for_a_unicode_frame_count(tmp_path, capsys, digits):
    lines = EX.read_text().splitlines()
    frames = next(i for i, s in enumerate(lines) if s.startswith("Frames:"))
    lines[frames] = f"Frames: {digits}"
    clip = tmp_path / "digits.bvh"
    clip.write_text("\n".join(lines) + "\n", encoding="utf-8")
    for argv in (["info", clip], ["reconstruct", clip, "--out", tmp_path / "o.bvh"], ["evaluate", clip]):
        rc, err = run(argv, capsys)
        shown = [s for s in err.splitlines() if s.strip()]
        assert rc == 2, (argv[0], err[-800:])
        assert len(shown) == 1 and "Traceback" not in err, (argv[0], err[-800:])
        assert f"digits.bvh:{frames + 1}:" in shown[0] and "Frames" in shown[0], shown[0]
    assert not (tmp_path / "o.bvh").exists()
