"""Declarative retarget profiles, one TOML file per source rig (see :mod:`engine.motion.retarget`).

A profile names the source joint for each canonical joint (``[joints]``; canonical joints
it lacks are left out), optional ``[landmarks]`` used to build bone frames, the unit
scale, the up and forward axes of the source's rest pose, whether rotations need a
rest-pose alignment, whether root position channels are relative to the root OFFSET and
how many leading frames to drop. Adding a rig means adding one ``.toml`` file here.

Rigs without a profile are mapped automatically (:mod:`engine.motion.rigs.automap`, with unit
and up axis from :mod:`engine.motion.rigs.infer`); a user's mapping file (``--rig-map``, the
same format with every field but ``[joints]`` optional) overrides both. See
:func:`resolve_rig` and ``docs/skeleton.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.errors import RigError, UserError
from engine.input_files import read_toml
from engine.motion.rigs.automap import automap, check_mapping
from engine.motion.rigs.infer import infer_axes, infer_units
from engine.validation import Num, check_value, shown

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
    #: The rig's zero pose stands for a T-pose although it draws the elbows bent (a
    #: converter copied T-pose rotations onto it): their bend is measured from a straight
    #: rest (retarget version 4, ``docs/skeleton.md``).
    straight_elbows: bool = False
    #: The same for the knees (retarget version 5): the zero pose stands for straight legs.
    straight_knees: bool = False
    path: str = ""
    #: Why each joint / field was chosen (automatic mappings only), for ``rig suggest``.
    reasons: dict[str, str] = field(default_factory=dict)
    #: Source joints folded into each canonical bone (automatic mappings only).
    folded: dict[str, list[str]] = field(default_factory=dict)

    def required_names(self) -> set[str]:
        """Source joint names whose presence identifies this rig."""
        names = set(self.joints.values())
        names |= {v for v in self.landmarks.values() if not v.startswith("end:")}
        return names


#: Fields of a rig profile / mapping file and what each must hold.
_TEXT_FIELDS = ("name", "description", "up", "forward")
_BOOL_FIELDS = ("align", "root_channels_relative_to_offset", "straight_elbows", "straight_knees")
_TABLE_FIELDS = ("joints", "landmarks")
_NUMBERS = {
    "units_to_m": Num(1e-6, 1e3, open_lo=True, unit="metres per file unit"),
    "skip_frames": Num(0, 1_000_000, integer=True),
}


def _read_toml(path: Path, what: str) -> dict:
    """A profile or mapping file, read through the validation layer (size, type, UTF-8,
    syntax) and its fields checked for type; errors name the file and the field."""
    data = read_toml(path, what)
    known = set(_TEXT_FIELDS) | set(_BOOL_FIELDS) | set(_TABLE_FIELDS) | set(_NUMBERS)
    unknown = sorted(set(data) - known)
    if unknown:
        raise UserError(
            f"{path}: {what}: unknown field(s) {', '.join(shown(u) for u in unknown)}; "
            f"known: {', '.join(sorted(known))}"
        )
    for key in _TEXT_FIELDS:
        if key in data and not isinstance(data[key], str):
            raise UserError(f"{path}: {what}: field {key!r} must be a string, got {shown(data[key])}")
    for key in _BOOL_FIELDS:
        if key in data and not isinstance(data[key], bool):
            raise UserError(f"{path}: {what}: field {key!r} must be true or false, got {shown(data[key])}")
    for key, spec in _NUMBERS.items():
        if key in data:
            data[key] = check_value(spec, data[key], f"{path}: {what}", key)
    for table in _TABLE_FIELDS:
        if table in data and not isinstance(data[table], dict):
            raise UserError(f'{path}: {what}: [{table}] must be a table of names (canonical = "source")')
        for k, v in data.get(table, {}).items():
            if not isinstance(v, str) or not v:
                raise UserError(
                    f"{path}: {what}: field '{table}.{k}' must be a joint name (a non-empty string), got {shown(v)}"
                )
    return data


def _parse(path: Path, data: dict | None = None) -> RigProfile:
    data = _read_toml(path, "rig profile") if data is None else data
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
            joints={str(k): str(v) for k, v in dict(data["joints"]).items()},
            landmarks=dict(data.get("landmarks", {})),
            straight_elbows=bool(data.get("straight_elbows", False)),
            straight_knees=bool(data.get("straight_knees", False)),
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
    first = ", ".join(shown(n, 24) for n in joint_names[:4])
    closest = min(profiles, key=lambda p: len(p.required_names() - present), default=None)
    hint = ""
    if closest is not None:
        missing = sorted(closest.required_names() - present)
        hint = f"; closest known rig {closest.name} lacks {', '.join(missing[:4])}{'...' if len(missing) > 4 else ''}"
    raise RigError(
        f"{source or 'BVH'}: unknown skeleton ({len(joint_names)} joints, first: {first}){hint}; "
        f"known rigs: {', '.join(p.name for p in profiles)} (see docs/bvh.md)"
    )


def resolve_rig(raw, rig_map: str | Path | None = None, profiles: list[RigProfile] | None = None) -> RigProfile:
    """The rig description for a parsed BVH (``engine.motion.bvh.RawBVH``).

    In order: the user's mapping file ``rig_map`` if given; a TOML profile of
    ``engine/motion/rigs/`` whose joints all appear in the file; otherwise an automatic
    mapping. Unit, up axis and root convention a mapping file leaves out are inferred.
    Raises :class:`RigError` (what was not found, and the file's joint names)."""
    names = list(raw.names)
    if rig_map is None:
        profiles = profiles if profiles is not None else load_profiles()
        matches = [p for p in profiles if p.required_names() <= set(names)]
        if matches:
            return max(matches, key=lambda p: len(p.required_names()))
        auto = automap(names, raw.parents, raw.offsets, raw.end_sites, raw.path)
        return _complete(
            {"name": "auto", "joints": auto.joints, "landmarks": auto.landmarks},
            raw,
            str(raw.path),
            auto.reasons,
            auto.folded,
        )
    data = _read_toml(Path(rig_map), "rig mapping")
    if "joints" not in data or not isinstance(data["joints"], dict):
        raise UserError(f"{rig_map}: rig mapping lacks a [joints] table (canonical joint = source joint)")
    check_mapping(names, raw.parents, {str(k): str(v) for k, v in data["joints"].items()}, str(rig_map))
    if "landmarks" not in data:
        auto_lm = {}
        try:
            auto_lm = automap(names, raw.parents, raw.offsets, raw.end_sites, raw.path).landmarks
        except RigError:
            pass
        data = {**data, "landmarks": auto_lm}
    return _complete({"name": "map", **data}, raw, str(rig_map), {}, {})


def _complete(data: dict, raw, path: str, reasons: dict, folded: dict) -> RigProfile:
    """Fill unit, axes and root convention a mapping leaves out, then validate it as a profile."""
    data = dict(data)
    reasons = dict(reasons)
    joints = data["joints"]
    need = {"root", "lhip", "lknee", "lankle", "rhip", "rankle", "upperneck"}
    if not need <= set(joints) and not {"units_to_m", "up", "forward"} <= set(data):
        raise RigError(
            f"{path}: cannot infer unit and up axis without {', '.join(sorted(need - set(joints)))} "
            "in [joints]; give units_to_m, up and forward"
        )
    if "units_to_m" not in data:
        data["units_to_m"], reasons["units_to_m"] = infer_units(_leg_length(raw, joints))
    if "up" not in data or "forward" not in data:
        up, fwd, rel, why = infer_axes(raw, joints)
        data.setdefault("up", up)
        data.setdefault("forward", fwd)
        data.setdefault("root_channels_relative_to_offset", rel)
        reasons["axes"] = why
    data.setdefault("align", True)
    data.setdefault("description", f"mapped {'automatically' if data['name'] == 'auto' else 'by ' + path}")
    prof = _parse(Path(path), data)
    return RigProfile(**{**prof.__dict__, "reasons": reasons, "folded": folded})


def _leg_length(raw, joints: dict[str, str]) -> float:
    """Hip-to-ankle length along the source chain (sum of OFFSET lengths), file units."""
    idx = {n: i for i, n in enumerate(raw.names)}
    j, stop = idx[joints["lankle"]], idx[joints["lhip"]]
    total = 0.0
    while j != stop and j >= 0:
        total += float(np.linalg.norm(raw.offsets[j]))
        j = raw.parents[j]
    return total
