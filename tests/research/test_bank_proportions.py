"""research/bank_proportions.py: its bone-chain lengths and the scaling of readings about
the anchor."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.solver.tracker_prior import ANCHORS, BANK_JOINTS

from .script_loader import load_script


def _offsets(rng) -> np.ndarray:
    return rng.uniform(0.05, 0.3, size=(len(sk.PARENTS), 3))


def test_chain_lengths_sum_the_bones_between_the_joints():
    bp = load_script("bank_proportions")
    off = _offsets(np.random.default_rng(1))
    bone = np.linalg.norm(off, axis=1)
    lengths = bp.chain_lengths(off)
    i = sk.JOINT_INDEX
    # root to the left ankle: the hip, thigh and shin bones
    assert np.isclose(lengths[0, -1], bone[[i["lhip"], i["lknee"], i["lankle"]]].sum())
    # the head to the left wrist goes down the neck and out along the arm
    up = ANCHORS.index("upperneck")
    arm = [i[j] for j in ("lclavicle", "lshoulder", "lelbow", "lwrist")]
    neck = [i["upperneck"], i["lowerneck"]]
    assert np.isclose(lengths[up, BANK_JOINTS.index("lwrist")], bone[arm + neck].sum())
    assert lengths[0, BANK_JOINTS.index("root")] == 0.0


def test_scaling_keeps_the_anchor_and_stretches_each_joint_about_it():
    bp = load_script("bank_proportions")
    rng = np.random.default_rng(2)
    cols = [BANK_JOINTS.index(j) for j in ("root", "upperneck", "lwrist")]
    pos, prev = rng.normal(size=(5, 3, 3)), rng.normal(size=(5, 3))
    ratio = np.ones((5, len(ANCHORS), len(BANK_JOINTS) + 1))
    same, same_prev = bp.scaled(pos, prev, ratio, 0, cols)
    assert np.allclose(same, pos) and np.allclose(same_prev, prev)
    ratio[..., 0, BANK_JOINTS.index("lwrist")] = 2.0
    out, _ = bp.scaled(pos, prev, ratio, 0, cols)
    assert np.allclose(out[:, 2] - out[:, 0], 2.0 * (pos[:, 2] - pos[:, 0]))
    assert np.allclose(out[:, :2], pos[:, :2])
