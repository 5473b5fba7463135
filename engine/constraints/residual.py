"""A constraint's maths, written once: a residual of the pose, batched over frames.

Every term the pose optimizer minimises (trackers, the temporal prior, smoothing, the
ground band and every user constraint) is a :class:`Term`: a vector function of the pose
whose squared norm is the term's loss (Ceres' cost functions are the model). A term is
built once per solve from its constraint's parameters frozen for the frame(s)
(:meth:`engine.constraints.base.Constraint.term`) and evaluated on ``A`` frames at once:

* ``P (A, 22, 3)``: world joint positions, metres;
* ``W (A, 22, 3, 3)``: world joint rotation matrices;
* ``z (A, L)``: the latents (for terms on the latent itself).

:meth:`Term.residual` returns ``r (A, m)`` and, when asked (numpy only), its Jacobian
blocks: ``d_pos (A, m, k, 3)`` w.r.t. the positions of ``pos_joints (k,)``, ``d_rot (A,
m, k', 3)`` w.r.t. a small world-frame turn ``a`` of the rotations of ``rot_joints
(k',)`` (``W_j -> exp([a]x) W_j``; the joint's position and its children left alone),
and ``d_latent (A, m, L)``. A term whose entries each read one joint (trackers, pins, end
effectors, smoothing) gives its Jacobian per entry instead: ``entry_joint (m,)``, the joint
entry ``i`` reads, with ``d_pos_entry (A, m, 3)`` and ``d_rot_entry (A, m, 3)``, the rows
of the blocks above that are not structurally zero (``m x 3`` numbers instead of ``m x k x
3``, and one product to scatter them). Everything else is derived from that one definition:

* the loss of each constraint: ``|r|^2`` over its entries (:meth:`Term.losses`);
* the solver's fast path: ``2 w J^T r``, accumulated into position, rotation and latent
  gradients over all of a frame's terms at once
  (:class:`~engine.constraints.term_stack.TermStack`), which :mod:`engine.solver.chain` carries through
  FK and the decoder in closed form; ``A = 1`` is the frame-by-frame solve and ``A > 1``
  the batched offline solve (:mod:`engine.solver.batch`);
* the torch reference: the same residual evaluated on tensors (:data:`TORCH`), through
  autograd (:meth:`engine.constraints.base.Constraint.loss`);
* the offline stopping test: a bound on the norm of groups of residual entries
  (:meth:`Term.satisfied_by`), read from the residual the objective already evaluated.

A term may hold several constraints of one kind (all the trackers of a frame are one
term): :attr:`Term.names` lists them and :attr:`Term.owner` says which entry of ``r``
belongs to which. The array kit (:class:`Kit`) makes one residual function serve numpy
and torch; ``tests/engine/test_terms.py`` checks every kind's Jacobian against autograd
on the inputs its :meth:`~engine.constraints.base.Constraint.examples` declares.
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class FrameInputs:
    """What a term may depend on besides the pose being solved.

    Attributes
    ----------
    previous_positions : ndarray (22, 3) or None
        The previous frame's solved world positions, metres (None on the first frame).
    frame : int
        Frame index in the clip.
    prediction : ndarray (L,) or None
        The temporal predictor's latent for the frame.
    """

    previous_positions: np.ndarray | None = None
    frame: int = 0
    prediction: np.ndarray | None = None


class Kit:
    """The array operations a residual uses, for numpy arrays (:data:`NUMPY`) or torch
    tensors (:data:`TORCH`); arithmetic operators and indexing work on both directly."""

    def __init__(self, module: Any) -> None:
        self.xp = module
        self.is_numpy = module is np

    def const(self, x: Any, like: Any) -> Any:
        """A parameter (numpy) as an array of ``like``'s kind, dtype and device."""
        if self.is_numpy:
            return np.asarray(x, dtype=np.float64)
        return self.xp.as_tensor(np.array(x, dtype=np.float64), dtype=like.dtype, device=like.device)

    def joints(self, x: Any, index: Any) -> Any:
        """``x[:, index]``: the rows ``index`` (an index array or a slice) of ``x``'s second
        axis. numpy's ``take`` gathers them at a third of fancy indexing's cost on the
        solver's small arrays; a slice stays a view."""
        if self.is_numpy and not isinstance(index, slice):
            return x.take(index, axis=1)
        return x[:, index]

    def relu(self, x: Any) -> Any:
        return np.maximum(x, 0.0) if self.is_numpy else self.xp.relu(x)

    def sqrt(self, x: Any) -> Any:
        return self.xp.sqrt(x)

    def clamp_min(self, x: Any, low: float) -> Any:
        return np.maximum(x, low) if self.is_numpy else x.clamp_min(low)

    def cat(self, parts: list, axis: int = -1) -> Any:
        return np.concatenate(parts, axis=axis) if self.is_numpy else self.xp.cat(parts, dim=axis)

    def logsumexp(self, x: Any, axis: int = -1) -> Any:
        if not self.is_numpy:
            return self.xp.logsumexp(x, dim=axis)
        m = x.max(axis=axis, keepdims=True)
        return (m + np.log(np.exp(x - m).sum(axis=axis, keepdims=True))).squeeze(axis)

    def zeros(self, shape: tuple[int, ...], like: Any) -> Any:
        return np.zeros(shape) if self.is_numpy else like.new_zeros(shape)


NUMPY = Kit(np)


def torch_kit() -> Kit:
    """The torch kit (torch is imported on first use: editors never need it)."""
    global TORCH
    if TORCH is None:
        import torch

        TORCH = Kit(torch)
    return TORCH


TORCH: Kit | None = None


@dataclass
class Residuals:
    """A term's residual on ``A`` frames and, when asked for, its Jacobian blocks (module doc)."""

    r: Any
    pos_joints: np.ndarray | None = None
    d_pos: np.ndarray | None = None
    rot_joints: np.ndarray | None = None
    d_rot: np.ndarray | None = None
    d_latent: np.ndarray | None = None
    entry_joint: np.ndarray | None = None
    d_pos_entry: np.ndarray | None = None
    d_rot_entry: np.ndarray | None = None


class Term:
    """Base of every kind's term: subclasses set :attr:`names` and :attr:`owner` and define
    :meth:`residual`; a term the offline stopping rule should wait for also sets
    :attr:`check_group` and :attr:`check_limit2` (or :meth:`check_limits`).

    Attributes
    ----------
    names : tuple of str
        The names of the constraints the term holds (loss reporting).
    owner : ndarray (m,) int
        Index in :attr:`names` of the constraint each residual entry belongs to.
    check_group : ndarray (m,) int or None
        The group of residual entries each entry belongs to for :meth:`satisfied_by`
        (``0 .. G-1``, one constraint's entries only; -1: not read). None: the term never
        holds the offline stop.
    check_limit2 : ndarray (G,)
        The largest squared norm of each group's entries that lets the solve stop.
    """

    names: tuple[str, ...] = ()
    owner: np.ndarray = np.zeros(0, dtype=np.intp)
    check_group: np.ndarray | None = None
    check_limit2: np.ndarray = np.zeros(0)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        """``r (A, m)`` at ``P (A, 22, 3)``, ``W (A, 22, 3, 3)``, ``z (A, L)``, with the
        Jacobian blocks when ``jac`` (numpy only). A term with per-frame parameters
        (:class:`FrameRows`) reads its rows ``rows`` (index array, ``(A,)``) of them."""
        raise NotImplementedError

    def check_limits(self, sel: Any) -> np.ndarray:
        """The squared bound of each check group, ``(G,)``, or ``(A, G)`` for a term whose
        bounds change per frame (``sel``: the rows of its per-frame parameters that
        :meth:`residual` read, a slice or an index array)."""
        return self.check_limit2

    # -- derived from the residual ------------------------------------------------------
    def satisfied_by(self, res: Residuals, rows: Any = None) -> np.ndarray:
        """Per frame ``(A,)`` and constraint ``(n,)``: whether the offline optimizer may
        stop on its account, read from the residual ``res`` of those frames: every check
        group of the constraint has a squared norm within its bound (a non-finite one
        never has). Always, for a term without checks."""
        a = len(res.r)
        out = np.ones((a, len(self.names)), dtype=bool)
        if self.check_group is None:
            return out
        order, starts, group_owner = self._groups()
        if not len(order):
            return out
        r = np.asarray(res.r)[:, order]
        squared = np.add.reduceat(r * r, starts, axis=1)  # (A, G)
        held = ~(squared <= self.check_limits(slice(0, a) if rows is None else rows))
        for g in np.flatnonzero(held.any(0)):
            out[:, group_owner[g]] &= ~held[:, g]
        return out

    def satisfied(self, P: np.ndarray, W: np.ndarray, z: np.ndarray, rows: Any = None) -> np.ndarray:
        """:meth:`satisfied_by` of the residual at ``P``, ``W``, ``z`` (numpy); the solver's
        objectives read the residual they evaluated instead."""
        if self.check_group is None:
            return np.ones((len(P), len(self.names)), dtype=bool)
        return self.satisfied_by(self.residual(NUMPY, P, W, z, rows=rows), rows)

    def _groups(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The checked entries in group order, where each group starts in it, and each
        group's constraint (cached: a term's groups never change)."""
        cached = getattr(self, "_group_cache", None)
        group = self.check_group
        assert group is not None  # asked only of a term with checks
        if cached is None or cached[0] is not group:
            order = np.flatnonzero(group >= 0)
            order = order[np.argsort(group[order], kind="stable")]
            starts = np.flatnonzero(np.r_[True, np.diff(group[order]) != 0])
            cached = self._group_cache = (group, order, starts, self.owner[order[starts]])
        return cached[1], cached[2], cached[3]

    def _membership(self) -> np.ndarray:
        """``(m, n)``, 1 at ``[i, owner[i]]``: ``r2 @ _membership()`` sums each constraint's
        squared entries (kept while :attr:`owner` stands)."""
        kept = self.__dict__.get("_member")
        if kept is None or kept[0] is not self.owner:
            kept = self._member = (self.owner, _members(self.owner, len(self.names)))
        return kept[1]

    def kept(self, name: str, sel: Any, make: Callable[[], Any]) -> Any:
        """``make()``, a value that depends only on the term's parameters of the frames
        ``sel`` (a Jacobian block constant within a frame): made once and returned at every
        evaluation while the parameters stand (read only) when ``sel`` is a slice (the
        first rows, as a solve of one frame reads them); made anew for an index array.
        :meth:`FrameRows.rows` and :meth:`FrameRows.set_row` forget what was kept."""
        if not isinstance(sel, slice):
            return make()
        kept = self.__dict__.setdefault("_kept_blocks", {})
        key = (name, sel.start, sel.stop)
        value = kept.get(key)
        if value is None:
            value = kept[key] = make()
        return value

    def losses(self, res: Residuals, kit: Kit = NUMPY) -> Any:
        """Each constraint's loss ``(A, n)``: the squared norm of its residual entries."""
        member = self._membership()
        r2 = res.r * res.r
        return r2 @ (member if kit.is_numpy else kit.const(member, r2))


_MEMBERS: dict[tuple[bytes, int], np.ndarray] = {}  # owner arrays seen -> their 0/1 matrix (shared)


def _members(owner: np.ndarray, count: int) -> np.ndarray:
    """:meth:`Term._membership` of ``owner (m,)`` over ``count`` constraints. Cached: a
    term's owners never change, and frame after frame share theirs."""
    key = (owner.tobytes(), count)
    out = _MEMBERS.get(key)
    if out is None:
        if len(_MEMBERS) > 4096:
            _MEMBERS.clear()
        out = np.zeros((len(owner), count))
        out[np.arange(len(owner)), owner] = 1.0
        _MEMBERS[key] = out
    return out


class FrameRows:
    """A term whose parameters have a frame axis (trackers, smoothing target, predicted
    latent): built for one frame, :meth:`rows` gives it ``T`` rows and :meth:`set_row`
    writes one frame's parameters into a row, which is how the batched offline solve
    (:mod:`engine.solver.batch`) gives each of its frames its own readings.

    Subclasses list their per-frame arrays (leading axis the frame) in :attr:`PER_FRAME`.
    """

    PER_FRAME: tuple[str, ...] = ()

    def rows(self, count: int) -> Any:
        """A copy with ``count`` rows, each row 0 of this one."""
        out = copy.copy(self)
        for name in self.PER_FRAME:
            setattr(out, name, np.repeat(getattr(self, name)[:1], count, axis=0))
        out._kept_blocks = {}
        return out

    def set_row(self, row: int, frame: Any) -> None:
        """Row ``row`` takes the parameters of ``frame`` (a one-frame term of the same shape)."""
        for name in self.PER_FRAME:
            getattr(self, name)[row] = getattr(frame, name)[0]
        self._kept_blocks: dict[tuple, Any] = {}

    def select(self, like: Any, rows: Any) -> Any:
        """The row selection for ``A = len(like)`` frames: ``rows``, or the first ``A``."""
        return slice(0, len(like)) if rows is None else rows


class PointTerm(FrameRows, Term):
    """``scale * (P_k - target_k)`` for the joints ``k`` of :attr:`joints`, 3 entries each
    (joint by joint), every entry reading one joint: the residual of a pin, of the
    smoothing term and of the gait targets. Per frame ``target (A, k, 3)`` and ``scale (A,
    k, 3)`` (0: that entry is off).

    Parameters
    ----------
    name : str
        The constraint's name.
    joints : sequence of int
        The joints, ``k`` of them.
    target : ndarray (k, 3)
        Their targets, metres.
    scale : float or ndarray broadcasting to (k, 3)
        Each entry's factor.
    """

    PER_FRAME = ("target", "scale")

    def __init__(self, name: str, joints: tuple[int, ...], target: np.ndarray, scale: Any) -> None:
        self.names = (name,)
        self.joints, self._take, self.owner, self.entry_joint, self._unit = _point_layout(tuple(joints))
        k = len(self.joints)
        self.target = np.asarray(target, dtype=np.float64).reshape(1, k, 3)
        self.scale = np.full((1, k, 3), scale, dtype=np.float64)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        sel = self.select(P, rows)
        scale, a = self.scale[sel], P.shape[0]
        r = (kit.joints(P, self._take) - kit.const(self.target[sel], P)) * kit.const(scale, P)
        r = r.reshape(a, len(self.owner))
        if not jac:
            return Residuals(r)
        # entry 3 k + c reads P_k along axis c: its row is scale times that axis (constant within a frame)
        d_pos = self.kept("d_pos", sel, lambda: scale.reshape(a, -1, 1) * self._unit)
        return Residuals(r, entry_joint=self.entry_joint, d_pos_entry=d_pos)


@functools.lru_cache(maxsize=64)
def _point_layout(joints: tuple[int, ...]) -> tuple[np.ndarray, Any, np.ndarray, np.ndarray, np.ndarray]:
    """A :class:`PointTerm`'s index arrays over ``joints`` (shared, read only): the joints,
    how to take their rows of ``P`` (a slice when consecutive), each entry's constraint and
    joint, and each entry's axis ``(3 k, 3)``."""
    j = np.array(joints, dtype=np.intp)
    k = len(j)
    take = slice(joints[0], joints[0] + k) if joints == tuple(range(joints[0], joints[0] + k)) else j
    return j, take, np.zeros(3 * k, dtype=np.intp), np.repeat(j, 3), np.tile(np.eye(3), (k, 1))
