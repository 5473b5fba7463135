"""research/judge_vae.py: the model card's four criteria read from two measure folders."""

from __future__ import annotations

import json

import pytest

from .script_loader import load_script


def _folder(path, pos=1.0, natural=8.0, goal=0.0, outside=False, tests=0):
    path.mkdir()
    jv = load_script("judge_vae")
    for name, presets in (("val", jv.VAL_PRESETS), ("hdm", jv.OTHER_PRESETS), ("dp", jv.OTHER_PRESETS)):
        for p in presets:
            (path / f"{name}_{p}.json").write_text(json.dumps({"total": {"pos_cm": pos, "rot_deg": 10.0}}))
    for e in jv.EVENTS:
        task = {"task": "hand_to_knee", "poser": "pose-mode", "naturalness_cm": natural, "within_spread": not outside}
        task["goal_errors"] = [{"kind": "position", "error": goal}, {"kind": "rotation", "error": 9.0}]
        ik = dict(task, poser="ik", naturalness_cm=99.0)
        (path / f"tasks_e{e}.json").write_text(json.dumps({"tasks": [task, ik]}))
    (path / "authoring_tests.json").write_text(json.dumps({"exit_status": tests}))
    return path


@pytest.mark.parametrize(
    "cand, own, holds",
    [
        ({}, (0.6, 0.5), True),
        ({"pos": 0.97}, None, True),  # better tracking, criterion 1 not given
        ({}, (0.5, 0.6), False),  # own error higher
        ({"pos": 1.04}, None, False),  # 4 % worse tracking
        ({"natural": 8.9}, None, False),  # 11 % farther from real poses
        ({"goal": 0.6}, None, False),  # goal missed by 0.6 cm more
        ({"outside": True}, None, False),
        ({"tests": 1}, None, False),
    ],
)
def test_each_criterion_decides(tmp_path, cand, own, holds):
    jv = load_script("judge_vae")
    base = _folder(tmp_path / "base")
    other = _folder(tmp_path / "cand", **cand)
    assert jv.judge(base, other, own) is holds
