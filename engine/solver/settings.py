"""Settings of the pose solver (one dataclass; validated; a change applies from the next frame)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.validation import SETTINGS, check_fields

MODES = ("realtime", "offline")
#: Latent update rules: plain gradient steps (DragPoser eq. in sec. 4.4), Adam restarted every
#: frame, or Adam whose moment estimates carry over from frame to frame.
OPTIMIZERS = ("auto", "sgd", "adam", "adam-carry")
#: ``tuning``: per-sensor-set profiles (engine/solver/profiles.py) or the values as set.
TUNINGS = ("preset", "off")
#: ``heading``: what the decoded root rotation is relative to without a hip tracker.
HEADINGS = ("previous", "anchor")
#: ``prior``: where the temporal prior's latent comes from (engine/solver/tracker_prior.py).
PRIORS = ("predictor", "trackers")
#: Connected sensors from which ``auto`` uses Adam (and the predictor looks one step ahead).
FULL_SET = 6


@dataclass
class OptimizerSettings:
    """Parameters of the pose optimizer; a change applies from the next frame.

    Attributes
    ----------
    mode : str
        ``realtime`` (fixed ``iterations``) or ``offline`` (until tolerances are met).
    iterations : int
        Adam steps per frame in realtime mode.
    max_iterations : int
        Cap on Adam steps per frame in offline mode.
    lr : float
        Adam learning rate (latent units per step, roughly).
    optimizer : str
        Latent update rule: ``sgd`` (plain gradient steps of ``step_size``, the paper's
        update), ``adam`` (restarted every frame), ``adam-carry`` (moments kept across
        frames) or ``auto``: ``adam-carry`` with six or more connected sensors, plain
        steps with fewer (Adam moves every latent dimension by about ``lr`` per step, so
        with few trackers the unconstrained body parts wander; see docs/optimizer.md).
    step_size : float
        Step of the ``sgd`` rule: ``z -= step_size * gradient``.
    momentum : float
        Nesterov momentum of the ``sgd`` rule within a frame (0 = none).
    position_tolerance : float
        Metres; a sensor is satisfied when its position error is below it (offline).
    rotation_tolerance : float
        Degrees; same for the rotation of a 6-DoF sensor.
    sensor_rotation_weight : float
        Weight of a sensor's rotation term (``sin^2(angle/2)``) against its squared
        position error (m^2).
    temporal_weight : float
        Weight of the temporal prior (MSE to the predictor's latent).
    prior : str
        ``predictor``: the temporal prior's latent is the temporal predictor's (the
        paper); ``trackers``: the latent of the training poses whose trackers look like
        this frame's (:mod:`engine.solver.tracker_prior`; beyond the paper), while the
        connected trackers include hips or head and a pose bank is loaded, else the
        predictor's. The ``hip`` and ``head`` profiles use ``trackers``.
    tracker_prior_weight : float
        Weight of the temporal prior while its latent comes from the trackers.
    tracker_prior_neighbours : int
        Training frames whose latents the tracker prior averages (0 = the pose bank's own
        count, 8 for the shipped bank). 24 measured smoother than 8 on every sparse set
        with about the same positions (docs/optimizer.md).
    init_from_prediction : bool
        Start each frame from the predictor's latent when there is one. Off by default:
        Algorithm 1 starts from the previous frame's latent and uses the prediction only
        through the temporal prior, and with the shipped predictor starting from its
        latent measured 5-18 cm worse (6 sensors, realtime, two validation clips).
    future_window : int
        Predictor steps per run (W_f); 0 picks DragPoser's defaults: 1 with six or more
        connected sensors, 16 with fewer.
    past_window : int
        Past latents the predictor sees (W_p).
    predictor_every : int
        The predictor runs every this many frames (n).
    patience : int
        Offline: stop after this many steps without a relative improvement of
        ``min_improvement`` in the total loss.
    min_improvement : float
        Relative improvement that counts as progress (offline).
    divergence_factor : float
        A final loss above ``divergence_factor`` times the starting loss (plus 1e-6)
        counts as divergence; the frame falls back to its starting latent.
    root_anchor : str
        Without a connected hip tracker, the joint whose tracker places the body
        (``upperneck``, the head, by default; any joint name), or ``none`` to integrate
        the decoded root displacement from frame to frame (drifts without a hip tracker:
        tens of centimetres over a clip with head and hands only).
    sensor_blend : float
        Seconds over which a tracker that reconnects is blended in
        (``engine/methods/sensor_blend.py``); one that disconnects ends at once; 0 = the
        target jumps. Trackers that place the body (hips, ``root_anchor``) are never
        blended.
    smooth_weight : float
        Weight of the ``smooth`` term: every joint's squared deviation (m^2, mean over
        joints) from the constant-velocity extrapolation of the previous two solved
        poses; it damps frame-to-frame jitter without holding steady motion back.
    ground_weight : float
        Weight of the ``ground`` term (the lower ankle 5-14 cm above the floor at z = 0)
        while no foot tracker is connected; it makes the legs reach the floor below
        tracked hips or head.
    tuning : str
        ``preset``: the settings in :data:`engine.solver.profiles.TUNED` that were not
        set explicitly take the values of the connected sensor set's profile
        (``engine/solver/profiles.py``); ``off``: the values here are used as they are.
    sensor_rotations : bool
        After each solve, give every joint with a connected 6-DoF tracker (other than the
        hips, which are always the tracker's) exactly the tracker's world rotation, by
        setting its local rotation from its solved parent (DragPoser's joint adjustment,
        applied to the head, hands and feet). Positions of those joints are unchanged;
        their children (toes) follow the foot.
    neck_twist_share : float
        In [0, 1]. With a 6-DoF head tracker and ``sensor_rotations``, the part of the
        head's rotation correction that is a twist about the neck is split: this share
        turns the lower neck about the neck bone (no joint moves) and the head takes the
        rest (``engine.solver.limb_ik.share_neck_twist``); 0 = all of it in the head.
    reach : bool
        After each solve, put every tracked wrist and ankle exactly on its tracker by its
        limb's two bones (``engine/solver/limb_ik.py``): the decoder alone leaves them
        1-2 cm off in realtime.
    heading : str
        Without a hip tracker, the frame the decoded root rotation is relative to:
        ``previous`` (the previous solved root's heading, integrated from frame to
        frame) or ``anchor`` (the heading of the ``root_anchor`` joint's 6-DoF tracker
        when there is one, so nothing accumulates; see docs/optimizer.md). With a hip
        tracker that gives no rotation (3-DoF), ``anchor`` also keeps the reference within
        45 degrees of the heading of the feet and hands trackers' left-right line, and the
        first frame faces that way.
    hands_heading_limit : float
        Degrees. With ``heading = anchor`` and no hip tracker, the reference heading is
        also kept within this many degrees of the body's facing read off the head tracker
        and the hands' left-right line (:func:`engine.solver.pose.head_hands_facing`): the
        head's heading alone let the pelvis turn about 90 degrees away from the body
        (docs/optimizer.md, "Stability with head and hands"). 180 = off.
    threads : int
        Torch intra-op threads while solving (0 = leave torch's setting). The tensors
        are tiny, so one thread is fastest; on a busy 2-core machine, torch's default
        made a frame with the real-size VAE about 20x slower in our measurements.
    """

    mode: str = "realtime"
    iterations: int = 10
    max_iterations: int = 100
    lr: float = 0.05
    position_tolerance: float = 0.01
    rotation_tolerance: float = 5.0
    sensor_rotation_weight: float = 0.1
    temporal_weight: float = 0.01
    init_from_prediction: bool = False
    future_window: int = 0
    past_window: int = 16
    predictor_every: int = 4
    patience: int = 10
    min_improvement: float = 1e-4
    divergence_factor: float = 100.0
    root_anchor: str = "upperneck"
    optimizer: str = "auto"
    step_size: float = 0.3
    momentum: float = 0.0
    threads: int = 1
    sensor_blend: float = 0.0
    smooth_weight: float = 0.0
    ground_weight: float = 0.0
    tuning: str = "preset"
    sensor_rotations: bool = True
    neck_twist_share: float = 0.5
    reach: bool = True
    heading: str = "anchor"
    hands_heading_limit: float = 10.0
    prior: str = "predictor"
    tracker_prior_weight: float = 1.0
    tracker_prior_neighbours: int = 24

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise :class:`UserError` naming the first bad field."""
        if self.mode not in MODES:
            raise UserError(f"optimizer setting 'mode' must be one of {', '.join(MODES)}, got {self.mode!r}")
        ints = ("iterations", "max_iterations", "future_window", "past_window", "predictor_every", "patience",
                "threads", "tracker_prior_neighbours")
        zero_ok = ("future_window", "threads", "tracker_prior_neighbours")
        for name in ints:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < (0 if name in zero_ok else 1):
                raise UserError(f"optimizer setting {name!r} must be a positive integer, got {v!r}")
            setattr(self, name, int(v))
        floats = ("lr", "position_tolerance", "rotation_tolerance", "sensor_rotation_weight", "temporal_weight",
                  "min_improvement", "divergence_factor", "momentum", "step_size", "sensor_blend",
                  "smooth_weight", "ground_weight", "tracker_prior_weight", "hands_heading_limit", "neck_twist_share")  # fmt: skip
        for name in floats:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise UserError(f"optimizer setting {name!r} must be a finite number >= 0, got {v!r}")
            setattr(self, name, float(v))
        if self.optimizer not in OPTIMIZERS:
            raise UserError(f"optimizer setting 'optimizer' must be one of {', '.join(OPTIMIZERS)}, got {self.optimizer!r}")
        if self.tuning not in TUNINGS:
            raise UserError(f"optimizer setting 'tuning' must be one of {', '.join(TUNINGS)}, got {self.tuning!r}")
        if self.prior not in PRIORS:
            raise UserError(f"optimizer setting 'prior' must be one of {', '.join(PRIORS)}, got {self.prior!r}")
        if self.heading not in HEADINGS:
            raise UserError(f"optimizer setting 'heading' must be one of {', '.join(HEADINGS)}, got {self.heading!r}")
        for name in ("sensor_rotations", "reach"):
            if not isinstance(getattr(self, name), bool):
                raise UserError(f"optimizer setting {name!r} must be true or false, got {getattr(self, name)!r}")
        if self.root_anchor != "none" and self.root_anchor not in sk.JOINT_INDEX:
            raise UserError(f"optimizer setting 'root_anchor' must be a joint name or 'none', got {self.root_anchor!r}")
        if self.momentum >= 1:
            raise UserError(f"optimizer setting 'momentum' must be below 1, got {self.momentum!r}")
        if self.lr <= 0:
            raise UserError("optimizer setting 'lr' must be > 0")
        if self.step_size <= 0:
            raise UserError("optimizer setting 'step_size' must be > 0")
        check_fields(SETTINGS, vars(self), "optimizer settings")  # ranges (engine/validation.py)

    def steps_cap(self) -> int:
        return self.iterations if self.mode == "realtime" else self.max_iterations
