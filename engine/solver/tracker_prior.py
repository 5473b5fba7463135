"""A temporal prior that sees the trackers: the latents of training poses whose trackers
look like this frame's (beyond the paper).

DragPoser's temporal predictor guesses the next latent from past latents only. With a
sparse sensor set those past latents are themselves guesses, and the untracked legs
follow them: with a prior as good as the truth, presets ``4`` and ``3-hip-hands`` reach
1.5-1.6 cm instead of 7.6-9.2 (``research/oracle_prior.py``, docs/accuracy.md). The
:class:`PoseBank` gives a prior from what *is* measured. It holds, for every frame of the
training clips, the world positions and rotations of the joints trackers sit on
(:data:`BANK_JOINTS`) and the VAE encoder's latent of the true pose. For a frame being
solved, the connected bank joints' readings are turned into :func:`features` (tracked
joints relative to an anchor, hips or else head, in the anchor's heading frame; the
anchor's height; the tracked rotations without heading; the anchor's displacement over
the last :data:`LAG` frames), and the prior's target is the mean latent of the ``k``
training frames with the nearest features (standardised Euclidean distance), a
nearest-neighbour lookup in the spirit of motion matching. It reads only this frame's
and earlier readings, so it works live. The solver then treats that latent exactly as it
treats the predictor's (the ``temporal_prior`` term), so every other constraint still
acts and can still be edited.

The bank belongs to the VAE whose encoder made its latents: the shipped bank
(``assets/models/pose_bank.npz``) goes with the shipped VAE only. Build one with
``scripts/build_pose_bank.py``.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from engine.input_files import file_sha256
from engine.kinematics import quaternion as Q
from engine.solver.bank_prefilter import FRAMES, Neighbourhood, Prefilter, nearest

#: Joints whose tracker readings the bank stores, in this order.
BANK_JOINTS: tuple[str, ...] = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")
#: Anchors (first one connected wins) and their slots in :attr:`PoseBank.prev_anchor`.
ANCHORS: tuple[str, ...] = ("root", "upperneck")
#: Frames over which the anchor's displacement is a feature.
LAG = 4
DEFAULT_BANK = Path(__file__).resolve().parents[2] / "assets" / "models" / "pose_bank.npz"


def features(pos: np.ndarray, rot: np.ndarray, anchor: int, prev_anchor: np.ndarray) -> np.ndarray:
    """Tracker features of ``F`` frames.

    Parameters
    ----------
    pos : ndarray (F, S, 3)
        World positions of the ``S`` tracked joints, metres.
    rot : ndarray (F, S, 4)
        Their world rotations (w, x, y, z).
    anchor : int
        Index (in ``S``) of the anchor joint.
    prev_anchor : ndarray (F, 3)
        The anchor's position :data:`LAG` frames earlier (its first position at the start).

    Returns
    -------
    ndarray (F, 3 (S - 1) + 1 + 6 S + 3)
        Other joints relative to the anchor, the anchor's height, the first two columns of
        each rotation matrix (halved), the anchor's displacement (doubled); everything
        turned about the vertical so the anchor faces -Y: the features do not depend on
        where the wearer stands or which way they face.
    """
    f, s = pos.shape[:2]
    unyaw = Q.conjugate(Q.heading(rot[:, anchor]))  # turns the anchor to face -Y
    rel = Q.rotate(unyaw[:, None], pos - pos[:, anchor : anchor + 1])
    others = [i for i in range(s) if i != anchor]
    # the F * S rotations as one flat (F S, 4) array: one matrix product each instead of
    # F stacked small ones (the same sums of the same terms, ~3x faster on the whole bank)
    turned = Q.mul(np.repeat(unyaw, s, axis=0), rot.reshape(f * s, 4))
    mats = Q.to_matrix(turned)[..., :2].reshape(f, -1)
    disp = Q.rotate(unyaw, pos[:, anchor] - prev_anchor)
    return np.concatenate((rel[:, others].reshape(f, -1), pos[:, anchor, 2:3], 0.5 * mats, 2.0 * disp), -1)


def feature_columns(joints: Sequence[str]) -> list[int]:
    """Columns of :func:`features` of ``joints`` (any order, an anchor among them) within
    the features of all :data:`BANK_JOINTS` around the same anchor (:func:`_anchor_of`),
    in the order :func:`features` of ``joints`` writes them."""
    anchor = _anchor_of(joints)
    others = [j for j in BANK_JOINTS if j != anchor]  # the full layout's relative-position blocks
    rel = [3 * others.index(j) + c for j in joints if j != anchor for c in range(3)]
    height = 3 * len(others)
    mats = [height + 1 + 6 * BANK_JOINTS.index(j) + c for j in joints for c in range(6)]
    disp = height + 1 + 6 * len(BANK_JOINTS)
    return [*rel, height, *mats, disp, disp + 1, disp + 2]


@dataclass
class _Table:
    """Standardised features of every bank frame for all :data:`BANK_JOINTS` around one anchor."""

    mean: np.ndarray  # (D,) float64
    std: np.ndarray  # (D,) float64
    table: torch.Tensor  # (N, D) float32
    gram: np.ndarray  # (D, D) float64 table.T @ table, which every combination's prefilter reads a block of


@dataclass
class _Index:
    """A tracker combination's view of its anchor's :class:`_Table`: the query is written
    into the combination's columns of a zero vector, so ``table @ q`` sums over those
    columns only and no per-combination copy of the table is kept."""

    table: _Table
    cols: np.ndarray  # (D_c,) its columns, in features(joints) order
    norms: torch.Tensor  # (N,) squared lengths of the rows over those columns
    full: bool  # cols is the whole table in order (the product is the table's own)
    prefilter: Prefilter  # exact lower bounds that spare most rows' products
    mean: np.ndarray  # (D_c,) the table's mean and std over cols, float64
    std: np.ndarray
    cols_t: torch.Tensor  # cols as a tensor, for writing the query


@dataclass
class PoseBank:
    """Tracker readings and true latents of the training frames (see the module doc).

    Attributes
    ----------
    positions : ndarray (N, 6, 3)
        World positions of :data:`BANK_JOINTS`, metres.
    rotations : ndarray (N, 6, 4)
        Their world rotations.
    prev_anchor : ndarray (N, 2, 3)
        Positions of the two :data:`ANCHORS` :data:`LAG` frames earlier in the same clip.
    latents : ndarray (N, L)
        VAE encoder mean of each frame's true pose.
    vae_sha256 : str
        Hash of the VAE weights file the latents come from ("" = unknown).
    k : int
        Neighbours averaged per lookup.
    """

    positions: np.ndarray
    rotations: np.ndarray
    prev_anchor: np.ndarray
    latents: np.ndarray
    vae_sha256: str = ""
    k: int = 8
    _indexes: dict = field(default_factory=dict, repr=False)
    _tables: dict = field(default_factory=dict, repr=False)
    _hints: dict = field(default_factory=dict, repr=False)  # combination -> last neighbours
    _near: dict = field(default_factory=dict, repr=False)  # combination -> its live queries' rows
    #: Index work done so far: anchor tables built plus combinations derived from them
    #: (a live frame must find its combination ready: :meth:`prepare`).
    index_builds: int = field(default=0, repr=False)

    def __post_init__(self) -> None:
        n = len(self.latents)
        shapes = {
            "positions": (n, len(BANK_JOINTS), 3),
            "rotations": (n, len(BANK_JOINTS), 4),
            "prev_anchor": (n, len(ANCHORS), 3),
        }
        for name, shape in shapes.items():
            if getattr(self, name).shape != shape:
                raise ValueError(f"pose bank: {name} has shape {getattr(self, name).shape}, expected {shape}")
        if n < self.k:
            raise ValueError(f"pose bank: {n} frames, fewer than k = {self.k}")
        self._latents = torch.as_tensor(np.asarray(self.latents, np.float32))

    def __len__(self) -> int:
        return len(self.latents)

    def prepare(self, combinations: Sequence[Sequence[str]] = ()) -> "PoseBank":
        """Build what lookups need ahead of the first frame: both anchors' tables (the
        costly part, ~0.5 s each on the shipped bank) and the index of each of
        ``combinations`` (tuples of bank joints, an anchor among them; a column sum each).
        A combination not prepared is derived on its first lookup. Returns ``self``."""
        for anchor in ANCHORS:
            self._table(anchor)
        for joints in combinations:
            self._index(tuple(joints))
        return self

    def _table(self, anchor: str) -> _Table:
        tab = self._tables.get(anchor)
        if tab is None:
            a = BANK_JOINTS.index(anchor)
            x = features(
                self.positions.astype(np.float64),
                self.rotations.astype(np.float64),
                a,
                self.prev_anchor[:, ANCHORS.index(anchor)].astype(np.float64),
            )
            mean, std = x.mean(0), x.std(0) + 1e-6
            table = torch.as_tensor((x - mean) / std, dtype=torch.float32)
            t64 = table.double().numpy()
            tab = self._tables[anchor] = _Table(mean, std, table, t64.T @ t64)
            self.index_builds += 1
        return tab

    def _index(self, joints: tuple[str, ...]) -> _Index:
        idx = self._indexes.get(joints)
        if idx is None:
            tab = self._table(_anchor_of(joints))
            cols = np.asarray(feature_columns(joints), dtype=np.intp)
            full = len(cols) == tab.table.shape[1] and bool((cols == np.arange(len(cols))).all())
            sub = tab.table if full else tab.table[:, torch.from_numpy(cols)]
            pre = Prefilter(sub, gram=tab.gram[np.ix_(cols, cols)])
            idx = self._indexes[joints] = _Index(
                tab, cols, (sub * sub).sum(1), full, pre, tab.mean[cols], tab.std[cols], torch.from_numpy(cols)
            )
            self.index_builds += 1
        return idx

    def latent(self, joints: Sequence[str], pos: np.ndarray, rot: np.ndarray, k: int = 0) -> torch.Tensor:
        """Prior latent ``(L,)`` for readings of ``joints`` (a subset of :data:`BANK_JOINTS`
        holding an anchor) over the last ``LAG + 1`` frames: ``pos (LAG+1, S, 3)``, ``rot
        (LAG+1, S, 4)``, oldest first (repeat the first frame at the start of a clip);
        the mean of ``k`` neighbours (0: the bank's :attr:`k`). The previous lookup's
        neighbours bound the search (any hint gives the same answer)."""
        return self.lookup(joints, pos, rot, k)[0]

    def lookup(self, joints: Sequence[str], pos: np.ndarray, rot: np.ndarray, k: int = 0) -> tuple[torch.Tensor, float]:
        """:meth:`latent` and how far the readings are from the bank's: the neighbours'
        mean distance to the query in standardised feature units. On the CMU validation
        clips of everyday motion it is 0.5-1.2 with preset ``4``; on dances, CMU's and other
        labs', 1.6-4.8."""
        z, far = self._lookup(joints, pos[None], rot[None], k, keep_hint=True, distance=True)
        return z[0], far

    def latent_frames(self, joints: Sequence[str], pos: np.ndarray, rot: np.ndarray, k: int = 0) -> torch.Tensor:
        """:meth:`latent` of ``F`` consecutive frames, ``(F, L)``, with the rows and bits
        ``F`` calls of it give: ``pos (F, LAG+1, S, 3)``, ``rot (F, LAG+1, S, 4)`` each
        frame's window as :meth:`latent` takes it. The features are computed for all
        frames at once and each frame's search is bounded by the previous frame's
        neighbours (its prefilter then passes a few percent of the bank's rows, where a
        product over the whole bank reads all of them); the realtime lookup's hint is
        left as it was."""
        return self._lookup(joints, pos, rot, k)[0]

    def _lookup(
        self,
        joints: Sequence[str],
        pos: np.ndarray,
        rot: np.ndarray,
        k: int,
        keep_hint: bool = False,
        distance: bool = False,
    ) -> tuple[torch.Tensor, float]:
        """:meth:`latent_frames` and, with ``distance``, the last frame's distance of
        :meth:`lookup` (else 0); with ``keep_hint`` the last frame's neighbours become the
        next lookup's hint (:meth:`latent`)."""
        joints = tuple(joints)
        idx, a = self._index(joints), anchor_index(joints)
        k = min(k or self.k, len(self))
        if not len(pos):
            return torch.zeros(0, self._latents.shape[1]), 0.0
        x = features(pos[:, -1], rot[:, -1], a, pos[:, 0, a])
        q32 = ((x - idx.mean) / idx.std).astype(np.float32)
        hint, out = self._hints.get(joints), []
        # a live lookup's rows near its last queries (the batch's own bounds serve a clip)
        near = self._near.setdefault(joints, Neighbourhood()) if keep_hint else None
        for start in range(0, len(q32), FRAMES):
            chunk = q32[start : start + FRAMES]
            # a clip's bounds, FRAMES queries to one product (one query: its own in nearest)
            bounds = idx.prefilter.bounds(chunk) if len(chunk) > 1 else [None]
            for q, bound in zip(chunk, bounds):
                hint = self._nearest(idx, q, hint, k, bound, near)
                out.append(hint)
        if keep_hint:
            self._hints[joints] = hint
        far = 0.0
        if distance:
            rows = idx.table.table[out[-1]][:, idx.cols_t].double()
            far = float(torch.linalg.vector_norm(rows - torch.from_numpy(q32[-1]).double(), dim=1).mean())
        return self._latents[torch.stack(out)].mean(1), far

    def _nearest(
        self,
        idx: _Index,
        q32: np.ndarray,
        hint: torch.Tensor | None,
        k: int,
        bound: torch.Tensor | None = None,
        near: Neighbourhood | None = None,
    ) -> torch.Tensor:
        """The ``k`` nearest rows ``(k,)`` of ``idx`` to the standardised query ``q32 (D_c,)``
        (``bound``: its prefilter bounds, if made; ``near``: see :func:`nearest`)."""
        tab = idx.table
        if idx.full:
            q = torch.from_numpy(q32)
        else:  # the other columns multiply zeros
            q = torch.zeros(tab.table.shape[1])
            q[idx.cols_t] = torch.from_numpy(q32)
        # |t - q|^2 = |t|^2 - 2 t.q + |q|^2; the last term is the same for every row
        return nearest(tab.table, idx.norms, q, q32, idx.prefilter, hint, k, bound, near)

    def save(self, path: str | Path) -> None:
        """Write the bank (float16 arrays, compressed) atomically."""
        from engine.atomic import atomic_path

        with atomic_path(path, suffix=".npz") as tmp:
            np.savez_compressed(
                tmp,
                positions=self.positions.astype(np.float16),
                rotations=self.rotations.astype(np.float16),
                prev_anchor=self.prev_anchor.astype(np.float16),
                latents=self.latents.astype(np.float16),
                vae_sha256=np.array(self.vae_sha256),
                k=np.array(self.k),
            )

    @classmethod
    def load(cls, path: str | Path) -> "PoseBank":
        """Read a bank written by :meth:`save` (plain arrays only, no pickles)."""
        from engine.errors import UserError

        try:
            with np.load(Path(path), allow_pickle=False) as d:
                return cls(
                    d["positions"].astype(np.float64),
                    d["rotations"].astype(np.float64),
                    d["prev_anchor"].astype(np.float64),
                    d["latents"].astype(np.float32),
                    str(d["vae_sha256"]),
                    int(d["k"]),
                )
        except (OSError, KeyError, ValueError) as exc:
            raise UserError(f"{path}: not a pose bank ({exc})") from exc


@functools.cache
def default_bank(vae_path: str | Path | None = None) -> PoseBank | None:
    """The shipped bank (loaded once per process), or None when it is missing or was not
    made with the encoder of the VAE at ``vae_path`` (default: the shipped VAE; then the
    temporal predictor stays the prior). A user's VAE file that is byte for byte the
    shipped one (a predictor retrained on the shipped VAE) keeps the bank; a bank that
    records no VAE hash is used only with the shipped VAE. Its tables are built by
    :meth:`PoseBank.prepare` or by the first lookups."""
    from engine.models.loading import DEFAULT_VAE

    vae = Path(vae_path) if vae_path is not None else DEFAULT_VAE
    if not (DEFAULT_BANK.is_file() and vae.is_file()):
        return None
    bank = PoseBank.load(DEFAULT_BANK)
    if bank.vae_sha256 and bank.vae_sha256 != file_sha256(vae):
        return None
    if not bank.vae_sha256 and vae_path is not None:
        return None
    return bank


def combination(joints: Iterable[str]) -> tuple[str, ...] | None:
    """The bank joints among ``joints`` (6-DoF trackers' joints), in :data:`BANK_JOINTS`
    order, as lookups key them; None when they are fewer than two or hold no anchor."""
    given = set(joints)
    out = tuple(j for j in BANK_JOINTS if j in given)
    return out if len(out) >= 2 and any(a in out for a in ANCHORS) else None


def _anchor_of(joints: Sequence[str]) -> str:
    return joints[anchor_index(joints)]


def anchor_index(joints: Sequence[str]) -> int:
    """Index in ``joints`` of the features' anchor (the first of :data:`ANCHORS` there)."""
    for a in ANCHORS:
        if a in joints:
            return list(joints).index(a)
    raise ValueError(f"no anchor ({' or '.join(ANCHORS)}) among {joints}")
