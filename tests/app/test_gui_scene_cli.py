"""``gui FILE --scene SCENE.json`` (with --measure and --screenshot), and
``--after-frames N`` playing exactly N frames."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.gui


def _gui(tmp_path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "XDG_CONFIG_HOME": str(tmp_path / "config"), "OMP_NUM_THREADS": "1"}
    env.pop("QT_QPA_PLATFORM", None)  # the real window on the test's X display
    cmd = [sys.executable, "-m", "engine.cli.main", "gui", *args]
    return subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)


@pytest.fixture
def scene_file(tmp_path, synthetic_motion):
    from engine.motion.bvh import save_motion_bvh
    from engine.studio.session import Session

    clip = tmp_path / "walk.bvh"
    save_motion_bvh(clip, synthetic_motion.slice(0, 60))
    session = Session(method="ik")
    session.constraints.add("look_at", name="look")
    session.constraints.add("distance", name="hands", distance=0.3)
    scene = session.to_scene()
    scene["frame"] = 5
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return clip, path


def test_measure_with_a_scene_reports_its_constraints(tmp_path, scene_file):
    clip, scene = scene_file
    out = tmp_path / "m.json"
    done = _gui(tmp_path, str(clip), "--method", "ik", "--scene", str(scene), "--measure", "2", "--json", str(out))
    assert done.returncode == 0, done.stderr[-2000:]
    figures = json.loads(out.read_text())
    assert figures["constraints"] == ["look (look_at)", "hands (distance)"]
    assert figures["draws_per_s"] > 0 and figures["solved_per_s"] > 0


def test_screenshot_with_a_scene_plays_exactly_the_frames_asked(tmp_path, scene_file):
    clip, scene = scene_file
    out = tmp_path / "shot.png"
    scene_out = tmp_path / "after.json"
    code = (
        "import sys; from engine.cli.main import main; import app.main as m; orig = m.MainWindow.close\n"
        "def close(self):\n"
        f"    open({str(scene_out)!r}, 'w').write(str(self.session.latest.frame) + ' ' + str(self.session.latest.solved))\n"
        "    return orig(self)\n"
        "m.MainWindow.close = close\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    env = {**os.environ, "XDG_CONFIG_HOME": str(tmp_path / "config"), "OMP_NUM_THREADS": "1"}
    env.pop("QT_QPA_PLATFORM", None)
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            code,
            "gui",
            str(clip),
            "--method",
            "ik",
            "--scene",
            str(scene),
            "--screenshot",
            str(out),
            "--after-frames",
            "1",
        ],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert out.is_file()
    frame, _ = scene_out.read_text().split()
    assert int(frame) == 6, "one frame played from the scene's frame 5"


def test_a_bad_scene_is_one_line_naming_the_file_and_exit_2(tmp_path, scene_file):
    clip, _ = scene_file
    bad = tmp_path / "bad.json"
    bad.write_text('{"constraints": [{"kind": "nope"}]}')
    done = _gui(tmp_path, str(clip), "--method", "ik", "--scene", str(bad), "--screenshot", str(tmp_path / "x.png"))
    assert done.returncode == 2, done.stderr[-2000:]
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "bad.json" in lines[0], done.stderr
