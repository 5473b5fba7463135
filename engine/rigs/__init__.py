"""Declarative retarget profiles, one TOML file per source rig (see :mod:`engine.retarget`).

A profile names the source joint for each canonical joint (``[joints]``; canonical joints
it lacks are left out), optional ``[landmarks]`` used to build bone frames, the unit
scale, the up and forward axes of the source's rest pose, whether rotations need a
rest-pose alignment, whether root position channels are relative to the root OFFSET and
how many leading frames to drop. Adding a rig means adding one ``.toml`` file here.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from engine import skeleton as sk
from engine.errors import RigError, UserError

PROFILE_DIR = Path(__file__).resolve().parent
LANDMARKS = ("l_toe_tip", "r_toe_tip", "l_eye", "r_eye", "l_index", "l_pinky", "r_index", "r_pinky")
_AXES = {"+x", "-x", "+y", "-y", "+z", "-z"}


@dataclass(frozen=True)
class RigProfile:
    name: str
    description: str
    units_to_m: float
    up: str
    forward: str
    align: bool
    root_channels_relative_to_offset: bool
    skip_frames: int
    joints: dict[str, str]
    landmarks: dict[str, str] = field(default_factory=dict)
    path: str = ""

    def required_names(self) -> set[str]:
        """Source joint names whose presence identifies this rig."""
        names = set(self.joints.values())
        names |= {v for v in self.landmarks.values() if not v.startswith("end:")}
        return names


def _parse(path: Path) -> RigProfile:
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise UserError(f"{path}: cannot read rig profile: {exc}") from exc
    try:
        prof = RigProfile(
            name=str(data["name"]),
            description=str(data.get("description", "")),
            units_to_m=float(data["units_to_m"]),
            up=str(data["up"]),
            forward=str(data["forward"]),
            align=bool(data["align"]),
            root_channels_relative_to_offset=bool(data.get("root_channels_relative_to_offset", False)),
            skip_frames=int(data.get("skip_frames", 0)),
            joints=dict(data["joints"]),
            landmarks=dict(data.get("landmarks", {})),
            path=str(path),
        )
    except KeyError as exc:
        raise UserError(f"{path}: rig profile lacks the field {exc.args[0]!r}") from exc
    for key in ("up", "forward"):
        if getattr(prof, key) not in _AXES:
            raise UserError(f"{path}: field {key!r} must be one of {sorted(_AXES)}")
    if prof.up[1] == prof.forward[1]:
        raise UserError(f"{path}: 'up' and 'forward' must be different axes")
    unknown = set(prof.joints) - set(sk.JOINT_NAMES)
    if unknown:
        raise UserError(f"{path}: [joints] has non-canonical names {sorted(unknown)}")
    if "root" not in prof.joints:
        raise UserError(f"{path}: [joints] must map the canonical 'root'")
    bad = set(prof.landmarks) - set(LANDMARKS)
    if bad:
        raise UserError(f"{path}: unknown landmarks {sorted(bad)}; known: {', '.join(LANDMARKS)}")
    return prof


def load_profiles(directory: Path = PROFILE_DIR) -> list[RigProfile]:
    """All profiles in ``directory``, sorted by name."""
    return sorted((_parse(p) for p in directory.glob("*.toml")), key=lambda p: p.name)


def detect_rig(joint_names: list[str], source: str = "", profiles: list[RigProfile] | None = None) -> RigProfile:
    """The profile whose joints (and landmarks) all appear in ``joint_names``.

    When several match, the one using the most source joints wins. Raises
    :class:`RigError` listing what each known rig expects when none matches."""
    profiles = profiles if profiles is not None else load_profiles()
    present = set(joint_names)
    matches = [p for p in profiles if p.required_names() <= present]
    if matches:
        return max(matches, key=lambda p: len(p.required_names()))
    lines = [f"{source or 'BVH'}: unknown skeleton ({len(joint_names)} joints, first: "
             f"{', '.join(joint_names[:6])}). Known rigs and the joints they need:"]
    for p in profiles:
        missing = sorted(p.required_names() - present)
        lines.append(f"  - {p.name} ({p.description}): needs {', '.join(sorted(p.required_names())[:8])}..."
                     f" (missing here: {', '.join(missing[:6])}{'...' if len(missing) > 6 else ''})")
    lines.append("Add a profile to engine/rigs/ to support a new rig.")
    raise RigError("\n".join(lines))
