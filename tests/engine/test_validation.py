"""The validation layer (engine/validation.py): schemas, special files, safe JSON, short messages."""

from __future__ import annotations

import os

import pytest

from engine.errors import UserError, shorten_words
from engine.input_files import read_json
from engine.solver.settings import SETTINGS
from engine.validation import (
    CLI,
    Num,
    ValidationError,
    check_fields,
    check_input_file,
    check_output_path,
    check_value,
    one_line,
)


@pytest.mark.parametrize(
    "spec, value, reason",
    [
        (CLI["seed"], -1, "out of range"),
        (CLI["fps"], float("nan"), "not finite"),
        (CLI["fps"], float("inf"), "not finite"),
        (CLI["fps"], 1e-300, "out of range"),
        (CLI["noise_pos"], -1.0, "out of range"),
        (SETTINGS["threads"], 100_000, "out of range"),
        (SETTINGS["past_window"], 1_000_000_000, "out of range"),
        (Num(3, 6, integer=True), 6.5, "not a whole number"),
        (CLI["lr"], 0.0, "out of range"),
        (CLI["lr"], "abc", "not a number"),
        (CLI["lr"], True, "not a number"),
    ],
)
def test_numbers_outside_their_schema_are_one_line_naming_field_and_range(spec, value, reason):
    with pytest.raises(ValidationError) as err:
        check_value(spec, value, "somewhere.json", "field_x")
    text = str(err.value)
    assert "\n" not in text and reason in text
    assert text.startswith("somewhere.json: field_x = ") and "allowed: " in text


def test_values_inside_are_converted():
    assert check_value(Num(3, 6, integer=True), 6.0, "w", "f") == 6
    assert check_fields(SETTINGS, {"threads": 2, "root_anchor": "none"}, "w") == {"threads": 2, "root_anchor": "none"}


def test_integer_ranges_are_printed_as_integers():
    with pytest.raises(ValidationError, match=r"\[0, 4294967295\]"):
        check_value(CLI["seed"], -1, "--seed", "value")


def test_fifo_device_symlink_loop_folder_and_size_are_refused_before_reading(tmp_path):
    fifo = tmp_path / "x.bvh"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.bvh"
    zero.symlink_to("/dev/zero")
    (tmp_path / "a.bvh").symlink_to(tmp_path / "b.bvh")
    (tmp_path / "b.bvh").symlink_to(tmp_path / "a.bvh")
    big = tmp_path / "big.bvh"
    big.write_bytes(b"x" * 101)
    cases = {
        fifo: "not a regular file",
        zero: "not a regular file",
        tmp_path / "a.bvh": "symbolic links",
        tmp_path: "is a folder",
        tmp_path / "none.bvh": "cannot read BVH file: not found",
    }
    for path, reason in cases.items():
        with pytest.raises(ValidationError, match=reason):
            check_input_file(path)  # returns at once: nothing is opened
    with pytest.raises(ValidationError, match="larger than the limit of 100 bytes"):
        check_input_file(big, max_bytes=100)
    assert check_input_file(big) == big


def test_output_paths_are_checked_without_writing(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValidationError, match="is a folder"):
        check_output_path(tmp_path, "--out")
    with pytest.raises(ValidationError, match="not a folder"):
        check_output_path(tmp_path / "file" / "out.bvh", "--out")
    with pytest.raises(ValidationError, match="cannot write in /proc"):
        check_output_path("/proc/out.bvh", "--out")
    assert check_output_path(tmp_path / "new" / "deeper" / "out.bvh") == tmp_path / "new" / "deeper" / "out.bvh"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"], "the check leaves nothing behind"


# deep nesting, 5001-digit numbers and Latin-1 bytes: tests/engine/test_hardening_cli.py (scenes)
@pytest.mark.parametrize(
    "content, reason",
    [
        (b'{"a": NaN}', "NaN is not a JSON number"),
        (b'{"a": 1,}', ":1: invalid JSON"),
        (b"{}" + b" " * 200, "larger than the limit of 100 bytes"),
    ],
)
def test_read_json_turns_every_bad_document_into_one_line(tmp_path, content, reason, monkeypatch):
    from engine import validation

    monkeypatch.setitem(validation.MAX_BYTES, "scene", 100)
    path = tmp_path / "scene.json"
    path.write_bytes(content)
    with pytest.raises(ValidationError) as err:
        read_json(path, "scene")
    assert reason in str(err.value) and "\n" not in str(err.value)


def test_huge_tokens_are_cut_in_every_user_error():
    token = "x" * 5_000_000
    text = str(UserError(f"bad value '{token}' in file.bvh"))
    assert len(text) < 400 and text.endswith("in file.bvh")
    assert shorten_words("short words stay") == "short words stay"
    assert one_line("a\n  b\n") == "a b"
