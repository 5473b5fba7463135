"""ASF/AMC input: the reader's maths on a tiny written skeleton, its errors (file and line),
skeleton discovery, and the shared takes that exist in both formats (``cmu_asf/02`` against
their cgspeed BVH conversion in ``cmu_mb/``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from engine.errors import BVHError, UserError
from engine.kinematics import quaternion as Q
from engine.motion.asf_amc import AsfAmcError, load_amc, load_asf
from engine.motion.source_file import find_skeleton, load_source

ASF = """\
# a two-bone arm hanging from a root
:version 1.10
:name TEST
:units
  mass 1.0
  length 1.0
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name upper
     direction 1 0 0
     length 2
     axis 0 0 90 XYZ
    dof rx ry rz
  end
  begin
     id 2
     name lower
     direction 1 0 0
     length 1
     axis 0 0 0 XYZ
    dof rz
  end
:hierarchy
  begin
    root upper
    upper lower
  end
"""


def _amc(*frames: str) -> str:
    out = [":FULLY-SPECIFIED", ":DEGREES"]
    for i, body in enumerate(frames, 1):
        out += [str(i), *body.strip().splitlines()]
    return "\n".join(out) + "\n"


def _world(raw) -> np.ndarray:
    """Joint and end-site world positions (F, J+ends, 3) by plain matrix FK of the RawBVH."""
    q = raw.local_quaternions()
    f, j = q.shape[:2]
    rot = np.zeros((f, j, 3, 3))
    pos = np.zeros((f, j, 3))
    for k in range(j):
        m = Q.to_matrix(q[:, k])
        p = raw.parents[k]
        if p < 0:
            rot[:, k], pos[:, k] = m, raw.positions[:, k]
        else:
            rot[:, k] = rot[:, p] @ m
            pos[:, k] = pos[:, p] + np.einsum("fij,fj->fi", rot[:, p], raw.positions[:, k])
    ends = [pos[:, k] + np.einsum("fij,j->fi", rot[:, k], off) for k, off in sorted(raw.end_sites.items())]
    return np.concatenate([pos, np.stack(ends, 1)], 1)


@pytest.fixture
def arm(tmp_path: Path) -> Path:
    (tmp_path / "arm.asf").write_text(ASF)
    return tmp_path


def test_rest_and_rotated_positions_follow_the_asf_axes(arm: Path):
    """Frame 1 is the rest pose; in frame 2 the upper bone's rx turns about its own x axis,
    which its ``axis 0 0 90`` puts along world y: the bone (along world x) swings to -z."""
    (arm / "m.amc").write_text(
        _amc("root 1 2 3 0 0 0\nupper 0 0 0\nlower 0", "root 1 2 3 0 0 0\nupper 90 0 0\nlower 0")
    )
    raw = load_amc(arm / "m.amc", arm / "arm.asf", fps=30)
    assert raw.names == ("Hips", "upper", "lower") and raw.parents == (-1, 0, 1)
    assert raw.fps == pytest.approx(30)
    w = _world(raw)
    np.testing.assert_allclose(w[0], [[1, 2, 3], [1, 2, 3], [3, 2, 3], [4, 2, 3]], atol=1e-9)
    np.testing.assert_allclose(w[1], [[1, 2, 3], [1, 2, 3], [1, 2, 1], [1, 2, 0]], atol=1e-9)


def test_a_single_dof_bone_and_the_root_rotation(arm: Path):
    """``lower`` animates rz only (one value); the root's RZ turns the whole arm."""
    (arm / "m.amc").write_text(_amc("root 0 0 0 0 0 90\nupper 0 0 0\nlower 90"))
    w = _world(load_amc(arm / "m.amc", arm / "arm.asf"))
    np.testing.assert_allclose(w[0, 2], [0, 2, 0], atol=1e-9)  # elbow: the arm turned to +y
    np.testing.assert_allclose(w[0, 3], [-1, 2, 0], atol=1e-9)  # the forearm turned 90 deg more


@pytest.mark.parametrize(
    ("body", "line", "words"),
    [
        ("root 0 0 0 0 0 0\nupper 0 0\nlower 0", 5, "expected 3 values"),
        ("root 0 0 0 0 0 0\nupper 0 0 0\nelbow 0", 6, "not in the skeleton"),
        ("root 0 0 0 0 0 0\nupper 0 x 0\nlower 0", 5, "expected a number"),
        ("root 0 0 0 0 0 nan\nupper 0 0 0\nlower 0", 4, "not a finite number"),
        ("root 0 0 0 0 0 0\nlower 0", 3, "lacks bone 'upper'"),
    ],
)
def test_amc_errors_name_the_line(arm: Path, body: str, line: int, words: str):
    (arm / "m.amc").write_text(_amc(body))
    with pytest.raises(AsfAmcError, match=f"m.amc:{line}: .*{words}"):
        load_amc(arm / "m.amc", arm / "arm.asf")


def test_amc_frame_numbers_must_count_up(arm: Path):
    text = _amc("root 0 0 0 0 0 0\nupper 0 0 0\nlower 0") + "3\nroot 0 0 0 0 0 0\nupper 0 0 0\nlower 0\n"
    (arm / "m.amc").write_text(text)
    with pytest.raises(AsfAmcError, match=r"m.amc:7: frame number 3: expected 2"):
        load_amc(arm / "m.amc", arm / "arm.asf")


@pytest.mark.parametrize(
    ("old", "new", "words"),
    [
        ("    dof rz\n", "    dof rz rq\n", "dof: expected rx, ry, rz"),
        ("     length 1\n", "     length one\n", "length: expected a number"),
        ("    upper lower\n", "    upper lower hand\n", "hierarchy names bone 'hand'"),
        ("     axis 0 0 0 XYZ\n", "     axis 0 0 0 XYQ\n", "expected an axis order"),
    ],
)
def test_asf_errors_name_the_line(arm: Path, old: str, new: str, words: str):
    text = ASF.replace(old, new)
    line = text.splitlines().index(new.rstrip("\n")) + 1
    (arm / "arm.asf").write_text(text)
    with pytest.raises(AsfAmcError, match=f"arm.asf:{line}: .*{words}"):
        load_asf(arm / "arm.asf")


def test_skeleton_is_found_beside_or_by_name(tmp_path: Path):
    (tmp_path / "HDM_bd.asf").write_text(ASF)
    amc = tmp_path / "HDM_bd_squat_001_120.amc"
    amc.write_text(_amc("root 0 0 0 0 0 0\nupper 0 0 0\nlower 0"))
    assert find_skeleton(amc) == tmp_path / "HDM_bd.asf"  # the only one
    (tmp_path / "HDM_bk.asf").write_text(ASF)
    assert find_skeleton(amc) == tmp_path / "HDM_bd.asf"  # the one whose name starts the AMC's
    other = tmp_path / "walk.amc"
    other.write_text(amc.read_text())
    with pytest.raises(AsfAmcError, match="walk.amc: several ASF skeletons .*--asf"):
        load_source(other)
    assert load_source(other, asf=tmp_path / "HDM_bk.asf").frames == 1
    with pytest.raises(UserError, match="--asf: no such file"):
        find_skeleton(other, tmp_path / "none.asf")
    with pytest.raises(BVHError, match="HDM_bd.asf: an ASF file holds a skeleton without motion"):
        load_source(tmp_path / "HDM_bd.asf")


def test_no_skeleton_beside_says_what_to_do(tmp_path: Path):
    amc = tmp_path / "lonely.amc"
    amc.write_text(_amc("root 0 0 0 0 0 0"))
    with pytest.raises(AsfAmcError, match="lonely.amc: no ASF skeleton beside .*--asf SKELETON.asf"):
        load_source(amc)


CMU_PAIRS = ["02/02_01", "05/05_02", "06/06_13", "09/09_11"]


@pytest.mark.parametrize("take", CMU_PAIRS)
def test_shared_amc_takes_match_their_cgspeed_bvh(shared_mocap: Path, take: str):
    """The same CMU take as ASF/AMC and as the cgspeed BVH: the same canonical motion
    within 1 cm and 2 degrees, frame for frame."""
    from engine.motion.retarget import load_motion

    bvh = shared_mocap / "cmu_mb" / (Path(take).name + ".bvh")
    if not bvh.is_file():
        pytest.skip(f"{bvh} is not in the shared data")
    a = load_motion(shared_mocap / "cmu_asf" / (take + ".amc"))
    b = load_motion(bvh)
    n = min(len(a), len(b))
    assert abs(len(a) - len(b)) <= 1
    pa, pb = a.positions()[:n], b.positions()[:n]
    assert np.linalg.norm(pa - pb, axis=-1).max() < 0.01
    deg = np.degrees(Q.angle(a.local_rot[:n], b.local_rot[:n]))
    assert deg.max() < 2.0


def test_info_reads_an_amc_file_from_the_command_line(shared_mocap: Path):
    amc = shared_mocap / "hdm05" / "HDM_bd_squat1Reps_001_120.amc"
    if not amc.is_file():
        pytest.skip(f"{amc} is not in the shared data")
    out = subprocess.run(
        [sys.executable, "-m", "engine.cli.main", "info", str(amc), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert '"source_fps": 120' in out.stdout and '"source_joints": 31' in out.stdout
