"""``reconstruct`` command with a stand-in DragPoser (the shipped models are not needed)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.cli.main import main
from engine.methods import _FACTORIES, register_method
from engine.methods.dragposer import DragPoserMethod
from engine.motion.bvh import save_motion_bvh
from engine.motion.retarget import load_motion
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder


@pytest.fixture
def standin_dragposer():
    created = []

    def factory(mode="realtime", iterations=None, lr=None, **kw):
        values = {"mode": mode, **kw}
        if iterations is not None:
            values["iterations" if mode == "realtime" else "max_iterations"] = iterations
        if lr is not None:
            values["lr"] = lr
        created.append(DragPoserMethod(MLPDecoder(), CountingPredictor(), **values))
        return created[-1]

    old = _FACTORIES.get("dragposer")
    register_method("dragposer", factory)
    yield created
    if old is not None:
        register_method("dragposer", old)


@pytest.fixture
def clip_path(synthetic_motion, tmp_path):
    path = tmp_path / "walk.bvh"
    save_motion_bvh(path, synthetic_motion)
    return path


def test_reconstruct_writes_a_bvh_and_a_summary(standin_dragposer, clip_path, tmp_path, capsys):
    out = tmp_path / "out.bvh"
    code = main(
        [
            "reconstruct",
            str(clip_path),
            "--out",
            str(out),
            "--sensors",
            "6",
            "--iterations",
            "2",
            "--max-frames",
            "12",
            "--faulty",
            "0.05",
            "--no-progress",
        ]
    )
    assert code == 0
    rec = load_motion(out)
    assert len(rec) == 12 and np.isfinite(rec.root_pos).all()
    text = capsys.readouterr().out
    assert "frames 12" in text and "ms/frame" in text and "iterations mean" in text
    assert standin_dragposer[0].settings.iterations == 2


def test_scene_adds_constraints_and_settings_but_flags_win(standin_dragposer, clip_path, tmp_path):
    scene = tmp_path / "scene.json"
    scene.write_text(
        json.dumps(
            {
                "settings": {"mode": "offline", "max_iterations": 7, "lr": 0.02},
                "constraints": [{"kind": "look_at", "name": "look", "target": [0, -3, 1.6]}],
            }
        )
    )
    out = tmp_path / "out.bvh"
    assert (
        main(
            [
                "reconstruct",
                str(clip_path),
                "--out",
                str(out),
                "--scene",
                str(scene),
                "--lr",
                "0.03",
                "--max-frames",
                "5",
                "--no-progress",
            ]
        )
        == 0
    )
    m = standin_dragposer[0]
    assert m.settings.mode == "offline" and m.settings.max_iterations == 7 and m.settings.lr == 0.03
    assert m.get_constraint("look").kind == "look_at"


def test_scene_constraints_for_a_method_without_constraints_are_a_user_error(clip_path, tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"constraints": [{"kind": "look_at", "name": "look", "target": [0, -3, 1.6]}]}))
    out = tmp_path / "out.bvh"
    assert (
        main(
            [
                "reconstruct",
                str(clip_path),
                "--out",
                str(out),
                "--scene",
                str(scene),
                "--method",
                "ik",
                "--max-frames",
                "5",
                "--no-progress",
            ]
        )
        == 2
    )
    assert "'ik' takes no constraints" in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--sensors", "tail"], "tail"),
        (["--faulty", "2"], "faulty"),
        (["--iterations", "0"], "iterations"),
        (["--set", "optimizer=lbfgs"], "optimizer"),
    ],
)
def test_bad_options_are_user_errors(standin_dragposer, clip_path, tmp_path, capsys, flags, message):
    assert main(["reconstruct", str(clip_path), "--out", str(tmp_path / "o.bvh"), *flags]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o.bvh").exists()


def test_bad_scene_names_the_file(standin_dragposer, clip_path, tmp_path, capsys):
    scene = tmp_path / "bad.json"
    scene.write_text('{"constraints": [{"kind": "pin", "joint": "tail"}]}')
    assert main(["reconstruct", str(clip_path), "--out", str(tmp_path / "o.bvh"), "--scene", str(scene)]) == 2
    err = capsys.readouterr().err
    assert "bad.json" in err and "joint" in err


def test_set_flags_reach_the_optimizer(standin_dragposer, clip_path, tmp_path):
    out = tmp_path / "o.bvh"
    argv = [
        "reconstruct",
        str(clip_path),
        "--out",
        str(out),
        "--max-frames",
        "6",
        "--no-progress",
        "--set",
        "optimizer=adam-carry",
        "--set",
        "root_anchor=none",
    ]
    assert main(argv) == 0 and out.is_file()
    s = standin_dragposer[0].settings
    assert (s.optimizer, s.root_anchor) == ("adam-carry", "none")
