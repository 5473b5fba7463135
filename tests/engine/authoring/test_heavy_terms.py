"""A heavy term (a pin's default weight, 30) in the pose mode's plain gradient steps: the
solve takes it without overshooting, so joints no term holds stay put. Without halving
the step on an overshoot, a pin 3 cm from the elbow sends the total from 0.03 to 4.8 in
one step and moves the other wrist by 20 cm."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.constraints.pin import PinConstraint

J = sk.JOINT_INDEX


def test_a_pin_weighed_30_moves_its_joint_and_leaves_the_other_arm(vae):
    mode = PoseMode(vae, 1.75)
    before = mode.pose.positions.copy()
    goal = before[J["lelbow"]] + [0.0, -0.03, 0.0]
    mode.constraints.append(PinConstraint(joint="lelbow", position=goal, weight=30.0))
    mode.solve()
    after = mode.pose.positions
    assert np.linalg.norm(after[J["lelbow"]] - goal) < 0.01
    for j in ("rwrist", "relbow", "upperneck", "rankle"):
        assert np.linalg.norm(after[J[j]] - before[J[j]]) < 0.02, j


def test_an_overshoot_is_a_total_above_half_again_its_start():
    from engine.authoring.character import overshot

    def records(*totals):
        return [{"total": t} for t in totals]

    assert overshot(records(0.027, 0.917, 0.2))
    assert not overshot(records(0.027, 0.03, 0.02))  # a small rise on the way down
    assert not overshot(records(0.027))
