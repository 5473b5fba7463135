"""The presets a method declares it needs are the ones its first frame checks."""

from __future__ import annotations

import pytest

from engine.methods.presets import REQUIRED_PRESET, preset_problem
from engine.tracking import PRESET_SENSORS


@pytest.mark.parametrize(
    "method, module, joints",
    [("sparseposer", "engine.models.sparseposer", "SPARSE_JOINTS"), ("rpm", "engine.models.rpm", "RPM_JOINTS")],
)
def test_the_required_preset_holds_exactly_the_joints_the_method_checks(method, module, joints):
    import importlib

    want = getattr(importlib.import_module(module), joints)
    assert sorted((s.joint, s.dof) for s in PRESET_SENSORS[REQUIRED_PRESET[method]]) == sorted((j, 6) for j in want)


def test_preset_problem_names_the_preset_needed():
    assert preset_problem("rpm", "3-head-hands") is None and preset_problem("ik", "4") is None
    assert preset_problem("sparseposer", "6") is None
    assert "'3-head-hands'" in preset_problem("rpm", "6") and "'6'" in preset_problem("sparseposer", "6x3dof")
    assert "none" in preset_problem("ik", None)


def test_sensors_problem_reads_the_enabled_joints_and_their_dof_whatever_the_preset():
    import dataclasses

    from engine.methods.presets import sensors_problem

    six = PRESET_SENSORS["6"]
    assert sensors_problem("ik", six) is None and sensors_problem("sparseposer", six) is None
    assert "'3-head-hands'" in sensors_problem("rpm", six)
    # the six with hips and feet switched off are RPM's three trackers
    off = tuple(dataclasses.replace(s, enabled=s.joint in ("upperneck", "lwrist", "rwrist")) for s in six)
    assert sensors_problem("rpm", off) is None
    assert "'6'" in sensors_problem("sparseposer", PRESET_SENSORS["6x3dof"])
