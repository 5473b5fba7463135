"""Fixtures of the authoring tests: the shipped pose VAE and the issue's example scene."""

from __future__ import annotations

import json

import pytest
import torch

#: The example of the authoring issue and docs/authoring.md, exactly as written there.
EXAMPLE = """{"format": "dragposer-scene", "version": 2,
 "animation": {"fps": 30, "frames": 61},
 "keys": [{"frame": 0, "targets": {"lwrist": [0.25, -0.35, 1.10]}},
          {"frame": 60, "targets": {"lwrist": [0.45, -0.10, 1.75]}}],
 "constraints": [{"kind": "floor", "name": "floor", "weight": 1.0, "enabled": true}]}
"""


@pytest.fixture(scope="session")
def vae():
    from engine.models import load_default_models

    torch.set_num_threads(1)
    return load_default_models().vae


@pytest.fixture
def example_scene(tmp_path):
    path = tmp_path / "example.json"
    path.write_text(EXAMPLE)
    assert json.loads(EXAMPLE)["version"] == 2
    return path
