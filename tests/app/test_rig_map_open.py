"""The studio's Open dialog with a rig it cannot map: pick a mapping file (``--rig-map``),
or have one suggested; the mapping is remembered for the file and used on saving onto
its rig. A real window; the dialogs are answered through FileActions' hooks."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.engine.rig_fixtures import write_family_bvh

pytestmark = pytest.mark.gui


def _renamed(tmp_path: Path) -> tuple[Path, Path]:
    """A LAFAN1-style clip whose joints are renamed ``bone_NN`` (no automatic mapping can
    read that), and the mapping file that fixes it (``rig suggest`` on the original, renamed)."""
    from engine.cli.rig import write_suggestion
    from engine.motion.bvh import load_bvh

    orig = write_family_bvh(tmp_path / "orig.bvh", "lafan", frames=90)
    good = tmp_path / "orig.toml"
    assert write_suggestion(orig, good)
    names = sorted(load_bvh(orig).names, key=len, reverse=True)
    table = {n: f"bone_{i:02d}" for i, n in enumerate(names)}
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\b")
    bvh, rig_map = tmp_path / "odd.bvh", tmp_path / "odd.toml"
    bvh.write_text(pattern.sub(lambda m: table[m.group(1)], orig.read_text()))
    rig_map.write_text(pattern.sub(lambda m: table[m.group(1)], good.read_text()))
    return bvh, rig_map


def _never(*args):
    raise AssertionError(f"unexpected dialog: {args[1:]}")


def test_unmapped_file_opens_with_a_picked_mapping_which_is_remembered(studio, tmp_path):
    bvh, rig_map = _renamed(tmp_path)
    before = studio.session.motion
    asked = []
    studio.files.ask_unmapped = lambda w, path, msg: (asked.append(msg), "pick")[1]
    studio.files.pick_rig_map = lambda w, start: str(rig_map)
    assert studio.files.open_path(bvh)
    assert "bone_00" in asked[0] and "rig suggest" in asked[0]  # the error lists the file's joints
    assert studio.session.path == bvh and studio.session.motion is not before
    assert studio.files.rig_map_of(bvh) == rig_map.resolve()
    assert "odd.toml" in studio.statusBar().currentMessage()
    # reopening (recent files, drag and drop) needs no question any more
    studio.files.ask_unmapped = studio.files.pick_rig_map = _never
    studio.session.set_motion(before)
    assert studio.files.open_path(bvh) and studio.session.path == bvh


def test_cancel_or_bad_mapping_keeps_the_current_clip(studio, tmp_path):
    bvh, rig_map = _renamed(tmp_path)
    before = studio.session.motion
    studio.files.ask_unmapped = lambda *a: ""
    studio.files.pick_rig_map = _never
    assert not studio.files.open_path(bvh)
    assert studio.session.motion is before
    # a mapping that names a joint the file lacks: asked again, with the mapping's error
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(rig_map.read_text().replace('"bone_', '"nope_', 1))
    answers, asked = iter(["pick", ""]), []
    studio.files.ask_unmapped = lambda w, path, msg: (asked.append(msg), next(answers))[1]
    studio.files.pick_rig_map = lambda w, start: str(wrong)
    assert not studio.files.open_path(bvh)
    assert len(asked) == 2 and "wrong.toml" in asked[1] and "nope_" in asked[1]
    assert studio.session.motion is before and studio.files.rig_map_of(bvh) is None


def test_suggest_writes_a_template_beside_the_file_and_says_where(studio, tmp_path):
    bvh, _ = _renamed(tmp_path)
    told = []
    studio.files.ask_unmapped = lambda *a: "suggest"
    studio.files.tell = lambda w, title, msg: told.append(msg)
    assert not studio.files.open_path(bvh)
    out = tmp_path / "odd.rigmap.toml"
    assert out.is_file() and str(out) in told[0] and str(out) in studio.statusBar().currentMessage()
    text = out.read_text()
    assert "[joints]" in text and "bone_00" in text and "# lknee" in text  # to fill in
    # a second suggestion never overwrites the first (the user may be editing it)
    assert not studio.files.open_path(bvh)
    assert (tmp_path / "odd.rigmap-2.toml").is_file() and out.read_text() == text


def test_save_onto_the_source_rig_uses_the_files_mapping(studio, qtbot, tmp_path):
    from engine.motion.bvh import load_bvh

    bvh, rig_map = _renamed(tmp_path)
    assert studio.files.open_path(bvh, rig_map)
    out = tmp_path / "back.bvh"
    studio.files.save_on_source_rig(str(out))
    qtbot.waitUntil(lambda: not studio.files.export.running, timeout=60000)
    assert "Saved" in studio.statusBar().currentMessage()
    back = load_bvh(out)
    assert back.names == load_bvh(bvh).names and back.frames == studio.session.num_frames
