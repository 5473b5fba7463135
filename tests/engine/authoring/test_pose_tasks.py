"""The pose-mode benchmark: its measures on constructed poses, the IK poser, the options
hook, and one task end to end (engine/authoring/pose_tasks.py, pose_metrics.py,
pose_reference.py, ik_poser.py; ``bench --pose-tasks``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring import pose_metrics as M
from engine.authoring import pose_reference as R
from engine.authoring import pose_tasks as T
from engine.authoring.character import Pose, yaw_quaternion
from engine.authoring.ik_poser import IKPoser
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.motion.retarget_frames import CANON_HINGE
from tests.conftest import MOCAP

J = sk.JOINT_INDEX
OFFSETS = sk.REST_OFFSETS
STAND = M.standing_heights(OFFSETS)[0]  # root height of the rest pose standing on the floor


def t_pose() -> np.ndarray:
    return np.tile([1.0, 0.0, 0.0, 0.0], (sk.NUM_JOINTS, 1))


def about(axis, deg: float) -> np.ndarray:
    axis = np.asarray(axis, float)
    return QN.from_axis_angle(axis / np.linalg.norm(axis), np.radians(deg))


def standing(local: np.ndarray) -> np.ndarray:
    return np.array([0.0, 0.0, STAND])


# -- per-pose measures ----------------------------------------------------------------


def test_a_t_pose_standing_is_balanced_upright_and_within_every_limit():
    c = M.check_pose(t_pose(), standing(t_pose()), OFFSETS)
    assert c.violations == [] and min(c.flexion_deg.values()) > -1.0
    assert c.feet_down == {"left": True, "right": True}
    assert c.balanced and 3.0 < c.balance_margin_cm < 10.0  # the CoM between heel and toes
    assert c.trunk_tilt_deg < 1.5
    assert c.com[2] == pytest.approx(1.07, abs=0.05)  # about 57 % of the 1.87-m height


@pytest.mark.parametrize(
    "limb, upper, end",
    [
        ("lknee", "lhip", "lankle"),
        ("rknee", "rhip", "rankle"),
        ("lelbow", "lshoulder", "lwrist"),
        ("relbow", "rshoulder", "rwrist"),
    ],
)
def test_a_knee_or_elbow_bent_backwards_is_flagged_and_bent_forwards_is_not(limb, upper, end):
    rest = M.flexion_deg(t_pose(), OFFSETS)[limb]
    for deg, flagged in ((-30.0, True), (-5.0, False), (60.0, False)):
        local = t_pose()
        local[J[limb]] = about(CANON_HINGE[upper], deg - rest)  # straight, then bent by deg
        flex = M.flexion_deg(local, OFFSETS)[limb]
        assert flex == pytest.approx(deg, abs=3.0)
        assert bool(M.hyperextensions({limb: flex})) is flagged
    # the measure follows the limb: the whole leg or arm turned keeps its flexion
    local[J[upper]] = about([0.3, 1.0, 0.2], 70.0)
    assert M.flexion_deg(local, OFFSETS)[limb] == pytest.approx(flex, abs=1e-6)


def test_a_trunk_bent_forward_tilts_and_legs_swung_aside_leave_the_com_outside_the_feet():
    local = t_pose()
    local[J["lowerback"]] = about([1.0, 0.0, 0.0], 90.0)  # +X axis: the top of the spine goes to -Y (forward)
    positions = fk(local, standing(local), OFFSETS)[0]
    assert positions[J["upperneck"], 1] < -0.3  # bent forward, not back
    bent = M.check_pose(local, standing(local), OFFSETS)
    assert bent.trunk_tilt_deg > 70.0 and bent.com[1] < -0.1  # the pelvis-to-head line; the bend is above the pelvis
    local = t_pose()  # both legs swung 15 deg to the left, feet kept flat: the body's weight is right of them
    for hip, ankle in (("lhip", "lankle"), ("rhip", "rankle")):
        local[J[hip]], local[J[ankle]] = about([0.0, 1.0, 0.0], -15.0), about([0.0, 1.0, 0.0], 15.0)
    c = M.check_pose(local, standing(local), OFFSETS)
    assert c.feet_down == {"left": True, "right": True} and c.trunk_tilt_deg < 1.5
    assert c.balanced is False and c.balance_margin_cm < -3.0


def test_feet_off_the_floor_have_no_balance_and_a_lifted_foot_is_not_down():
    c = M.check_pose(t_pose(), standing(t_pose()) + [0.0, 0.0, 0.1], OFFSETS)
    assert c.feet_down == {"left": False, "right": False} and c.balance_margin_cm is None and c.balanced is None
    local = t_pose()
    local[J["lhip"]] = about([1.0, 0.0, 0.0], -40.0)  # left leg raised forwards
    assert M.check_pose(local, standing(local), OFFSETS).feet_down == {"left": False, "right": True}


def test_polygon_margin_is_signed_distance_to_the_edge():
    hull = M.convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]]))
    assert len(hull) == 4
    assert M.polygon_margin(np.array([0.5, 0.5]), hull) == pytest.approx(0.5)
    assert M.polygon_margin(np.array([0.9, 0.5]), hull) == pytest.approx(0.1)
    assert M.polygon_margin(np.array([2.0, 0.5]), hull) == pytest.approx(-1.0)
    assert M.polygon_margin(np.array([0.5, 0.0]), M.convex_hull(np.array([[0, 0], [1, 0]]))) == pytest.approx(0.0)


# -- naturalness ----------------------------------------------------------------------


def wobble(n: int, seed: int, amp: float = 0.3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    aa = rng.normal(0.0, amp, (n, sk.NUM_JOINTS, 3))
    angle = np.linalg.norm(aa, axis=-1)
    return QN.from_axis_angle(aa / angle[..., None], angle)


def test_a_reference_pose_is_0_from_the_set_wherever_it_stands_and_faces():
    clip = wobble(8, 1)
    ref = R.ReferenceSet.from_rotations([("a", clip), ("b", wobble(8, 2))], OFFSETS, stride=1)
    assert len(ref) == 32  # 2 clips x 8 frames x (pose + mirror image)
    local = clip[5].copy()
    local[0] = QN.mul(yaw_quaternion(70.0), local[0])  # turned about the vertical and moved
    positions = fk(local, np.array([1.5, -2.0, 0.9]), OFFSETS)[0]
    assert ref.nearest(positions) == pytest.approx(0.0, abs=1e-6)
    mirrored = QN.mirror_x(clip[3][list(sk.MIRROR_INDEX)])  # its left/right mirror image is in the set
    assert ref.nearest(fk(mirrored, np.zeros(3), OFFSETS)[0]) == pytest.approx(0.0, abs=1e-6)
    assert ref.nearest(fk(wobble(1, 9)[0], np.zeros(3), OFFSETS)[0]) > 0.02


def test_the_spread_is_each_pose_to_the_nearest_pose_of_another_take():
    a, b = wobble(3, 3, 0.1), wobble(3, 4, 0.6)
    ref = R.ReferenceSet.from_rotations([("a", np.concatenate([a, a])), ("b", b)], OFFSETS, stride=1, mirror=False)
    spread = ref.spread()
    d = R.pose_distances(ref.poses[:6], ref.poses[6:])
    assert spread[:6] == pytest.approx(d.min(1), rel=1e-6)  # not 0: a's own duplicates do not count
    assert spread[6:] == pytest.approx(d.min(0), rel=1e-6)
    assert (spread > 0.01).all()
    assert ref.spread_summary()["p95_cm"] >= ref.spread_summary()["median_cm"] > 1.0


def test_a_sampled_spread_is_the_spread_of_every_kth_pose():
    a, b, c = wobble(40, 5, 0.2), wobble(40, 6, 0.4), wobble(40, 7, 0.3)
    ref = R.ReferenceSet.from_rotations([("a", a), ("b", b), ("c", c)], OFFSETS, stride=1, mirror=False)
    full = ref.spread()
    sampled = ref.spread(sample=25)  # 120 poses: every 5th
    assert len(sampled) == 24 and sampled == pytest.approx(full[::5], rel=1e-6)
    assert ref.spread(sample=500) is full  # no fewer poses than asked: the whole (kept) spread
    s = ref.spread_summary(sample=25)
    assert s["median_cm"] == pytest.approx(100 * np.median(full[::5]))


def test_reference_files_keep_to_a_pose_count_and_can_be_cancelled(tmp_path):
    from engine.motion.bvh import save_motion_bvh
    from engine.motion.clip import Motion
    from engine.progress import Cancelled

    files = []
    for seed, n in ((3, 60), (4, 100)):
        path = tmp_path / f"take{seed}.bvh"
        root = np.tile([0.0, 0.0, STAND], (n, 1))
        save_motion_bvh(path, Motion(wobble(n, seed, 0.2), root, sk.Skeleton.canonical(), 60.0, path.stem))
        files.append(path)
    assert len(R.load_files(files, OFFSETS, stride=4, kind="files")) == 2 * (15 + 25)
    capped = R.load_files(files, OFFSETS, stride=4, kind="files", max_poses=30)
    # the smallest stride from 4 whose poses, mirrored, number 30 or fewer: 12 (5 + 9 frames)
    assert len(capped) == 28 and "every 12th frame" in capped.description
    calls = []
    with pytest.raises(Cancelled):
        R.load_files(files, OFFSETS, cancelled=lambda: calls.append(1) or len(calls) > 1)
    assert len(calls) == 2  # asked before each file: the second file was never read


def test_the_closest_reference_pose_names_its_take():
    a, b = wobble(6, 1), wobble(6, 2)
    ref = R.ReferenceSet.from_rotations([("a.bvh", a), ("b.bvh", b)], OFFSETS, stride=1)
    for clip, name in ((a, "a.bvh"), (b, "b.bvh")):
        d, take = ref.closest(fk(clip[3], np.array([0.4, 0.1, 0.9]), OFFSETS)[0])
        assert take == name and d == pytest.approx(0.0, abs=1e-6)
    d, take = ref.closest(fk(wobble(1, 9)[0], np.zeros(3), OFFSETS)[0])
    assert d == pytest.approx(ref.nearest(fk(wobble(1, 9)[0], np.zeros(3), OFFSETS)[0])) and d > 0.02


needs_data = pytest.mark.skipif(
    not (MOCAP / R.VALIDATION_FILES[0]).is_file(),
    reason=f"needs the validation files in {MOCAP} (set DRAGPOSER_SHARED_DATA)",
)


@needs_data
def test_real_knees_and_elbows_are_never_flagged_and_a_validation_pose_is_0_from_the_set():
    from engine.motion.retarget import load_motion

    paths = [MOCAP / f for f in R.VALIDATION_FILES[2:5]]
    ref = R.load_files(paths, OFFSETS, stride=8)
    motion = load_motion(paths[1])
    flex = np.array([list(M.flexion_deg(q, OFFSETS).values()) for q in motion.local_rot[::8]])
    assert flex.min() > -M.HYPEREXTENSION_DEG / 2 and flex.max() > 60.0  # bent, and only forwards
    frame = 8 * 7
    positions = fk(motion.local_rot[frame], motion.root_pos[frame], OFFSETS)[0]
    assert ref.nearest(positions) == pytest.approx(0.0, abs=1e-6)


def test_the_shipped_reference_poses_are_every_4th_frame_of_the_validation_files():
    ref = R.load_shipped(OFFSETS)
    assert len(ref.names) == 9 and "shipped" in ref.description
    assert len(ref) == 2 * 1611  # each pose and its mirror image
    coarse = R.load_shipped(OFFSETS, stride=16)
    assert 0.24 * len(ref) < len(coarse) < 0.26 * len(ref)
    assert np.isin(coarse.poses[:5].reshape(5, -1), ref.poses.reshape(len(ref), -1)).all()


@needs_data
def test_the_shipped_reference_poses_match_the_files_they_were_built_from():
    """Built by scripts/build_pose_reference.py: the same set load_files makes of the
    files, to float32 precision (regenerate the asset when this fails)."""
    shipped = R.load_shipped(OFFSETS)
    files = R.load_files(R.validation_files(MOCAP), OFFSETS)
    assert shipped.poses.shape == files.poses.shape
    np.testing.assert_allclose(shipped.poses, files.poses, atol=1e-5)
    np.testing.assert_array_equal(shipped.takes, files.takes)


def test_a_stride_the_shipped_poses_cannot_give_and_a_broken_file_are_refused(tmp_path):
    with pytest.raises(UserError, match="--reference-stride must be a multiple of 4"):
        R.load_shipped(OFFSETS, stride=6)
    bad = tmp_path / "poses.npz"
    np.savez(bad, local_rot=np.zeros((2, 22, 4)))
    with pytest.raises(UserError, match=f"{bad}: not a reference pose file \\(no field 'take'\\)"):
        R.load_shipped(OFFSETS, path=bad)
    with pytest.raises(UserError, match="validation file\\(s\\) not found"):
        R.validation_files(tmp_path)


# -- the IK poser and the options hook -----------------------------------------------


def start_pose() -> Pose:
    local = t_pose()
    for arm, s in (("lshoulder", -1), ("rshoulder", 1)):  # arms down the sides, elbows a little bent
        local[J[arm]] = about([0.0, 1.0, 0.0], s * 70.0)
    for knee in ("lknee", "rknee"):
        local[J[knee]] = about([1.0, 0.0, 0.0], 10.0)
    root = standing(local)
    return Pose(np.zeros(4, np.float32), local, root, fk(local, root, OFFSETS)[0])


def bones(p: np.ndarray) -> np.ndarray:
    return np.linalg.norm(p[1:] - p[list(sk.PARENTS[1:])], axis=-1)


def test_the_ik_poser_squats_with_the_feet_held_and_reaches_with_the_spine():
    start = start_pose()
    ik = IKPoser(start, OFFSETS)
    ik.set_target("root", start.root_pos - [0.0, 0.0, 0.3])
    p = ik.solve()
    assert p.root_pos[2] == pytest.approx(start.root_pos[2] - 0.3)
    for ankle in ("lankle", "rankle"):
        assert np.linalg.norm(p.positions[J[ankle]] - start.positions[J[ankle]]) < 1e-9
    assert all(f > 30.0 for j, f in M.flexion_deg(p.local_rot, OFFSETS).items() if "knee" in j)
    assert np.allclose(bones(p.positions), bones(start.positions), atol=1e-9)
    goal = start.positions[J["rtoe"]] + [0.0, -0.2, 0.35]  # below the arm's reach: the spine bends
    ik.set_target("rwrist", goal)
    p = ik.solve()
    assert np.linalg.norm(p.positions[J["rwrist"]] - goal) < 1e-6
    assert M.trunk_tilt_deg(p.positions) > 20.0


def test_set_options_are_typed_by_pose_modes_own_signature_and_unknown_names_are_refused():
    init, solve, settle = T.split_options(["height=1.7", "solve.iterations=8"])
    assert init == {"height": 1.7} and solve == {"iterations": 8} and settle == {}
    with pytest.raises(UserError, match="no option 'bogus'.*options: .*solve.iterations"):
        T.split_options(["bogus=1"])
    with pytest.raises(UserError, match="not a valid int"):
        T.split_options(["solve.iterations=many"])
    with pytest.raises(UserError, match="NAME=VALUE"):
        T.split_options(["height"])


def test_every_task_needs_no_more_drags_than_it_allows_and_names_real_joints():
    assert len(T.TASKS) == 7 and len(set(T.TASK_NAMES)) == 7
    for task in T.TASKS:
        assert 1 <= len(task.drags) <= task.allowed
        for d in task.drags:
            assert d.joint in J and (d.anchor is None or d.anchor in J)


# -- end to end -----------------------------------------------------------------------


def test_a_task_end_to_end_in_pose_mode_and_with_ik(vae):
    """Hands on hips with the shipped VAE: both posers meet both goals and the report
    carries every measure (a small synthetic reference; the real one is the CLI's)."""
    ref = R.ReferenceSet.from_rotations([("a", wobble(4, 5)), ("b", wobble(4, 6))], OFFSETS, stride=1)
    task = next(t for t in T.TASKS if t.name == "hands_on_hips")
    for poser in T.POSERS:
        r = T.run_task(task, poser, vae, ref, events=6)
        assert r.reached and r.max_position_error_cm < T.REACH_CM and len(r.goal_errors) == 2
        assert r.naturalness_cm > 0.0 and r.check.violations == []
        assert set(r.feet_moved_cm) == {"lankle", "rankle"}
        row = r.to_dict()
        assert {"naturalness_cm", "within_spread", "check", "balanced", "positions"} <= set(row)
        assert np.asarray(row["positions"]).shape == (sk.NUM_JOINTS, 3)
    assert max(r.feet_moved_cm.values()) < 1e-6  # the IK poser (last) holds the feet


def test_bench_pose_tasks_prints_the_table_and_writes_json(vae, tmp_path, capsys, monkeypatch):
    """Runs without any motion data: the reference is the poses shipped in assets/."""
    from engine.cli.main import main

    monkeypatch.chdir(tmp_path)  # no ./prepared: the shipped validation poses are the reference
    out = tmp_path / "tasks.json"
    assert (
        main(
            [
                "bench",
                "--pose-tasks",
                "--task",
                "head_turn",
                "--events",
                "4",
                "--reference-stride",
                "16",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "head_turn" in text and "pose-mode" in text and "9 validation files (shipped)" in text
    data = json.loads(out.read_text())
    assert [r["poser"] for r in data["tasks"]] == ["pose-mode", "ik"]
    assert data["reference"]["p95_cm"] > data["reference"]["median_cm"] > 0
    ik = data["tasks"][1]
    assert ik["reached"] and ik["goal_errors"][0]["kind"] == "turn" and ik["goal_errors"][0]["error"] < 1e-3


def test_bench_pose_tasks_refuses_a_clip_an_unknown_poser_and_a_bad_option(tmp_path, capsys):
    from engine.cli.main import main

    assert main(["bench", str(tmp_path / "x.bvh"), "--pose-tasks"]) == 2
    assert "reads no clip" in capsys.readouterr().err
    assert main(["bench", "--pose-tasks", "--method", "dragposer"]) == 2
    assert "unknown poser" in capsys.readouterr().err
    assert main(["bench", "--pose-tasks", "--set", "nope=1"]) == 2
    assert "no option 'nope'" in capsys.readouterr().err
    assert main(["bench", "--pose-tasks", "--method", "bake", "--events", "4"]) == 2
    assert "--events 4" in capsys.readouterr().err
    assert main(["bench", "--pose-tasks", "--task", "head_turn", "--reference", str(tmp_path / "none")]) == 2
    assert "--reference" in capsys.readouterr().err
    assert main(["bench", "--pose-tasks", "--task", "head_turn", "--reference", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"--reference {tmp_path}: validation file(s) not found" in err and R.VALIDATION_FILES[0] in err
    assert Path(tmp_path).is_dir()


def test_bench_pose_tasks_measures_naturalness_against_the_files_given(vae, tmp_path, capsys):
    """``--reference-files``: any motion files are the real poses, each file one take; the
    report names the take of the nearest one."""
    from engine.cli.main import main
    from engine.motion.bvh import save_motion_bvh
    from engine.motion.clip import Motion

    files = []
    for seed in (3, 4):
        path = tmp_path / f"take{seed}.bvh"
        root = np.tile([0.0, 0.0, STAND], (12, 1))
        save_motion_bvh(path, Motion(wobble(12, seed, 0.2), root, sk.Skeleton.canonical(), 60.0, path.stem))
        files.append(str(path))
    out = tmp_path / "tasks.json"
    args = [
        "bench",
        "--pose-tasks",
        "--task",
        "head_turn",
        "--method",
        "ik",
        "--events",
        "4",
        "--reference-stride",
        "4",
    ]
    assert main([*args, "--reference-files", *files, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "naturalness reference: 2 files, every 4th frame, mirrored, 12 poses" in text
    data = json.loads(out.read_text())
    (row,) = data["tasks"]
    assert row["nearest_take"] in files and R.take_label(row["nearest_take"]) in text
    assert R.take_label(row["nearest_take"]) == f"{tmp_path.name}/{Path(row['nearest_take']).name}"
    assert data["reference"]["poses"] == 12 and row["naturalness_cm"] > 0
    assert main([*args, "--reference-files", files[0], str(tmp_path / "gone.bvh")]) == 2
    assert f"--reference-files: no such file: {tmp_path / 'gone.bvh'}" in capsys.readouterr().err
    assert main([*args, "--reference-files", files[0]]) == 2
    assert "at least two takes" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([*args, "--reference-files", *files, "--reference", str(tmp_path)])
    assert "not allowed with argument --reference-files" in capsys.readouterr().err


@needs_data
def test_bench_pose_tasks_bakes_the_task_s_scene_and_reports_pose_mode_s_pose(vae, tmp_path, capsys, monkeypatch):
    from engine.cli.main import main

    monkeypatch.chdir(tmp_path)
    out = tmp_path / "tasks.json"
    assert (
        main(
            [
                "bench",
                "--pose-tasks",
                "--task",
                "squat",
                "--method",
                "pose-mode",
                "--method",
                "bake",
                "--reference-stride",
                "16",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    assert "knee" in capsys.readouterr().out
    mode, baked = json.loads(out.read_text())["tasks"]
    assert (mode["poser"], baked["poser"]) == ("pose-mode", "bake")
    assert np.abs(np.subtract(mode["positions"], baked["positions"])).max() < 1e-4
    assert baked["knee_height_cm"] == pytest.approx(mode["knee_height_cm"]) and baked["knee_height_cm"] > 25


@pytest.mark.parametrize("name", ["hand_to_knee", "pick_up"])
def test_low_reaches_end_on_their_goal_with_the_feet_planted_and_the_body_balanced(vae, name):
    """The two low reaches with the shipped VAE, 20 events as the benchmark drags: the
    wrist ends within 2 cm of its goal, both feet down where they stood, the centre of
    mass over the feet, no limb bent backwards. Without the reach rounds
    (``reach_rounds=0``) the same drag stops more than 2 cm short."""
    ref = R.ReferenceSet.from_rotations([("a", wobble(4, 5)), ("b", wobble(4, 6))], OFFSETS, stride=1)
    task = next(t for t in T.TASKS if t.name == name)
    r = T.run_task(task, "pose-mode", vae, ref)
    assert r.reached and r.max_position_error_cm <= T.REACH_CM
    assert all(r.check.feet_down.values()) and r.check.balance_margin_cm > 0.0
    assert max(r.feet_moved_cm.values()) < 0.5 and r.check.violations == []
    short = T.run_task(task, "pose-mode", vae, ref, ["reach_rounds=0"])
    assert short.max_position_error_cm > T.REACH_CM
