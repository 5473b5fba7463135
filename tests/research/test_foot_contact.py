"""research/foot_contact.py: the contact label, its agreement and the skating figure."""

from __future__ import annotations

import numpy as np

from research.foot_contact import FEET, agreement, contacts, foot_metrics


def _feet(frames: int, speed: float, fps: float = 60.0) -> np.ndarray:
    """Poses (F, 22, 3) whose left ankle stays on the floor and whose right ankle glides
    along -Y at ``speed`` m/s on the floor."""
    pos = np.zeros((frames, 22, 3))
    pos[:, :, 2] = 1.0
    pos[:, FEET, 2] = 0.08
    pos[:, FEET[1], 1] = -speed * np.arange(frames) / fps
    return pos


def test_a_planted_foot_is_in_contact_and_a_gliding_one_is_not():
    c = contacts(_feet(30, 1.0), 60.0, floor=0.08)
    assert c[:, 0].all() and not c[:, 1].any()


def test_agreement_and_skating_against_the_truth():
    truth, glide = _feet(30, 0.0), _feet(30, 1.0)
    m = foot_metrics(truth, glide, 60.0)
    assert abs(m["skate_cms"] - 50.0) < 1e-9  # one foot at 100 cm/s, the other still
    assert m["f1"] == 0.5 and m["acc"] == 0.5
    assert agreement(np.ones((5, 2), bool), np.ones((5, 2), bool)) == {"f1": 1.0, "acc": 1.0}
