"""Automatic mapping of a humanoid BVH rig onto the 22 canonical joints.

Names alone are ambiguous across rigs (``LeftShoulder`` is a clavicle in Mixamo and
CMU, ``left_shoulder`` is the upper arm in SMPL; ``left_foot`` is SMPL's toe), so the
mapper finds a few *anchors* by name and reads the rest off the hierarchy:

1. Every joint name is split into a **side** (``Left``/``Right`` prefixes or suffixes,
   ``L_``/``_L``/``.L``/``l``+capital as in Daz's ``lThigh``; namespaces such as
   ``mixamorig:`` are dropped) and a lower-case **core**.
2. Anchors by core name, per side: the ankle (core ending in ``foot`` or ``ankle``,
   the one nearest the root), the wrist (``hand``/``wrist``), and the head
   (``head``, not ``headtop``/``head_end``). Twist, roll and "share" helper bones
   are never anchors.
3. Chains are walked up from the anchors, skipping helper bones and joints that sit
   on their parent (zero OFFSET): ankle -> knee -> hip for the legs; wrist -> elbow ->
   shoulder -> clavicle for the arms. The chest is the common ancestor of both
   clavicles, the root (pelvis) the common ancestor of both hips and the head.
   Joints between them in a chain (``LHipJoint``, ``lButtock``, ``CC_Base_Pelvis``,
   a second neck bone) are *folded*: they belong to the bone that spans them.
4. The spine between root and chest gives ``lowerback`` (first joint) and
   ``upperback`` (the joint nearest 70 % of the way from lowerback to chest, the
   canonical proportion); the first joint after the chest towards the head is
   ``lowerneck``. The toe is the ankle's child in the foot chain.

Each choice is recorded with its reason (``rig suggest`` writes them next to the
mapping). A mapped joint always descends from its mapped parent; anything that breaks
that is reported as an error naming the joints. The unit and the up axis are inferred
by :mod:`engine.motion.rigs.infer`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from engine import skeleton as sk
from engine.errors import RigError

_HELPER = re.compile(r"twist|roll|share|helper|nub|end$|top|dummy|^ik|pole|target", re.IGNORECASE)
_FINGER = re.compile(r"thumb|index|middle|mid\d|ring|pinky|little|finger|carpal|palm", re.IGNORECASE)
# all-lower-case names with a one-letter side prefix (``lhip``, ``rankle``)
_LOWER_SIDE = re.compile(
    r"^([lr])(?=(hip|knee|ankle|foot|toe|thigh|shin|leg|upleg|clavicle|collar|shoulder|shldr|"
    r"arm|upperarm|forearm|elbow|wrist|hand)$)"
)
_SIDE_TOKEN = {"l": "l", "left": "l", "r": "r", "right": "r"}


@dataclass
class AutoMapping:
    """Canonical joint -> source joint, with the reason for each choice."""

    joints: dict[str, str]
    reasons: dict[str, str] = field(default_factory=dict)
    landmarks: dict[str, str] = field(default_factory=dict)
    folded: dict[str, list[str]] = field(default_factory=dict)


def split_name(name: str) -> tuple[str | None, str]:
    """``(side, core)`` of a joint name: side ``'l'``, ``'r'`` or None; core lower-case.

    >>> split_name("mixamorig:LeftUpLeg"), split_name("CC_Base_L_Thigh"), split_name("thigh_r")
    (('l', 'upleg'), ('l', 'ccbasethigh'), ('r', 'thigh'))
    """
    base = re.split(r"[:|]", name)[-1]
    tokens = [t for t in re.split(r"[_\.\s\-]+", base) if t]
    side = None
    kept = []
    for t in tokens:
        if side is None and t.lower() in _SIDE_TOKEN:
            side = _SIDE_TOKEN[t.lower()]
            continue
        kept.append(t)
    word = "".join(kept)
    if side is None:
        m = re.match(r"^(Left|Right|left|right|LEFT|RIGHT)(?=[A-Z_0-9]|$)", word) or re.match(
            r"^([lLrR])(?=[A-Z])", word
        )
        if m:
            side = m.group(1)[0].lower()
            word = word[m.end() :]
        else:
            m = re.search(r"(?<=[a-z0-9])(Left|Right|L|R)$", word) or re.match(_LOWER_SIDE, word)
            if m:
                side = m.group(1)[0].lower()
                word = word[: m.start()] + word[m.end(1) :] if m.start() == 0 else word[: m.start()]
    return side, word.lower()


class _Tree:
    def __init__(self, names, parents, offsets):
        self.names = list(names)
        self.parents = list(parents)
        self.offsets = np.asarray(offsets, float)
        self.split = [split_name(n) for n in self.names]
        lengths = np.linalg.norm(self.offsets, axis=1)
        self.tiny = 1e-3 * max(float(np.median(lengths[lengths > 0])) if (lengths > 0).any() else 1.0, 1e-9)

    def ancestors(self, j: int) -> list[int]:
        out = []
        while self.parents[j] >= 0:
            j = self.parents[j]
            out.append(j)
        return out

    def is_helper(self, j: int) -> bool:
        return bool(_HELPER.search(self.split[j][1]))

    def is_zero(self, j: int) -> bool:
        return float(np.linalg.norm(self.offsets[j])) < self.tiny

    def children(self, j: int) -> list[int]:
        return [k for k, p in enumerate(self.parents) if p == j]

    def find(self, side: str | None, pred) -> list[int]:
        hits = [
            j
            for j, (s, core) in enumerate(self.split)
            if s == side and pred(core) and not self.is_helper(j) and not _FINGER.search(core)
        ]
        # keep the hit nearest the root (SMPL: left_ankle above left_foot)
        return [j for j in hits if not any(a in hits for a in self.ancestors(j))]

    def lca(self, items: list[int]) -> int:
        common = [items[0], *self.ancestors(items[0])]
        for j in items[1:]:
            chain = [j, *self.ancestors(j)]
            common = [a for a in common if a in chain]
        return common[0]

    def real_parent(self, j: int, stop: int) -> int | None:
        """Nearest ancestor below ``stop`` that is a real bone (not a helper, not zero-length below)."""
        child = j
        for a in self.ancestors(j):
            if a == stop:
                return None
            # an ancestor sitting exactly on its child in the chain carries no bone of its own
            if not self.is_helper(a) and not self.is_zero(child):
                return a
            child = a
        return None


def automap(
    names, parents, offsets, end_sites: dict[int, np.ndarray] | None = None, source: str = "BVH"
) -> AutoMapping:
    """Map a rig's joints onto the canonical skeleton (see the module docs).

    Raises :class:`RigError` naming the canonical joints it could not find and the
    file's own joint names."""
    t = _Tree(names, parents, offsets)
    m = AutoMapping({})
    missing: list[str] = []

    def put(canon: str, j: int | None, why: str) -> None:
        if j is None:
            return
        m.joints[canon] = t.names[j]
        m.reasons[canon] = why

    def anchor(side, pred, what) -> int | None:
        hits = t.find(side, pred)
        if len(hits) == 1:
            return hits[0]
        missing.append(what + (f", {len(hits)} candidates" if hits else ""))
        return None

    found_head = anchor(None, lambda c: c.endswith("head"), "upperneck (a joint named *Head)")
    found_legs, found_arms = {}, {}
    for s in ("l", "r"):
        found_legs[s] = anchor(s, lambda c: c.endswith("foot") or c.endswith("ankle"), f"{s}ankle (*Foot or *Ankle)")
        found_arms[s] = anchor(s, lambda c: c.endswith("hand") or c.endswith("wrist"), f"{s}wrist (*Hand or *Wrist)")
    if missing:
        raise _unmappable(source, names, missing)
    # nothing is missing: every anchor was found
    assert found_head is not None
    head = found_head
    legs = {s: j for s, j in found_legs.items() if j is not None}
    arms = {s: j for s, j in found_arms.items() if j is not None}

    chest = None
    uppers = {}
    for s, wrist in arms.items():
        elbow = t.real_parent(wrist, -1)
        shoulder = t.real_parent(elbow, -1) if elbow is not None else None
        uppers[s] = (wrist, elbow, shoulder)
    chest = t.lca([u[2] for u in uppers.values() if u[2] is not None] or list(arms.values()))
    for s, (wrist, elbow, shoulder) in uppers.items():
        clav = t.real_parent(shoulder, chest) if shoulder is not None else None
        put(f"{s}wrist", wrist, "wrist/hand by name")
        put(f"{s}elbow", elbow, "parent bone of the wrist")
        put(f"{s}shoulder", shoulder, "parent bone of the elbow")
        put(f"{s}clavicle", clav, "bone between the shoulder and the chest")
    hips = {}
    for s, ankle in legs.items():
        knee = t.real_parent(ankle, -1)
        hip = t.real_parent(knee, -1) if knee is not None else None
        hips[s] = hip
        put(f"{s}ankle", ankle, "ankle/foot by name (nearest the root)")
        put(f"{s}knee", knee, "parent bone of the ankle")
        put(f"{s}hip", hip, "parent bone of the knee")
        toes = [k for k in t.children(ankle) if not t.is_helper(k) and not _FINGER.search(t.split[k][1])]
        if len(toes) == 1:
            put(f"{s}toe", toes[0], "child of the ankle")
            tip = t.children(toes[0])
            if end_sites and toes[0] in end_sites:
                m.landmarks[f"{s}_toe_tip"] = f"end:{t.names[toes[0]]}"
            elif len(tip) == 1:
                m.landmarks[f"{s}_toe_tip"] = t.names[tip[0]]
        elif end_sites and ankle in end_sites:
            m.landmarks[f"{s}_toe_tip"] = f"end:{t.names[ankle]}"
    left_hip, right_hip = hips["l"], hips["r"]
    if left_hip is None or right_hip is None:
        raise _unmappable(source, names, [f"{s}hip" for s, h in hips.items() if h is None])
    root = t.lca([left_hip, right_hip, head])
    put("root", root, "common ancestor of both hips and the head")
    put("upperneck", head, "head by name")
    spine = [j for j in reversed(t.ancestors(chest)) if j in t.ancestors(chest) and root in t.ancestors(j)]
    spine = [j for j in spine if not t.is_zero(j) and not t.is_helper(j)]
    if chest != root:
        put("chest", chest, "common ancestor of both arms")
    if spine:
        put("lowerback", spine[0], "first spine bone above the root")
        if len(spine) > 1:
            pos = {j: _rest(t, j) for j in [spine[0], chest, *spine]}
            span = np.linalg.norm(pos[chest] - pos[spine[0]])
            want = 0.7 * span
            best = min(spine[1:], key=lambda j: abs(np.linalg.norm(pos[j] - pos[spine[0]]) - want))
            put("upperback", best, "spine bone nearest 70 % of the way from lowerback to chest")
    neck = [j for j in reversed(t.ancestors(head)) if chest in t.ancestors(j) and not t.is_zero(j)]
    if neck:
        put("lowerneck", neck[0], "first bone above the chest towards the head")
    for s in ("l", "r"):
        eyes = t.find(s, lambda c: c.endswith("eye"))
        if len(eyes) == 1:
            m.landmarks[f"{s}_eye"] = t.names[eyes[0]]
        for lm, pat in (("index", r"index\D*1$|index$"), ("pinky", r"(pinky|little)\D*1$|(pinky|little)$")):
            hits = [
                j
                for j, (side, core) in enumerate(t.split)
                if side == s and re.search(pat, core) and arms[s] in t.ancestors(j)
            ]
            hits = [j for j in hits if not any(a in hits for a in t.ancestors(j))]
            if len(hits) == 1:
                m.landmarks[f"{s}_{lm}"] = t.names[hits[0]]
    _check_chain(t, m, source)
    for canon, src in m.joints.items():
        j, p = t.names.index(src), sk.PARENTS[sk.JOINT_INDEX[canon]]
        while p >= 0 and sk.JOINT_NAMES[p] not in m.joints:
            p = sk.PARENTS[p]
        if p < 0:
            continue
        stop = t.names.index(m.joints[sk.JOINT_NAMES[p]])
        between = []
        for a in t.ancestors(j):
            if a == stop:
                break
            between.append(t.names[a])
        if between:
            m.folded[canon] = between[::-1]
    return m


def _rest(t: _Tree, j: int) -> np.ndarray:
    pos = np.zeros(3)
    while j >= 0:
        pos = pos + t.offsets[j]
        j = t.parents[j]
    return pos


def _check_chain(t: _Tree, m: AutoMapping, source: str) -> None:
    """Every mapped joint must descend from the source joint of its canonical parent."""
    bad = []
    for canon, src in m.joints.items():
        p = sk.PARENTS[sk.JOINT_INDEX[canon]]
        while p >= 0 and sk.JOINT_NAMES[p] not in m.joints:
            p = sk.PARENTS[p]
        if p < 0:
            continue
        parent_src = m.joints[sk.JOINT_NAMES[p]]
        if t.names.index(parent_src) not in t.ancestors(t.names.index(src)):
            bad.append(f"{canon}={src} does not descend from {sk.JOINT_NAMES[p]}={parent_src}")
    if bad:
        raise RigError(f"{source}: joint mapping breaks the chain: " + "; ".join(bad))


def check_mapping(names, parents, joints: dict[str, str], source: str) -> None:
    """Check a user's or profile's mapping: names exist and chains are respected."""
    unknown = sorted(v for v in joints.values() if v not in names)
    if unknown:
        raise RigError(f"{source}: mapped joints not in the file: {', '.join(unknown)}")
    _check_chain(_Tree(names, parents, np.zeros((len(names), 3))), AutoMapping(dict(joints)), source)


def _unmappable(source: str, names, missing: list[str]) -> RigError:
    shown = ", ".join(names[:60]) + (" ..." if len(names) > 60 else "")
    return RigError(
        f"{source}: cannot map this skeleton automatically; canonical joints not found: {'; '.join(missing)}. "
        f"Its {len(names)} joints: {shown}. Write a mapping with "
        f"'dragposer-studio rig suggest FILE --out MAP.toml', fix it and pass --rig-map MAP.toml."
    )
