"""The studio saves reconstructions as BVH or glTF by the extension; the save dialog
offers every format and an extension no writer knows is refused before the solve."""

from __future__ import annotations

import pytest

from app.motion_files import MOTION_FILTERS, with_filter_suffix
from tests.stand_ins import RestPoseMethod

pytestmark = pytest.mark.gui


def test_the_dialog_offers_every_format_and_a_bare_name_takes_the_filter_s():
    assert MOTION_FILTERS == "BVH motion (*.bvh);;glTF 2.0 binary (*.glb);;glTF 2.0 JSON (*.gltf)"
    assert with_filter_suffix("/tmp/walk", "glTF 2.0 binary (*.glb)") == "/tmp/walk.glb"
    assert with_filter_suffix("/tmp/walk", "BVH motion (*.bvh)") == "/tmp/walk.bvh"
    assert with_filter_suffix("/tmp/walk.gltf", "BVH motion (*.bvh)") == "/tmp/walk.gltf"


def test_save_reconstruction_writes_a_glb_and_refuses_an_unknown_extension(studio, qtbot, tmp_path, monkeypatch):
    from tests.engine.gltf_reading import read_gltf, validate, validator_command

    studio.files.export.factory = lambda name: RestPoseMethod()
    errors = []
    monkeypatch.setattr(studio.files, "show_error", lambda title, text: errors.append(text))
    studio.files.save_reconstruction(str(tmp_path / "r.fbx"))
    assert not studio.files.export.running and "known: .bvh" in errors[0]
    out = tmp_path / "r.glb"
    studio.files.save_reconstruction(str(out))
    qtbot.waitUntil(lambda: not studio.files.export.running, timeout=20000)
    assert len(errors) == 1
    doc = read_gltf(out).doc
    assert doc.skins and doc.meshes and len(doc.animations[0].channels) > 22
    if validator_command() is not None:
        assert [(r["errors"], r["warnings"]) for r in validate([out])] == [(0, 0)]
