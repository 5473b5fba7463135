"""Settings of the pose solver: one dataclass whose fields carry their own schema.

Each field of :class:`OptimizerSettings` has a :class:`Setting` in its metadata (label,
help, allowed values, whether the studio's panel shows it). Everything else is generated
from it: the checks of :meth:`OptimizerSettings.validate` (:data:`SETTINGS`), the
class's ``Attributes`` documentation, the choice lists of the command line, the
studio's optimizer panel (through ``app/schema.py``) and the settings table of
``docs/optimizer.md`` (:func:`markdown_table`). Adding a setting is one ``setting(...)``
line here.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from engine import skeleton as sk
from engine.solver.setting_schema import Setting, attributes_doc, setting, settings_of, settings_table
from engine.validation import Choice, Flag, Num, Spec, check_value

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
#: ``tracker_prior``: what turns the trackers into the prior's latent (``prior = trackers``).
TRACKER_PRIORS = ("network", "neighbours", "both")
#: Connected sensors from which ``auto`` uses Adam (and the predictor looks one step ahead).
FULL_SET = 6


def _int(lo: int, hi: int) -> Num:
    return Num(lo, hi, integer=True)


_ANCHORS = Choice(("none", *sk.JOINT_NAMES), summary="a joint name or 'none'")


@dataclass
class OptimizerSettings:
    """Parameters of the pose optimizer; a change applies from the next frame.

    Checked on construction (:meth:`validate`); the fields are listed below, generated
    from their metadata.
    """

    mode: str = setting(
        "realtime",
        "Mode",
        "realtime: a fixed number of iterations per frame; offline: "
        "until the tolerances are met (at most max_iterations).",
        Choice(MODES),
        panel=True,
    )
    iterations: int = setting(
        10, "Iterations / frame", "Steps per frame in realtime mode.", _int(1, 10_000), panel=True, step=1
    )
    max_iterations: int = setting(
        100, "Max iterations", "Cap on steps per frame in offline mode (and on frame 0).", _int(1, 100_000)
    )
    optimizer: str = setting(
        "auto",
        "Latent update",
        "sgd: plain gradient steps of step_size (the paper's "
        "update); adam: restarted every frame; adam-carry: moments kept across frames; "
        "auto: adam-carry with six or more connected sensors, sgd with fewer (Adam moves "
        "every latent dimension by about lr per step, so with few trackers the "
        "unconstrained body parts wander).",
        Choice(OPTIMIZERS),
        panel=True,
    )
    lr: float = setting(
        0.05,
        "Adam learning rate",
        "Adam's learning rate (latent units per step, roughly).",
        Num(0, 10, open_lo=True),
        panel=True,
        step=0.005,
    )
    step_size: float = setting(
        0.3,
        "Gradient step size",
        "Step of the sgd rule: z -= step_size * gradient.",
        Num(0, 100, open_lo=True),
        panel=True,
        step=0.05,
    )
    momentum: float = setting(
        0.0, "Momentum", "Nesterov momentum of the sgd rule within a frame (0 = none).", Num(0, 0.999)
    )
    temporal_weight: float = setting(
        0.01,
        "Temporal prior weight",
        "Weight of the temporal prior (mean squared latent distance to the prior's latent).",
        Num(0, 1e6),
        panel=True,
        step=0.1,
    )
    prior: str = setting(
        "predictor",
        "Prior from (sparse sets: trackers)",
        "predictor: the temporal prior's "
        "latent is the temporal predictor's (the paper); trackers: the pose bank's latent for "
        "this frame's tracker readings (engine/solver/tracker_prior.py), while hips or head "
        "are connected and a pose bank is loaded, else the predictor's.",
        Choice(PRIORS),
        panel=True,
    )
    tracker_prior: str = setting(
        "both",
        "Tracker prior from",
        "both: the mean of the tracker network's latent (the trackers' last half second, "
        "engine/solver/tracker_net.py) and the pose bank's; network: the network's alone; "
        "neighbours: the mean latent of the pose bank's nearest training frames alone. Where no "
        "network is shipped for the connected trackers, the bank's.",
        Choice(TRACKER_PRIORS),
        panel=True,
    )
    tracker_prior_weight: float = setting(
        1.0,
        "Tracker prior weight",
        "Weight of the temporal prior while its latent comes from the trackers.",
        Num(0, 1e6),
        panel=True,
        step=0.1,
    )
    tracker_prior_neighbours: int = setting(
        24,
        "Tracker prior neighbours",
        "Training frames whose latents the "
        "tracker prior averages (0 = the pose bank's own count, 8 for the "
        "shipped bank).",
        _int(0, 4096),
    )
    root_anchor: str = setting(
        "upperneck",
        "Root anchor (no hip tracker)",
        "Without a connected hip tracker, "
        "the joint whose tracker places the body, or none to integrate the decoded root "
        "displacement (drifts: tens of centimetres over a clip with head and hands).",
        _ANCHORS,
        panel=True,
        offered=("upperneck", "none"),
    )
    sensor_blend: float = setting(
        0.0,
        "Sensor blend-in",
        "Time over which a tracker that reconnects is blended "
        "in (engine/methods/sensor_blend.py); one that disconnects ends at once; 0 = "
        "the target jumps. The hips and root_anchor trackers are never blended.",
        Num(0, 1e6, unit="s"),
        panel=True,
        step=0.1,
    )
    position_tolerance: float = setting(
        0.01,
        "Position tolerance",
        "Offline: a sensor is satisfied when its position error is below this.",
        Num(0, 10, unit="m"),
    )
    rotation_tolerance: float = setting(
        5.0, "Rotation tolerance", "Offline: the same for the rotation of a 6-DoF sensor.", Num(0, 180, unit="degrees")
    )
    sensor_rotation_weight: float = setting(
        0.1,
        "Sensor rotation weight",
        "Weight of a sensor's rotation term (sin^2(angle/2)) against its squared position error (m^2).",
        Num(0, 1e6),
    )
    init_from_prediction: bool = setting(
        False,
        "Start from the prediction",
        "Start each frame from the "
        "predictor's latent when there is one (default: from the previous "
        "frame's, as the paper's Algorithm 1; the shipped predictor's latent "
        "measured 5-18 cm worse as a start).",
        Flag(),
    )
    future_window: int = setting(
        0,
        "Future window",
        "Predictor steps per run (W_f); 0 = 1 with six or more connected sensors, 16 with fewer.",
        _int(0, 256),
    )
    past_window: int = setting(16, "Past window", "Past latents the predictor sees (W_p).", _int(1, 1024))
    predictor_every: int = setting(
        4, "Predictor every", "The predictor runs every this many frames (n).", _int(1, 10_000)
    )
    patience: int = setting(
        10,
        "Patience",
        "Offline: stop after this many steps without a relative improvement of min_improvement in the total loss.",
        _int(1, 100_000),
    )
    min_improvement: float = setting(
        1e-4, "Minimum improvement", "Offline: relative improvement that counts as progress.", Num(0, 1)
    )
    divergence_factor: float = setting(
        100.0,
        "Divergence factor",
        "A final loss above this times the "
        "starting loss (plus 1e-6) counts as divergence; the frame falls back to "
        "its starting latent.",
        Num(1, 1e12),
    )
    threads: int = setting(
        1,
        "Threads",
        "Torch intra-op threads while solving (0 = leave torch's setting); "
        "the tensors are tiny, so one thread is fastest.",
        _int(0, 64),
    )
    smooth_weight: float = setting(
        0.0,
        "Smoothing weight",
        "Weight of the smooth term: every joint's squared "
        "deviation (m^2, mean over joints) from the constant-velocity extrapolation "
        "of the previous two solved poses.",
        Num(0, 1e6),
    )
    ground_weight: float = setting(
        0.0,
        "Ground weight",
        "Weight of the ground term (the lower ankle 5-14 cm above the floor) while no foot tracker is connected.",
        Num(0, 1e6),
    )
    gait_weight: float = setting(
        0.0,
        "Gait weight",
        "Weight of the gait term while no foot tracker is "
        "connected: when the hips or head travel faster than 0.35 m/s, the stance ankle "
        "stays planted and the swing ankle moves to a landing spot ahead of its hip "
        "(engine/solver/gait.py), the standing foot named by the stance classifier; off at a run "
        "(above 2.2 m/s) and at 0. The head profile (no hip tracker) sets 3, the others 0 "
        "(docs/optimizer.md, 'Legs that step').",
        Num(0, 1e6),
    )
    stand_weight: float = setting(
        0.0,
        "Standing-legs weight",
        "Weight of the standing-legs pull while no foot tracker is connected: while the hips "
        "or head travel slower than 0.6 m/s (fading out by 1.2 m/s) each ankle is pulled "
        "horizontally under its hip joint, the way a standing performer's legs hang, where the "
        "pose bank holds no motion like the trackers' (engine/solver/gait.py). The hip "
        "profiles set 3, the others 0: without a hip "
        "tracker the pull moves the guessed pelvis instead (docs/optimizer.md, 'Standing legs').",
        Num(0, 1e6),
    )
    tuning: str = setting(
        "preset",
        "Tuning",
        "preset: the settings of engine/solver/profiles.py TUNED that were "
        "not set explicitly take the connected sensor set's profile values; off: the values "
        "here are used as they are.",
        Choice(TUNINGS),
    )
    sensor_rotations: bool = setting(
        True,
        "Tracker rotations",
        "After each solve, every joint with a connected "
        "6-DoF tracker other than the hips takes exactly the tracker's world "
        "rotation (positions unchanged; toes follow the foot).",
        Flag(),
    )
    neck_twist_share: float = setting(
        0.5,
        "Neck twist share",
        "With a 6-DoF head tracker and sensor_rotations, "
        "the share of the head's twist correction about the neck that turns the "
        "lower neck; the head takes the rest (0 = all in the head).",
        Num(0, 1),
    )
    reach: bool = setting(
        True,
        "Reach",
        "After each solve, put every tracked wrist and ankle exactly on its "
        "tracker by its limb's two bones (the decoder alone leaves them 1-2 cm off).",
        Flag(),
    )
    shoulder_reach: float = setting(
        20.0,
        "Shoulder reach",
        "With reach, when a wrist's tracker is beyond the straight arm, "
        "the clavicle turns the shoulder towards it by at most this many degrees first "
        "(0 = never): the arm alone leaves such a wrist short of its tracker.",
        Num(0, 45, unit="degrees"),
        step=5.0,
    )
    level_feet: bool = setting(
        False,
        "Level feet",
        "After each solve, an ankle whose tracker gives its position "
        "only (3-DoF) takes the pelvis's heading, without pitch or roll, as IK keeps it "
        "(the decoder's foot orientation misses other performers' feet).",
        Flag(),
    )
    head_reach: bool = setting(
        False,
        "Head reach",
        "After each solve, with a hip tracker, turn the spine so the "
        "head points at its tracker (before reach: the arms follow the chest).",
        Flag(),
    )
    heading: str = setting(
        "anchor",
        "Heading",
        "Without a hip tracker, what the decoded root rotation is "
        "relative to: previous (the previous solved root's heading, integrated) or anchor "
        "(the root_anchor joint's 6-DoF tracker heading, so nothing accumulates).",
        Choice(HEADINGS),
    )
    body_heading_follow: float = setting(
        0.05,
        "Body heading follow",
        "With a hip tracker that gives no rotation, the reference heading turns towards "
        "the heading network's body facing with this time constant (within the "
        "45-degree bound either way); 0 = bounded only.",
        Num(0, 10, unit="seconds"),
    )
    lines_heading_follow: float = setting(
        0.25,
        "Lines heading follow",
        "The same while the facing is read off the feet's and hands' left-right lines "
        "(heading network off, or a tracker it reads lost): they swing with every stride, "
        "so they are followed more slowly; 0 = bounded only.",
        Num(0, 10, unit="seconds"),
    )
    heading_network: bool = setting(
        True,
        "Heading network",
        "With a hip tracker that gives no rotation and 3-DoF trackers on the hips, head, "
        "hands and feet, the body facing comes from the heading network "
        "(assets/models/heading.npz), which reads their last half second, instead of the "
        "feet's and hands' left-right lines.",
        Flag(),
        panel=True,
    )
    hands_heading_limit: float = setting(
        10.0,
        "Hands heading limit",
        "With heading = anchor and no hip tracker, "
        "the reference heading is kept within this of the facing read off the "
        "head tracker and the hands' left-right line; 180 = off.",
        Num(0, 180, unit="degrees"),
    )

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Check and convert every field against its :class:`Setting`; raise
        :class:`~engine.validation.ValidationError` (one line naming the first bad field
        and its range) otherwise."""
        for name, spec in SETTINGS.items():
            setattr(self, name, check_value(spec, getattr(self, name), "optimizer settings", name))

    def steps_cap(self) -> int:
        return self.iterations if self.mode == "realtime" else self.max_iterations


def fields(cls: type = OptimizerSettings) -> Iterator[tuple[dataclasses.Field, Setting]]:
    """Every field of :class:`OptimizerSettings` (or another settings dataclass ``cls``)
    with its :class:`Setting`, in order (:func:`engine.solver.setting_schema.settings_of`)."""
    return settings_of(cls)


#: The settings' validation schema, by field (from the fields' metadata).
SETTINGS: Mapping[str, Spec] = {f.name: info.spec for f, info in fields()}


def choices() -> dict[str, tuple[str, ...]]:
    """Every choice setting -> the values it takes."""
    return {f.name: info.spec.options for f, info in fields() if isinstance(info.spec, Choice)}


def markdown_table() -> str:
    """The settings table of ``docs/optimizer.md`` (name, default, allowed, meaning)."""
    return settings_table(OptimizerSettings)


OptimizerSettings.__doc__ = (OptimizerSettings.__doc__ or "") + attributes_doc(OptimizerSettings)
