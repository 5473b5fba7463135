"""How pose mode keeps a pose natural: :class:`PoseOptions` and the crouch's limits
(:mod:`engine.authoring.pose_mode` uses them; ``bench --pose-tasks --set NAME=VALUE``
sets a field; a scene stores them as ``pose_options``, :func:`options_from_dict`, and
``bake`` poses its keys with them)."""

from __future__ import annotations

import dataclasses
import math
import typing
from dataclasses import dataclass
from typing import Any

from engine.errors import UserError
from engine.validation import shown

#: Weight of the pull towards the starting (or interpolated) latent: keeps the pose near
#: the learned manifold where the targets leave it free, as DragPoser's temporal prior does.
PRIOR_WEIGHT = 0.01

#: Key of a numeric field's accepted range ``(lo, hi)`` in its ``dataclasses.field`` metadata.
RANGE = "range"


def _option(default: Any, lo: float | None = None, hi: float | None = None) -> Any:
    """A field with ``default`` and, for a number, its range ``lo``-``hi`` as metadata."""
    return dataclasses.field(default=default, metadata={} if lo is None else {RANGE: (lo, hi)})


#: Lowest pelvis height the crouch moves it to, as a share of its standing height (a deep
#: squat; the two-bone legs cannot fold much further).
LOWEST_ROOT = 0.45
#: Of an arm's length, the distance from its shoulder beyond which a wrist target within
#: the stooping reach pulls the shoulder (``PoseOptions.stoop_deg``): the arm's two-bone
#: step puts the wrist on its target from there with the elbow still bent a little.
STOOP_REACH = 0.95
#: A dragged pelvis crouches once it is this far below its standing height, metres: less
#: is the jitter of a level drag of the hips.
SQUAT_FROM = 0.02


@dataclass
class PoseOptions:
    """How pose mode keeps a pose natural (``bench --pose-tasks --set name=value``).

    Attributes
    ----------
    plant_feet : bool
        Untargeted feet stay where they stand (ankle and toe each a target at their
        planted place) until that foot is dragged; a dragged foot is planted where it is
        left.
    plant_weight : float
        Weight of a planted foot's targets, as a user target's.
    balance : bool
        While both feet are planted, each solve starts with the pelvis moved horizontally
        by ``balance_gain`` of the distance from the centre of mass to the middle of the
        feet, so a body that leans or reaches keeps its weight over its feet (the planted
        feet stay, the legs lean). A pelvis the user drags goes where it is dragged. The
        step is cut short where it would take the shoulder of a reaching wrist's arm out
        of that arm's reach of its target, as long as the centre of mass stays
        :data:`engine.authoring.pose_root.REACH_MARGIN` inside the feet's support
        (:func:`engine.authoring.pose_root.reach_share`): a far reach then leans the
        trunk rather than pull the hand back from its goal.
    balance_gain : float
        Share of the centre of mass's distance from the feet that one solve corrects.
    balance_tolerance : float
        Distance (metres) from the middle of the feet within which the centre of mass is
        left where it is (well inside a standing support polygon), so a reach forward is
        not pulled back.
    crouch_balance : bool
        A pelvis lowered by a target on ``root`` (a squat) balances as a standing one
        does: each solve moves it level by the balance step above, away from the level
        place of its target, so the hips go back over the planted feet as they go down
        and the shins stay steep, instead of sinking straight down with the knees far
        ahead of the feet and the weight in front of the toes. The step stops short of
        taking the shoulder of a wrist target above the stooping reach's low point out
        of reach of its target: a pinned hand holds the body.
    crouch_tolerance : float
        The balance tolerance (metres) of a crouch: tighter than ``balance_tolerance``,
        which leaves a reach forward alone, because a crouching body whose weight is
        ahead of the middle of its feet stands on its toes.
    crouch_share : float
        Share of a dragged joint's downward distance to its target that the pelvis takes
        at the start of each solve (the planted legs bend under it), so a reach below
        what the trunk bends to bends the knees; the pelvis stays between
        :data:`LOWEST_ROOT` of its standing height and its standing height.
    crouch_below_reach : bool
        A dragged wrist's target crouches only for the part of its way below the
        lowest point the arm reaches from the standing body with the trunk bent forward
        by ``stoop_deg`` (the arm hanging straight from the bent trunk's shoulder): a
        hand put on the hips, the belly or a knee bends the trunk, not the knees; a hand
        to the floor crouches.
    stoop_deg : float
        How far (degrees) the trunk bends forward at the hips before a low reach
        crouches (``crouch_below_reach``), as a person reaching to a knee stoops with the
        legs nearly straight. While a wrist target lies within that reach and beyond
        :data:`STOOP_REACH` of its arm's length from the shoulder, the latent solve also
        pulls that shoulder to within that distance of the target (weight: the wrist
        target's), so the trunk bends and turns to it instead of stopping short. Under a
        pelvis-only target on the root (the pelvis dragged alone) no crouch takes a
        reach, and the pull acts on every wrist target beyond that distance, low or not;
        under another target on the root none acts. 0: the arm hangs from the standing
        shoulder and nothing pulls it.
    free_height : bool
        Drags solve with the lowest foot on the floor (the root's height is part of the
        pose, so reaching low bends the knees instead of folding the trunk) instead of
        holding the root where it stands. It runs on the solver's reference path, about
        30 times slower than the fast path that drags use otherwise: too slow for
        interactive drags on two cores.
    prior_weight : float
        Pull towards the starting latent (the character's neutral pose for a new pose),
        which keeps the parts no target constrains as they were.
    reach_rounds : int
        Most further rounds of a drag event's solve (each :data:`engine.authoring.pose_solve.ITERATIONS` steps from
        where the last ended, the crouch and balance steps redone first) while a dragged
        joint is more than ``reach_tolerance`` from its target after the exact limb step:
        a reach beyond the arm bends the body further within the same event, and a drag
        that is reached costs one round. While the pelvis crouches (a target on ``root``),
        also while it is off its height or a planted foot off its place, so a fast squat
        drag reaches its depth with the feet flat. The pick-up task's reach is
        sensitive to the last bits of the decoder's float32 sums: four rounds leave it
        1.3-2.1 cm short depending on the CPU, eight 1.2 cm (docs/authoring.md).
    reach_tolerance : float
        Distance (metres) of a dragged joint from its target below which no further
        round runs.
    settle_rounds : int
        Most such rounds when a drag ends (:meth:`engine.authoring.pose_mode.PoseMode.settle`):
        a wrist left at the arm's full stretch closes its last centimetres a few
        millimetres a round, and a settle is a single solve the user asked for, so it
        may take more rounds than a drag event.
    hold_weight : float
        Weight (as a user target's) of a pull on every joint the drag does not move
        towards where it was, relative to the root, when the drag began (see
        :meth:`engine.authoring.pose_mode.PoseMode.held`): a drag moves what its targets, the planted feet and the
        prior need and leaves the rest of the body where the user left it. 0: off.
    free_arm_weight : float
        Weight (as a user target's) of the free-arm hold: while only arm or head joints
        are dragged and no wrist target lies far down the body, the elbow and wrist of an
        arm no target holds stay where they hung from their shoulder when the drag began
        (:func:`engine.authoring.pose_hold.free_arms`): the prior would otherwise swing
        the arm the user left (8-18 cm for a wrist dragged out or up). The arm keeps its
        world direction and goes with its shoulder when the body moves. 0: off.
    turn_weight : float
        Share of a rotation target's weight in the latent solve. The exact step after
        the solve turns the joint onto its target whatever this is, so it sets only how
        much the rest of the body (the learned prior's idea of a turned head or hand)
        moves with a turn; 0: a turn moves only that joint.
    keep_trunk : bool
        While no trunk or leg joint has a target, no trunk bone (pelvis, spine, neck)
        leans further back than when the drag began: a bone the latent solve leaned back
        is turned forward until it does not, and the wrists and ankles are put back on
        their targets from there (:mod:`engine.authoring.pose_trunk`). A forward or side
        lean stays, so a low reach still bends the trunk; the pelvis is kept only while
        it stands on both planted feet (a crouch tips it back). Off by default: real
        poses with the arms overhead lean back a little (docs/authoring.md).
    """

    plant_feet: bool = True
    plant_weight: float = _option(1.0, 0.0, 10.0)
    balance: bool = True
    balance_gain: float = _option(0.5, 0.0, 1.0)
    balance_tolerance: float = _option(0.10, 0.0, 1.0)
    crouch_balance: bool = True
    crouch_tolerance: float = _option(0.03, 0.0, 1.0)
    crouch_share: float = _option(0.9, 0.0, 1.0)
    crouch_below_reach: bool = True
    stoop_deg: float = _option(65.0, 0.0, 90.0)
    free_height: bool = False
    prior_weight: float = _option(PRIOR_WEIGHT, 0.0, 10.0)
    reach_rounds: int = _option(8, 0, 50)
    reach_tolerance: float = _option(0.005, 0.0, 1.0)
    settle_rounds: int = _option(12, 0, 100)
    hold_weight: float = _option(0.0, 0.0, 10.0)
    turn_weight: float = _option(0.0, 0.0, 10.0)
    free_arm_weight: float = _option(1.0, 0.0, 10.0)
    keep_trunk: bool = False


def options_to_dict(options: PoseOptions) -> dict[str, Any]:
    """The fields of ``options`` that differ from the defaults, as plain JSON (a scene's
    ``pose_options``; empty for the defaults)."""
    default = PoseOptions()
    return {
        f.name: getattr(options, f.name)
        for f in dataclasses.fields(PoseOptions)
        if getattr(options, f.name) != getattr(default, f.name)
    }


def options_from_dict(value: Any, where: str) -> PoseOptions:
    """:class:`PoseOptions` from a scene's ``pose_options`` object (fields not given keep
    their defaults). Each field is checked against its type and range; errors are
    :class:`UserError` naming ``where`` and the field."""
    if not isinstance(value, dict):
        raise UserError(f"{where} must be an object (pose option -> value)")
    fields = {f.name: f for f in dataclasses.fields(PoseOptions)}
    unknown = sorted(set(value) - set(fields))
    if unknown:
        raise UserError(
            f"{where}: unknown field(s) {', '.join(shown(u) for u in unknown)}; pose options: {', '.join(fields)}"
        )
    hints = typing.get_type_hints(PoseOptions)
    out = {}
    for name, raw in value.items():
        kind, at = hints[name], f"{where}: field {name!r}"
        if kind is bool:
            if not isinstance(raw, bool):
                raise UserError(f"{at} must be true or false, got {shown(raw)}")
            out[name] = raw
            continue
        lo, hi = fields[name].metadata[RANGE]
        if kind is int and isinstance(raw, float) and raw.is_integer():
            raw = int(raw)
        number = (int,) if kind is int else (int, float)
        if isinstance(raw, bool) or not isinstance(raw, number) or not math.isfinite(raw) or not lo <= raw <= hi:
            what = "a whole number" if kind is int else "a number"
            raise UserError(f"{at} must be {what} in {lo:g}-{hi:g}, got {shown(raw)}")
        out[name] = kind(raw)
    return PoseOptions(**out)
