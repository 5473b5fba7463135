"""research/retarget_identity.py: the comparison catches one changed bit and a missing array."""

from __future__ import annotations

import numpy as np

from research.retarget_identity import differing


def test_one_changed_bit_a_new_shape_and_a_missing_array_are_differences():
    a = {
        "x|4|local_rot": np.array([[1.0, np.nan]]),
        "x|4|joints": np.array(["lhip", "|"]),
        "x|4|offsets": np.zeros((2, 3)),
    }
    same = {k: v.copy() for k, v in a.items()}
    assert differing(a, same) == []  # NaN equals NaN
    bit = dict(same, **{"x|4|local_rot": np.array([[np.nextafter(1.0, 2.0), np.nan]])})
    assert differing(a, bit) == ["x|4|local_rot"]
    assert differing(a, dict(same, **{"x|4|offsets": np.zeros((3, 3))})) == ["x|4|offsets"]
    assert differing(a, dict(same, **{"x|4|joints": np.array(["lhip", "rhip"])})) == ["x|4|joints"]
    del same["x|4|offsets"]
    assert differing(a, same) == ["x|4|offsets"]


def test_the_current_strategy_is_version_4_of_the_research_versions():
    """The versions research compares name the product's current strategy, not a copy."""
    from engine.motion.retarget_strategy import CURRENT
    from research.retarget_versions import VERSIONS

    assert VERSIONS[CURRENT.version] is CURRENT
