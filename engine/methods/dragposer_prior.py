"""The temporal prior's latent for a frame (:class:`PriorSource`), a collaborator of
:class:`engine.methods.dragposer.DragPoserMethod`: while hips or head are tracked and
``prior = trackers``, from the trackers (the pose bank's neighbours, the tracker network,
or their mean: ``tracker_prior``), else from the temporal predictor.
"""

from __future__ import annotations

import numpy as np
import torch

from engine.solver import LatentPredictor, OptimizerSettings, TemporalSchedule
from engine.solver.tracker_history import TrackerHistory
from engine.solver.tracker_net import TrackerNet, TrackerNets
from engine.solver.tracker_prior import LAG, PoseBank


class PriorSource:
    """The temporal prior's latent for a frame (module doc).

    Parameters
    ----------
    predictor : LatentPredictor or None
    bank : PoseBank or None
    settings : OptimizerSettings
        For the predictor's schedule.
    nets : TrackerNets or None
        The tracker networks: with ``tracker_prior = network`` a combination that has one
        takes its latent from it instead of the bank's neighbours (``both``: the mean of
        the two); the bank still says how far the readings are from the training poses.
    """

    def __init__(
        self,
        predictor: LatentPredictor | None,
        bank: PoseBank | None,
        settings: OptimizerSettings,
        nets: TrackerNets | None = None,
    ) -> None:
        self.predictor, self.bank, self.nets = predictor, bank, nets
        self.schedule = TemporalSchedule(settings.predictor_every, settings.past_window)
        self.distance: float | None = None  # how far the last frame's readings were from the bank's
        self.bank_later: tuple[tuple[str, ...], ...] = ()  # combinations between_frames prepares

    @property
    def from_bank(self) -> bool:
        """Whether the last frame's prior came from the pose bank (it then has a distance)."""
        return self.distance is not None

    def readings(self, s: OptimizerSettings, history: TrackerHistory) -> tuple | None:
        """The tracker prior's input for a frame (None: the predictor gives the prior)."""
        return history.arrays() if s.prior == "trackers" and self.bank is not None else None

    def latent(
        self, frame: int, s: OptimizerSettings, readings: tuple | None
    ) -> tuple[torch.Tensor | None, float, list[str]]:
        """The prior's latent for ``frame`` (None: none yet), its weight and warnings. The
        predictor runs only when its latent is the prior: while the bank answers, its
        runs would be thrown away; a run for later frames waits for :meth:`between_frames`."""
        self.schedule.configure(s.predictor_every, s.past_window)
        self.distance = None
        if readings is not None:
            joints, pos, rot = readings
            z, self.distance = self._bank().lookup(
                joints, pos[-LAG - 1 :], rot[-LAG - 1 :], k=s.tracker_prior_neighbours
            )
            net = self._net(s, joints)
            if net is not None:
                z = self._mix(s, torch.from_numpy(net.latents(pos[None], rot[None])[0]), z)
            return z, s.tracker_prior_weight, []
        prediction, warn = self.schedule.prediction(frame, self.predictor, max(1, s.future_window), defer=True)
        return prediction, s.temporal_weight, [warn] if warn else []

    def latent_frames(
        self, s: OptimizerSettings, joints: tuple[str, ...], pos: np.ndarray, rot: np.ndarray
    ) -> np.ndarray:
        """:meth:`latent`'s tracker latents of ``F`` frames at once, ``(F, L)``, from their
        readings ``pos (F, W, S, 3)``, ``rot (F, W, S, 4)`` (:meth:`readings` of each)."""
        net = self._net(s, joints)
        # the network row by row: a product of many rows sums in another order than one
        # frame's, and the frame-by-frame solve's stopping tests see the last bits
        guess = None if net is None else np.concatenate([net.latents(p[None], r[None]) for p, r in zip(pos, rot)])
        if guess is not None and s.tracker_prior == "network":  # the bank's latents are not needed
            return guess.astype(np.float64)
        z = self._bank().latent_frames(joints, pos[:, -LAG - 1 :], rot[:, -LAG - 1 :], k=s.tracker_prior_neighbours)
        if guess is not None:
            z = self._mix(s, torch.from_numpy(guess), z)
        return z.numpy().astype(np.float64)

    def _bank(self) -> PoseBank:
        assert self.bank is not None  # readings come only with a bank (:meth:`readings`)
        return self.bank

    def _net(self, s: OptimizerSettings, joints: tuple[str, ...]) -> TrackerNet | None:
        return self.nets.get(joints) if self.nets is not None and s.tracker_prior != "neighbours" else None

    @staticmethod
    def _mix(s: OptimizerSettings, net: torch.Tensor, bank: torch.Tensor) -> torch.Tensor:
        """The network's latent, or with ``tracker_prior = both`` its mean with the bank's."""
        return net if s.tracker_prior == "network" else 0.5 * (net + bank)

    def between_frames(self) -> None:
        """The deferred work: the bank's tables left for after the first frame, and one
        piece of the predictor's (nothing while the pose bank gives the prior)."""
        if self.bank_later and self.bank is not None:  # once, after the first frame
            later, self.bank_later = self.bank_later, ()
            self.bank.prepare(later)
        if not self.from_bank:
            self.schedule.run_pending()
