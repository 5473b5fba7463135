"""Sensor presets: the shipped JSON agrees with the code, and --sensors parsing."""

from __future__ import annotations

import json

import pytest

from engine.errors import UserError
from engine.tracking import presets as P


def test_json_matches_builtin_presets():
    data = json.loads(P.PRESETS_JSON.read_text())
    as_specs = {n: tuple(P.Sensor(e["joint"], dof=e["dof"]) for e in v) for n, v in data.items()}
    assert as_specs == P.BUILTIN_PRESETS
    assert list(data) == list(P.BUILTIN_PRESETS)  # same order (the GUI lists them so)
    assert P.PRESET_SENSORS == P.BUILTIN_PRESETS


def test_issue_presets():
    assert set(P.PRESETS["6"]) == {"root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"}
    assert set(P.PRESETS["5"]) == {"upperneck", "lwrist", "rwrist", "lankle", "rankle"}
    assert set(P.PRESETS["5-paper"]) == {"root", "upperneck", "lwrist", "rwrist", "rankle"}
    assert set(P.PRESETS["4"]) == {"root", "upperneck", "lwrist", "rwrist"}
    assert set(P.PRESETS["3-hip-hands"]) == {"root", "lwrist", "rwrist"}
    assert set(P.PRESETS["3-head-hands"]) == {"upperneck", "lwrist", "rwrist"}
    assert {s.dof for s in P.PRESET_SENSORS["6x3dof"]} == {3}
    assert P.PRESETS["6x3dof"] == P.PRESETS["6"]


def test_parse_custom_lists():
    assert P.parse_sensors("4") == P.PRESET_SENSORS["4"]
    assert P.parse_sensors(" root, lwrist:3 ,rwrist:6") == (
        P.Sensor("root", dof=6),
        P.Sensor("lwrist", dof=3),
        P.Sensor("rwrist", dof=6),
    )


@pytest.mark.parametrize("bad", ["foo", "root,hand", "", "lwrist:4", "lwrist:x", "root,root"])
def test_parse_errors_name_the_problem(bad):
    with pytest.raises(UserError) as exc:
        P.parse_sensors(bad)
    msg = str(exc.value)
    if bad in ("foo", "root,hand", ""):
        assert "3-head-hands" in msg and "upperneck" in msg  # lists presets and joints


def test_malformed_json_names_file(tmp_path):
    bad = tmp_path / "s.json"
    bad.write_text('{"x": [{"joint": "nose"}]}')
    with pytest.raises(UserError, match="s.json.*'x'"):
        P.load_presets(bad)
    bad.write_text("{")
    with pytest.raises(UserError, match="s.json"):
        P.load_presets(bad)
