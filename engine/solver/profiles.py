"""Per-sensor-set solver settings (DragPoser sec. 4.3: the future window grows with the
ambiguity of the sensor set; we tune the temporal weight, step sizes and smoothing too).

Which profile a frame uses depends on its *connected* trackers, so a lost tracker
switches the profile for as long as it is lost:

=========  ==============================================  ==================================
profile    connected trackers                              presets
=========  ==============================================  ==================================
``full``   6-DoF hips and at least :data:`FULL_SET` in all  ``6``
``full3``  3-DoF hips and at least :data:`FULL_SET` in all  ``6x3dof``
``hip``    hips, fewer in total                            ``4``, ``3-hip-hands``, ``5-paper``
``head``   no hips                                         ``3-head-hands``, ``5``
=========  ==============================================  ==================================

A profile only supplies the values of the settings the user left alone
(:meth:`engine.methods.dragposer_edits.FrameSettings.configure` records what was set);
``tuning = "off"`` disables profiles altogether. The values were chosen on the
validation files only; the sweeps are in ``docs/optimizer.md``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

from engine.solver.settings import FULL_SET, OptimizerSettings
from engine.solver.settings_edit import check_values

#: Settings a profile may supply (each profile gives all of them; a value it leaves out is
#: the :class:`OptimizerSettings` default).
TUNED = (
    "future_window",
    "temporal_weight",
    "step_size",
    "lr",
    "smooth_weight",
    "ground_weight",
    "sensor_rotation_weight",
    "prior",
    "tracker_prior_weight",
    "head_reach",
    "level_feet",
    "gait_weight",
    "stand_weight",
)


@dataclass(frozen=True)
class Profile:
    """The values a sensor set gives the :data:`TUNED` settings (checked against the
    settings' schema when the profile is made, so a misspelt name fails at import)."""

    name: str
    given: Mapping[str, Any]

    def __post_init__(self) -> None:
        stray = sorted(set(self.given) - set(TUNED))
        if stray:
            raise ValueError(f"profile {self.name!r}: {', '.join(stray)} not in TUNED")
        given, defaults = check_values(self.given, f"profile {self.name!r}"), OptimizerSettings()
        object.__setattr__(self, "given", {k: given.get(k, getattr(defaults, k)) for k in TUNED})

    def values(self) -> dict[str, Any]:
        """Every :data:`TUNED` setting's value in this profile."""
        return dict(self.given)


#: What the sparse sets' profiles (``hip``, ``head``) share. Smoothing 5: jitter 20.4 / 20.7 /
#: 19.7 -> 18.2 / 18.5 / 16.4 (truth 13.0) for presets 4 / 3-hip-hands / 3-head-hands, Pos
#: 4.99 / 5.02 / 7.67 -> 4.97 / 5.03 / 7.71 cm; 10 and 20 smooth more but cost velocity
#: error (docs/optimizer.md)
SPARSE = dict(future_window=16, smooth_weight=5.0, ground_weight=10.0, sensor_rotation_weight=0.1, prior="trackers")

PROFILES: dict[str, Profile] = {
    # hand and foot rotation weight 0.01: heavier pulls the arms' twist (the decoder turns
    # the upper arm to meet a hand's rotation that its wrist cannot), lighter loses the
    # forearm's; 9 validation files, 150 frames, Rot deg for 0.003 / 0.01 / 0.02 / 0.03:
    # 10.31 / 10.15 / 10.43 / 12.46 (docs/optimizer.md). The pose bank's latent as the
    # prior, weight 0.05: 1.18 cm / 10.15 deg -> 0.89 / 7.39; 0.03 0.89 / 7.56, 0.1 0.96 /
    # 7.41, 0.3 1.18 / 7.67 (heavier pulls the hands off their trackers). The head reached by
    # the spine (limb_ik.reach_head_local), realtime, Pos cm / Rot deg / Vel cm/s: 9 validation
    # files (150 frames) 0.82 / 7.14 / 10.2 -> 0.75 / 7.12 / 7.6; hdm05/ (whole) 1.49 / 13.4 /
    # 10.3 -> 1.30 / 13.4 / 8.8; dragposer/ (whole) 2.06 / 14.86 / 21.0 -> 1.97 / 14.91 / 18.2
    "full": Profile(
        "full",
        dict(
            future_window=1,
            smooth_weight=5.0,
            sensor_rotation_weight=0.01,
            prior="trackers",
            tracker_prior_weight=0.05,
            head_reach=True,
        ),
    ),
    # positions only: the smoothing term made 6x3dof worse (3 validation files, 150
    # frames: 3.97 -> 3.69 cm, 30.5 -> 28.2 deg without it), and without rotations the
    # predictor's longer look-ahead helps (retarget 3, 9 validation files: 4.06 -> 3.59 cm,
    # 21.9 -> 18.8 deg; docs/optimizer.md)
    # the head reached by the spine too: 6x3dof realtime, Pos / Rot / Vel, 9 validation files
    # (150 frames) 3.44 / 17.7 / 17.3 -> 3.39 / 17.7 / 14.9; hdm05/ (22 clips, whole) 5.84 /
    # 27.3 / 25.9 -> 5.29 / 27.8 / 22.7; dragposer/ (whole) 4.12 / 23.0 / 37.3 -> 3.98 / 22.8 /
    # 34.3 (docs/accuracy.md, "Other labs' performers")
    # the 3-DoF feet level along the pelvis heading (IK's rule): 6x3dof realtime, Pos / Rot,
    # hdm05/ 5.29 / 27.8 -> 5.02 / 27.4, dragposer/ 3.98 / 22.8 -> 3.79 / 22.7, 9 validation
    # files 3.39 / 17.7 -> 3.34 / 18.2 (docs/accuracy.md, "What the remaining `dragposer/`
    # gaps are made of")
    "full3": Profile(
        "full3",
        dict(
            future_window=16,
            temporal_weight=0.03,
            sensor_rotation_weight=0.03,
            head_reach=True,
            level_feet=True,
        ),
    ),
    # the spine turned so the head meets its tracker after the solve (limb_ik.reach_head_local):
    # preset 4, whole clips: hdm05/ 7.78 -> 6.91 cm, dragposer/ 7.66 -> 6.66, validation files
    # (300 frames) 5.31 -> 4.69 (docs/accuracy.md, "Other labs' performers: the head, not the legs")
    "hip": Profile("hip", {**SPARSE, "head_reach": True, "stand_weight": 3.0}),
    # gait: the stance classifier's planted feet (docs/optimizer.md, "Legs that step"): 3-head-hands,
    # realtime, Pos cm, validation files (600 frames) 6.640 -> 6.605, hdm05/ 12.144 -> 12.122,
    # dragposer/ 7.419 -> 7.378; the six walks' skating 79 -> 52 cm/s. With the hips tracked
    # (preset 4) the bank's legs are better: +1.0 to +1.7 %, so the hip profiles leave it off.
    "head": Profile("head", {**SPARSE, "gait_weight": 3.0}),
}


def profile_for(connected: Collection[str], hip_rotation: bool = True) -> Profile:
    """The profile of a frame whose connected trackers sit on the joints ``connected``
    (``hip_rotation``: the hip tracker, if any, gives its rotation)."""
    if "root" in connected:
        if len(connected) >= FULL_SET:
            return PROFILES["full" if hip_rotation else "full3"]
        return PROFILES["hip"]
    return PROFILES["head"]


def effective(
    settings: OptimizerSettings, connected: Collection[str], explicit: Collection[str], hip_rotation: bool = True
) -> OptimizerSettings:
    """``settings`` with the profile's values for the tuned fields not in ``explicit``
    (a new object; ``settings`` itself is unchanged). With ``tuning == "off"`` it is
    ``settings`` itself."""
    if settings.tuning == "off":
        return settings
    values = {k: v for k, v in profile_for(connected, hip_rotation).values().items() if k not in explicit}
    return dataclasses.replace(settings, **values) if values else settings
