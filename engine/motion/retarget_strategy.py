"""Which canonical motion retargeting produces: a strategy of named choices.

Every choice that changes the clips :func:`engine.motion.retarget.retarget` writes is a
field of :class:`RetargetStrategy`; the retargeting modules ask the strategy for the
choice. Its ``version`` names the whole set: ``data prepare`` records it in the prepared
data's settings (a new version rebuilds the data), ``info`` prints it, and the model
card (``assets/models/data.toml``, ``retarget_version``) says which one feeds the
shipped models. The product produces :data:`CURRENT` only; the definitions the project
compared it with are strategies in ``research/retarget_versions.py``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RetargetStrategy:
    """One definition of the canonical motion (docs/skeleton.md, *Versions*).

    Each flag applies only where the rig profile allows it (``align``,
    ``straight_elbows``, ``straight_knees`` of :class:`engine.motion.rigs.RigProfile`)."""

    #: Number recorded wherever clips of this definition are stored or learnt from.
    version: int
    #: Limbs, hands, feet and head take their twist from the body's points
    #: (:mod:`engine.motion.retarget_body`), through documented rules where the rig lacks
    #: the defining landmarks, and a wrist the body cannot define keeps no twist; without
    #: it every joint keeps the source's rotation with one constant alignment.
    body_twist: bool
    #: A profile's ``straight_elbows``: its zero pose's bent forearm is read as straight.
    straight_elbows: bool
    #: A profile's ``straight_knees``: legs its zero pose draws bent are read straight
    #: along the hip-to-ankle line.
    straight_knees: bool
    #: The canonical rest's toe tips lie on the sole's line
    #: (:func:`engine.motion.retarget_body.sole_tip`), where source rigs put theirs, rather
    #: than where the canonical toe's end site points.
    sole_toe_tips: bool


#: The definition the shipped models learnt from and every command retargets with.
CURRENT = RetargetStrategy(version=4, body_twist=True, straight_elbows=True, straight_knees=False, sole_toe_tips=False)
#: Its number: recorded by ``data prepare`` (a change rebuilds prepared data) and ``info``.
RETARGET_VERSION = CURRENT.version
#: The strategies the product produces, by version: what a model card may name.
STRATEGIES: dict[int, RetargetStrategy] = {CURRENT.version: CURRENT}
