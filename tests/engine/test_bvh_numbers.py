"""Numbers in a BVH file are ASCII decimals: other scripts' digits, superscripts and
underscores, which Python's ``int``/``float``/``str.isdigit`` treat unevenly, end in one
error naming the line, through the parser and through every command that reads BVH."""

from __future__ import annotations

from pathlib import Path

import pytest

from engine.bvh import load_bvh
from engine.cli.main import main
from engine.errors import BVHError

from tests.engine.test_bvh import LINES, edited, write

REPO = Path(__file__).resolve().parents[2]
EX = REPO / "assets" / "clips" / "example.bvh"
SUPERSCRIPT_TWO = "\u00b2"  # str.isdigit() says yes, int() refuses
ARABIC_INDIC = "\u0663\u0664"  # int() and float() read 34
FULLWIDTH = "\uff13"  # float() reads 3

CASES = {
    # name: (edited text, line the error must name, words the message must contain)
    "superscript Frames": (edited({22: f"Frames: {SUPERSCRIPT_TWO}"}), 22, "whole number"),
    "Arabic-Indic Frames": (edited({22: "Frames: \u0663"}), 22, "whole number"),
    "circled Frames": (edited({22: "Frames: \u2462"}), 22, "whole number"),
    "underscore Frames": (edited({22: "Frames: 0_3"}), 22, "whole number"),
    "Arabic-Indic Frame Time": (edited({23: "Frame Time: 0.0\u0663"}), 23, "not a number"),
    "underscore Frame Time": (edited({23: "Frame Time: 0.0_3"}), 23, "not a number"),
    "Arabic-Indic OFFSET": (edited({8: f"\t\tOFFSET 0.0 {ARABIC_INDIC} 0.0"}), 8, "not a number"),
    "fullwidth OFFSET": (edited({8: f"\t\tOFFSET {FULLWIDTH} 0.1 0.0"}), 8, "not a number"),
    "underscore OFFSET": (edited({8: "\t\tOFFSET 0.0 0.1 1_0"}), 8, "'1_0' is not a number"),
    "Arabic-Indic in a row": (edited({25: LINES[24].replace("6.0", ARABIC_INDIC)}), 25, "is not a number"),
    "superscript in a row": (edited({24: LINES[23].replace("5.0", f"5{SUPERSCRIPT_TWO}")}), 24, "is not a number"),
    "underscore in a row": (edited({26: LINES[25].replace("47.0", "4_7.0")}), 26, "'4_7.0' is not a number"),
    "no-break space in a row": (edited({24: LINES[23].replace(" 1.0 ", "\u00a01.0 ", 1)}), 24, "U+00A0"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_non_ascii_numbers_name_the_line(tmp_path, case):
    text, line, words = CASES[case]
    path = write(tmp_path, text)
    with pytest.raises(BVHError) as err:
        load_bvh(path)
    assert err.value.line == line, str(err.value)
    assert words in err.value.message, err.value.message
    assert str(err.value).startswith(f"{path}:{line}: ")


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


@pytest.mark.parametrize("digits", [SUPERSCRIPT_TWO, "\u0665\u0665\u0667"])
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
