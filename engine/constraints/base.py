"""Constraints: every tracker, target and rule the pose optimizer satisfies is one.

A constraint is a small dataclass with its parameters, a ``weight`` and an ``enabled``
flag, and one residual of the pose (:meth:`Constraint.term`,
:mod:`engine.constraints.residual`) whose squared norm is its loss. The optimizer sums
``weight * loss`` over enabled constraints. Parameters can change
between frames (the GUI does this live). Each kind registers itself by its ``kind``
string, so a scene can be saved to JSON and loaded back (:func:`from_dict`).

Array parameters are numpy arrays; in JSON they are lists, with non-finite entries
written as ``null`` (a NaN position means "not set yet", e.g. a pin that captures the
joint's position on first use).

Every constraint may be limited to a frame range: ``frames = (start, end)`` (inclusive
frame indices; ``None``, the default, is every frame), with ``blend_in`` frames before
``start`` and ``blend_out`` frames after ``end`` over which its weight rises from and
falls back to zero (:meth:`Constraint.activity`).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.residual import FrameInputs, Term
from engine.errors import UserError
from engine.gizmos import Gizmo
from engine.validation import check_known_fields, shown

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

#: kind string -> constraint class; filled by subclasses as they are defined.
REGISTRY: dict[str, type["Constraint"]] = {}
#: Editor tags a parameter's ``metadata["editor"]`` may take (:func:`param`).
EDITOR_TAGS = ("float", "int", "bool", "joint", "joints", "choice", "str", "vec3", "quat", "frames")


def _meta(editor: str, unit: str = "", choices: tuple[str, ...] = ()) -> dict[str, Any]:
    return {"editor": editor, "unit": unit, "choices": tuple(choices)}


def param(
    default: Any = dataclasses.MISSING,
    *,
    editor: str,
    unit: str = "",
    factory: Any = dataclasses.MISSING,
    choices: tuple[str, ...] = (),
    init: bool = True,
) -> Any:
    """A constraint parameter: a dataclass field whose metadata tells editors how to show it.

    Parameters
    ----------
    default, factory
        The field's default value, or a function making it (arrays).
    editor : str
        One of :data:`EDITOR_TAGS` (``joint``: a canonical joint name, ``joints``: a
        tuple of them, ``choice``: one of ``choices``).
    unit : str
        Unit of the value (``m``, ``deg``), empty for none.
    """
    if editor not in EDITOR_TAGS or (editor == "choice") != bool(choices):
        raise TypeError(f"param: editor {editor!r} needs choices exactly when it is 'choice'")
    return dataclasses.field(default=default, default_factory=factory, metadata=_meta(editor, unit, choices), init=init)


def missing_parts(cls: type["Constraint"]) -> list[str]:
    """What a constraint kind fails to declare (empty when complete): its term
    (:meth:`Constraint.term`), its joints (:meth:`Constraint.acts_on`), its example inputs
    (:meth:`Constraint.examples`), its studio placement, and editor metadata on each
    parameter."""
    own = lambda name: any(name in vars(k) for k in cls.__mro__ if k is not Constraint)  # noqa: E731
    out = [f"{m}()" for m in ("term", "acts_on", "examples") if not own(m)]
    if cls.user_facing and not own("placement"):
        out.append("placement()")
    for f in dataclasses.fields(cls):
        if f.name not in ("name", "weight", "enabled", *FRAME_FIELDS) and "editor" not in f.metadata:
            out.append(f"editor metadata on field {f.name!r} (engine.constraints.base.param)")
    return out


def joint_index(name: str, field: str = "joint", kind: str = "") -> int:
    """Index of a canonical joint; a :class:`UserError` names the field otherwise."""
    try:
        return sk.JOINT_INDEX[name]
    except (KeyError, TypeError):
        where = f"constraint {kind!r}: " if kind else ""
        raise UserError(f"{where}field {field!r}: unknown joint {name!r}") from None


class OnOneJoint:
    """For a kind that acts on the one joint its ``joint`` field names: the joint is
    checked (a :class:`UserError` names the field) and is what ``acts_on()`` returns.
    Listed before :class:`Constraint` (``class PinConstraint(OnOneJoint, Constraint)``);
    a kind with more to check calls ``super().check()`` first."""

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)  # type: ignore[attr-defined]

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)  # type: ignore[attr-defined]


@dataclass
class Constraint(ABC):
    """Base class. Subclasses are dataclasses whose extra fields are their parameters.

    Subclasses check their parameters in :meth:`check` (called on construction and by
    :func:`from_dict`), raising :class:`UserError` naming the field.
    """

    kind: ClassVar[str] = ""
    #: False for kinds methods build themselves (sensors, the temporal prior): the
    #: studio does not offer them to users.
    user_facing: ClassVar[bool] = True
    #: Human label shown in the GUI and loss plots (unique within a scene).
    name: str = ""
    weight: float = 1.0
    enabled: bool = True
    #: Active frames ``(start, end)``, inclusive, or None for every frame. Keyword-only
    #: so the kinds' own fields keep their positions.
    frames: tuple[int, int] | None = field(default=None, kw_only=True, metadata=_meta("frames", "frame"))
    #: Frames before ``start`` over which the weight rises from 0 to 1.
    blend_in: int = field(default=0, kw_only=True, metadata=_meta("int", "frame"))
    #: Frames after ``end`` over which the weight falls from 1 to 0.
    blend_out: int = field(default=0, kw_only=True, metadata=_meta("int", "frame"))

    def __init_subclass__(cls, **kw: Any) -> None:
        super().__init_subclass__(**kw)
        if cls.kind:
            REGISTRY[cls.kind] = cls

    @classmethod
    def check_complete(cls) -> None:
        """Check the kind declares everything (:func:`missing_parts`); called for each
        kind by the package's discovery, so a kind missing a part fails on import."""
        missing = missing_parts(cls)
        if missing:
            raise TypeError(f"constraint kind {cls.kind!r} ({cls.__module__}) lacks: {', '.join(missing)}")

    def __post_init__(self) -> None:
        if not self.name:
            self.name = self.kind
        try:
            self.weight = float(self.weight)
        except (TypeError, ValueError):
            raise UserError(f"constraint {self.kind!r}: field 'weight' must be a number") from None
        if not math.isfinite(self.weight) or self.weight < 0:
            raise UserError(f"constraint {self.kind!r}: field 'weight' must be finite and >= 0")
        self._check_frames()
        for f in dataclasses.fields(self):
            default = field_default(f)
            if isinstance(default, np.ndarray):
                value = np.asarray(getattr(self, f.name), dtype=np.float64)
                if value.shape != default.shape:
                    raise UserError(
                        f"constraint {self.kind!r}: field {f.name!r} needs {default.size} numbers, got {value.size}"
                    )
                setattr(self, f.name, value)
        self.check()

    def check(self) -> None:  # noqa: B027 - a no-op default that kinds override
        """Validate parameters (override); raise :class:`UserError` naming the field."""

    def _check_frames(self) -> None:
        where = f"constraint {self.kind!r}"
        for key in ("blend_in", "blend_out"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise UserError(f"{where}: field {key!r} must be a whole number of frames >= 0, got {shown(v)}")
            setattr(self, key, int(v))
        if self.frames is None:
            return
        r = self.frames
        if (
            not isinstance(r, (list, tuple))
            or len(r) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, np.integer)) for v in r)
        ):
            raise UserError(
                f"{where}: field 'frames' must be [start, end] (whole frame numbers) or null, got {shown(r)}"
            )
        start, end = int(r[0]), int(r[1])
        if start < 0 or end < start:
            raise UserError(f"{where}: field 'frames' needs 0 <= start <= end, got [{start}, {end}]")
        self.frames = (start, end)

    def activity(self, frame: int) -> float:
        """How much the constraint acts at ``frame``: its weight is multiplied by this.

        1 inside ``frames`` (and always when ``frames`` is None), 0 outside the range
        and its blends; over the ``blend_in`` frames before ``start`` it rises, and
        over the ``blend_out`` frames after ``end`` it falls, along a smoothstep (no
        kink where the blend meets the range). ``enabled`` is not considered here.

        Parameters
        ----------
        frame : int
            Frame index of the clip or animation.

        Returns
        -------
        float
            In [0, 1].
        """
        if self.frames is None:
            return 1.0
        start, end = self.frames
        if start <= frame <= end:
            return 1.0
        if frame < start:
            gap, span = start - frame, self.blend_in
        else:
            gap, span = frame - end, self.blend_out
        if gap > span:
            return 0.0
        t = 1.0 - gap / (span + 1)  # the frame next to the range is close to 1, never 1
        return t * t * (3.0 - 2.0 * t)

    def active_frames(self) -> tuple[int, int] | None:
        """First and last frame with a non-zero :meth:`activity` (None: every frame)."""
        if self.frames is None:
            return None
        return (max(0, self.frames[0] - self.blend_in), self.frames[1] + self.blend_out)

    @abstractmethod
    def term(self, frame: FrameInputs) -> Term:
        """This constraint's residual for one frame (:mod:`engine.constraints.residual`),
        its parameters frozen as they are now; what it captures on first use comes from
        ``frame.previous_positions``."""

    @classmethod
    def terms(cls, items: "list[Constraint]", frame: FrameInputs) -> list[Term]:
        """The terms of several constraints of this kind for one frame: one per
        constraint, unless the kind batches them into one (the trackers)."""
        return [c.term(frame) for c in items]

    @classmethod
    @abstractmethod
    def examples(cls, positions: np.ndarray) -> "list[Constraint]":
        """Instances of the kind that the generic tests check (gradients against
        autograd, fast against reference, batched against frame by frame, no mutation),
        each with a non-zero loss near the pose ``positions (22, 3)``, metres, and
        together covering the kind's branches (every mode, optional parts on and off)."""

    def loss(self, state: PoseState) -> torch.Tensor:
        """Scalar, non-negative: the squared norm of :meth:`term`'s residual at ``state``,
        through autograd (the reference the solver's fast path is checked against)."""
        from engine.constraints.residual import torch_kit

        kit = torch_kit()
        term = self.term(frame_inputs(state))
        P, W, z = state_arrays(state)
        return term.losses(term.residual(kit, P, W, z), kit)[0, 0]

    def satisfied(self, state: PoseState) -> bool:
        """Whether the offline optimizer may stop on this constraint's account."""
        P, W, z = (None if a is None else a.detach().double().cpu().numpy() for a in state_arrays(state))
        return bool(self.term(frame_inputs(state)).satisfied(P, W, z)[0, 0])

    @abstractmethod
    def acts_on(self) -> tuple[str, ...]:
        """Canonical joints whose pose the loss reads (empty: none, e.g. a latent prior)."""

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """Parameters that put a new constraint next to the character in the studio.

        ``params`` are the values it would get (defaults, or what the user chose) and
        ``positions (22, 3)`` the pose on screen, metres; returns the fields to change
        (``{}``: the defaults are fine wherever the body is). Every user-facing kind
        defines it (:func:`missing_parts`); kinds methods build are never placed.
        """
        return {}

    def settled(self, previous_positions: np.ndarray | None) -> "Constraint":
        """This constraint with any target it captures on first use fixed from the
        previous solved pose ``(22, 3)`` (a copy; ``self`` when nothing is captured).
        Methods keep the returned object for the later frames; the constraint itself is
        never changed (the studio publishes it to the engine thread)."""
        return self

    def gizmo(self, positions: np.ndarray | None = None) -> Gizmo | None:
        """What the viewport draws for this constraint (:mod:`engine.gizmos`), or None.

        ``positions (22, 3)``, the current world joint positions in metres, lets kinds
        that relate joints (distance, look-at) draw lines; without it they draw what
        they can from their parameters alone (possibly nothing: None).
        """
        return None

    def to_dict(self) -> dict[str, Any]:
        """Plain-JSON form: ``kind`` plus every field; arrays as lists, NaN as ``None``."""
        out: dict[str, Any] = {"kind": self.kind}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name in FRAME_FIELDS and self.frames is None and not v:
                continue  # an every-frame constraint reads as it always did
            if isinstance(v, np.ndarray):
                v = [float(x) if math.isfinite(x) else None for x in v.ravel().tolist()]
            elif isinstance(v, tuple):
                v = list(v)
            out[f.name] = v
        return out


#: The frame-range fields every kind has (written only when a range is set).
FRAME_FIELDS = ("frames", "blend_in", "blend_out")


def field_default(f: dataclasses.Field) -> Any:
    """The default value of a dataclass field (calling its factory), or None."""
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None


def from_dict(data: dict[str, Any]) -> Constraint:
    """Rebuild a constraint saved with :meth:`Constraint.to_dict`; errors name the field."""
    if not isinstance(data, dict):
        raise UserError(f"constraint: expected an object, got {type(data).__name__}")
    kinds = sorted(REGISTRY)
    if "kind" not in data:
        # a misspelt "kind" key is named with the key meant, as check_known_fields names others
        meant = [k for k in data if difflib.get_close_matches(str(k), ["kind"], n=1, cutoff=0.6)]
        hint = f"; unknown field {shown(meant[0])} (did you mean 'kind'?)" if meant else ""
        raise UserError(f"no field 'kind'{hint}; kinds: {', '.join(kinds)}")
    kind = data["kind"]
    if not isinstance(kind, str) or kind not in REGISTRY:
        near = difflib.get_close_matches(kind, kinds, n=1, cutoff=0.6) if isinstance(kind, str) else []
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise UserError(f"unknown constraint kind {shown(kind)}{hint}; known: {', '.join(kinds)}")
    cls = REGISTRY[kind]
    names = {f.name: f for f in dataclasses.fields(cls)}
    check_known_fields(data, ("kind", *names), f"constraint {kind!r}")
    kwargs = {}
    for key, value in data.items():
        if key == "kind":
            continue
        default = field_default(names[key])
        if isinstance(default, np.ndarray):
            try:
                value = np.array([np.nan if v is None else v for v in np.ravel(value)], dtype=np.float64)
            except (TypeError, ValueError, OverflowError):
                raise UserError(f"constraint {kind!r}: field {key!r} must be a list of numbers") from None
            if np.isinf(value).any():
                raise UserError(f"constraint {kind!r}: field {key!r} holds a number too large to use")
        elif isinstance(default, tuple):
            value = tuple(value) if isinstance(value, (list, tuple)) else value
        elif isinstance(default, bool):
            if not isinstance(value, bool):
                raise UserError(f"constraint {kind!r}: field {key!r} must be true or false")
        elif isinstance(default, (int, float)):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise UserError(f"constraint {kind!r}: field {key!r} must be a number")
            if isinstance(default, int) and isinstance(value, float) and not value.is_integer():
                raise UserError(f"constraint {kind!r}: field {key!r} must be a whole number, got {shown(value)}")
            try:
                value = type(default)(value)
            except OverflowError:
                raise UserError(f"constraint {kind!r}: field {key!r} = {shown(value)} is too large") from None
        elif isinstance(default, str) and not isinstance(value, str):
            raise UserError(f"constraint {kind!r}: field {key!r} must be a string")
        kwargs[key] = value
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise UserError(f"constraint {kind!r}: {exc}") from exc


def frame_inputs(state: PoseState) -> FrameInputs:
    """The :class:`FrameInputs` of a torch :class:`PoseState` (numpy, detached)."""
    prev, pred = state.previous_positions, state.prediction
    return FrameInputs(
        None if prev is None else prev.detach().double().cpu().numpy(),
        state.frame,
        None if pred is None else pred.detach().double().cpu().numpy(),
    )


def state_arrays(state: PoseState) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """A state's positions ``(1, 22, 3)``, world rotation matrices ``(1, 22, 3, 3)`` and
    latent ``(1, L)``: one frame, as terms take them."""
    from engine.kinematics import quaternion as Q

    W = state.rotation_matrices if state.rotation_matrices is not None else Q.to_matrix(state.world_rotations())
    return state.positions[None], W[None], state.latent[None]
