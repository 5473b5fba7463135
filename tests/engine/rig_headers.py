"""Real rigs' joint names and OFFSETs, copied as numbers from public BVH headers.

Each table lists ``JOINT PARENT X Y Z`` (``-`` for the root) and ``End JOINT X Y Z``
for End Sites, in the file's own order, units and axes. :mod:`rig_fixtures` writes a
synthetic motion on these hierarchies; the joint names and offsets are the real rigs'.
"""

from __future__ import annotations

import numpy as np

#: Daz/Poser: the "Daz-friendly" rig of the cgspeed conversion of the CMU database (the
#: rig of ../shared/data's cmu_daz clips; centimetres, Y-up, T-pose at zero rotation).
#: Source: AmmarkoV/RGBDAcquisition, opengl_acquisition_shared_library/
#: opengl_depth_and_color_renderer/Motions/DAZFriendlyCMU.bvh (commit cc47865).
DAZ = """
hip - 0 0 0
abdomen hip 0 20.6881 -0.73152
chest abdomen 0 11.7043 -0.48768
neck chest 0 22.1894 -2.19456
head neck -0.24384 7.07133 1.2192
leftEye head 4.14528 8.04674 8.04672
End leftEye 1 0 0
rightEye head -3.6576 8.04674 8.04672
End rightEye 1 0 0
rCollar chest -2.68224 19.2634 -4.8768
rShldr rCollar -8.77824 -1.95073 1.46304
rForeArm rShldr -28.1742 -1.7115 0.48768
rHand rForeArm -22.5879 0.773209 7.07136
rThumb1 rHand -1.2192 -0.487915 3.41376
rThumb2 rThumb1 -3.37035 -0.52449 3.41376
End rThumb2 -1.78271 -1.18214 1.43049
rIndex1 rHand -7.75947 0.938293 5.60832
rIndex2 rIndex1 -2.54057 -0.884171 1.56538
End rIndex2 -1.62519 -0.234802 1.16502
rMid1 rHand -8.24714 1.18213 3.41376
rMid2 rMid1 -3.10165 -0.590103 1.0647
End rMid2 -2.48547 -0.328903 0.83742
rRing1 rHand -8.82822 0.546677 1.51678
rRing2 rRing1 -2.60934 -0.819778 -0.0198488
End rRing2 -2.33842 -0.294052 0.168128
rPinky1 rHand -8.27202 -0.0477905 -0.4584
rPinky2 rPinky1 -1.82734 -0.647385 -0.700984
End rPinky2 -1.69225 -0.51767 -0.607171
lCollar chest 2.68224 19.2634 -4.8768
lShldr lCollar 8.77824 -1.95073 1.46304
lForeArm lShldr 28.1742 -1.7115 0.48768
lHand lForeArm 22.5879 0.773209 7.07136
lThumb1 lHand 1.2192 -0.487915 3.41376
lThumb2 lThumb1 3.37035 -0.52449 3.41376
End lThumb2 1.78271 -1.18214 1.43049
lIndex1 lHand 7.75947 0.938293 5.60832
lIndex2 lIndex1 2.54057 -0.884171 1.56538
End lIndex2 1.62519 -0.234802 1.16502
lMid1 lHand 8.24714 1.18213 3.41376
lMid2 lMid1 3.10165 -0.590103 1.0647
End lMid2 2.48547 -0.328903 0.83742
lRing1 lHand 8.82822 0.546677 1.51678
lRing2 lRing1 2.60934 -0.819778 -0.0198488
End lRing2 2.33842 -0.294052 0.168128
lPinky1 lHand 8.27202 -0.0477905 -0.4584
lPinky2 lPinky1 1.82734 -0.647385 -0.700984
End lPinky2 1.69225 -0.51767 -0.607171
rButtock hip -8.77824 4.35084 1.2192
rThigh rButtock 0 -1.70687 -2.19456
rShin rThigh 0 -36.8199 0.73152
rFoot rShin 0.73152 -45.1104 -5.12064
End rFoot -1.1221 -3.69964 12.103
lButtock hip 8.77824 4.35084 1.2192
lThigh lButtock 0 -1.70687 -2.19456
lShin lThigh 0 -36.8199 0.73152
lFoot lShin -0.73152 -45.1104 -5.12064
End lFoot 1.1221 -3.69964 12.103
"""

#: Mixamo: a character exported from mixamo.com (prefix ``mixamorig7:``; centimetres,
#: Y-up, T-pose at zero rotation; ``HeadTop_End`` and ``Toe_End`` are joints). Only the
#: middle finger of each hand is kept of the fingers.
#: Source: PeizhuoLi/ganimator, data/Joe/Walk-In-Circle.bvh (commit 81dd087).
MIXAMO = """
mixamorig7:Hips - 0 99.793892 0
mixamorig7:Spine mixamorig7:Hips 0 9.694397 -1.109700
mixamorig7:Spine1 mixamorig7:Spine 0 11.310143 -1.294687
mixamorig7:Spine2 mixamorig7:Spine1 0 12.925888 -1.479643
mixamorig7:Neck mixamorig7:Spine2 0 14.541641 -1.664600
mixamorig7:Head mixamorig7:Neck 0 6.944305 1.982500
mixamorig7:HeadTop_End mixamorig7:Head 0 22.789597 6.506100
End mixamorig7:HeadTop_End 0 23.700119 0
mixamorig7:LeftShoulder mixamorig7:Spine2 6.681300 12.786087 -1.621969
mixamorig7:LeftArm mixamorig7:LeftShoulder 13.585576 -3.446136 0.085203
mixamorig7:LeftForeArm mixamorig7:LeftArm 27.330299 0 -0.000001
mixamorig7:LeftHand mixamorig7:LeftForeArm 20.888802 0 -0.000001
mixamorig7:LeftHandMiddle1 mixamorig7:LeftHand 11.227951 0 -0.000001
mixamorig7:LeftHandMiddle2 mixamorig7:LeftHandMiddle1 3.465431 0 0
mixamorig7:LeftHandMiddle3 mixamorig7:LeftHandMiddle2 3.340118 0 0
mixamorig7:LeftHandMiddle4 mixamorig7:LeftHandMiddle3 2.993599 0 0
End mixamorig7:LeftHandMiddle4 2.993607 -0.000061 -0.003500
mixamorig7:RightShoulder mixamorig7:Spine2 -6.681300 12.786102 -1.707222
mixamorig7:RightArm mixamorig7:RightShoulder -13.585576 -3.446152 -0.085196
mixamorig7:RightForeArm mixamorig7:RightArm -27.318214 0 0.000002
mixamorig7:RightHand mixamorig7:RightForeArm -20.889801 0 0.000001
mixamorig7:RightHandMiddle1 mixamorig7:RightHand -11.291573 0 0
mixamorig7:RightHandMiddle2 mixamorig7:RightHandMiddle1 -3.513855 0 0
mixamorig7:RightHandMiddle3 mixamorig7:RightHandMiddle2 -3.299538 0 0
mixamorig7:RightHandMiddle4 mixamorig7:RightHandMiddle3 -2.888702 0 0
End mixamorig7:RightHandMiddle4 -2.888702 -0.000076 -0.003599
mixamorig7:LeftUpLeg mixamorig7:Hips 8.726300 -5.393196 -0.445400
mixamorig7:LeftLeg mixamorig7:LeftUpLeg 0.203112 -40.995728 -2.240422
mixamorig7:LeftFoot mixamorig7:LeftLeg -0.203116 -41.811745 -4.341125
mixamorig7:LeftToeBase mixamorig7:LeftFoot 2.022961 -9.567262 15.917597
mixamorig7:LeftToe_End mixamorig7:LeftToeBase 0.919500 0.587269 6.993709
End mixamorig7:LeftToe_End 0.919500 0.587269 6.993710
mixamorig7:RightUpLeg mixamorig7:Hips -8.726300 -5.393196 -0.458900
mixamorig7:RightLeg mixamorig7:RightUpLeg -0.203119 -40.995686 -2.183443
mixamorig7:RightFoot mixamorig7:RightLeg 0.203109 -41.812000 -3.686646
mixamorig7:RightToeBase mixamorig7:RightFoot -2.022940 -9.566534 15.362668
mixamorig7:RightToe_End mixamorig7:RightToeBase -0.919481 0.587567 7.048032
End mixamorig7:RightToe_End -0.919481 0.587567 7.048031
"""

#: LAFAN1 (Ubisoft La Forge animation dataset): every file of the dataset shares this
#: header (centimetres, Y-up). Its offsets lie along each joint's own x axis, so the zero
#: rotation pose is not a T-pose: the clips' rotations carry the bone frames.
#: Source: the header of the lafan1.zip BVH files (ubisoft/ubisoft-laforge-animation-dataset),
#: as reproduced in public reimplementations of "Robust Motion In-betweening" (a
#: ``Skeleton(offsets=..., parents=...)`` table with End Sites as zero rows, dropped here).
LAFAN1 = """
Hips - -42.198200 91.614723 -40.067841
LeftUpLeg Hips 0.103456 1.857829 10.548506
LeftLeg LeftUpLeg 43.499992 -0.000038 -0.000002
LeftFoot LeftLeg 42.372192 0.000015 -0.000007
LeftToe LeftFoot 17.299999 -0.000002 0.000003
RightUpLeg Hips 0.103457 1.857829 -10.548503
RightLeg RightUpLeg 43.500042 -0.000027 0.000008
RightFoot RightLeg 42.372257 -0.000008 0.000014
RightToe RightFoot 17.299992 -0.000005 0.000004
Spine Hips 6.901968 -2.603733 -0.000001
Spine1 Spine 12.588099 0.000002 0.000000
Spine2 Spine1 12.343206 0.000000 -0.000001
Neck Spine2 25.832886 -0.000004 0.000003
Head Neck 11.766620 0.000005 -0.000001
LeftShoulder Spine2 19.745899 -1.480370 6.000108
LeftArm LeftShoulder 11.284125 -0.000009 -0.000018
LeftForeArm LeftArm 33.000050 0.000004 0.000032
LeftHand LeftForeArm 25.200008 0.000015 0.000008
RightShoulder Spine2 19.746099 -1.480375 -6.000073
RightArm RightShoulder 11.284138 -0.000015 -0.000012
RightForeArm RightArm 33.000092 0.000017 0.000013
RightHand RightForeArm 25.199780 0.000135 0.000422
"""


#: ``joint_``-prefixed game rig: the Bandai Namco Research Motion dataset (centimetres,
#: Y-up; bone frames along each joint's x axis like LAFAN1, the right side's offsets
#: negated; the files give every joint 6 channels, written here with 3 rotations).
#: Source: BandaiNamcoResearchInc/Bandai-Namco-Research-Motiondataset,
#: dataset/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_bow_active_001.bvh (commit 3c23012).
BANDAI = """
joint_Root - 0 0 0
Hips joint_Root 0.847027 93.984 -452.225
Spine Hips 15.7357 0 0
Chest Spine 8.98455 -0.406207 0
Neck Chest 16.3773 0 0
Head Neck 6.45672 0 0
End Head 0 0 0
Shoulder_L Chest 12.9942 -0.242716 4.98039
UpperArm_L Shoulder_L 5.34809 0 0
LowerArm_L UpperArm_L 24.3286 1.87007e-05 0
Hand_L LowerArm_L 22.2916 0 0
End Hand_L 0 0 0
Shoulder_R Chest 12.9945 -0.242716 -4.98039
UpperArm_R Shoulder_R -5.34813 0 0
LowerArm_R UpperArm_R -24.3289 0.000322201 0
Hand_R LowerArm_R -22.2915 -0.000108084 0
End Hand_R 0 0 0
UpperLeg_L Hips -2.19248 -6.46944 0
LowerLeg_L UpperLeg_L 39.0811 0 -1.23785e-05
Foot_L LowerLeg_L 40.9854 0 -1.26872e-05
Toes_L Foot_L 11.7543 0 0
End Toes_L 0 0 0
UpperLeg_R Hips -2.19251 6.46944 0
LowerLeg_R UpperLeg_R -39.0811 -0.00228153 -0.0401928
Foot_R LowerLeg_R -40.9854 0 0
Toes_R Foot_R -11.7543 0 0
End Toes_R 0 0 0
"""


def parse(table: str) -> tuple[list[tuple[str, str | None, tuple]], dict[str, tuple]]:
    """``(rows, end_sites)`` of a table: rows are ``(name, parent, offset)`` in file order."""
    rows, ends = [], {}
    for line in table.strip().splitlines():
        a, b, *xyz = line.split()
        off = tuple(float(v) for v in xyz)
        if a == "End":
            ends[b] = off
        else:
            rows.append((a, None if b == "-" else b, off))
    return rows, ends


def _frame(a1: np.ndarray, a2: np.ndarray) -> np.ndarray:
    e1 = a1 / np.linalg.norm(a1)
    e2 = a2 - e1 * (a2 @ e1)
    e2 /= np.linalg.norm(e2)
    return np.stack([e1, e2, np.cross(e1, e2)], axis=1)


def _side(name: str) -> int:
    """+1 for a left joint (``Left...``, ``..._L``), -1 for a right one, 0 on the midline."""
    if name.startswith("Left") or name.endswith("_L"):
        return 1
    if name.startswith("Right") or name.endswith("_R"):
        return -1
    return 0


def _aim(child: str) -> np.ndarray:
    """World direction (Y-up, facing +Z, left = +X) of the bone ending at ``child`` in a T-pose."""
    if "Toe" in child:
        return np.array([0.0, -0.4, 1.0]) / np.hypot(0.4, 1.0)
    if "Leg" in child or "Foot" in child:
        return np.array([0.0, -1.0, 0.0])
    if any(k in child for k in ("Arm", "Hand")):
        return np.array([float(_side(child)), 0.0, 0.0])
    return np.array([0.0, 1.0, 0.0])  # spine, neck, head


def tpose_frames(rows) -> dict[str, np.ndarray]:
    """Global rotation (3, 3) of every joint that puts a local-frame rig (LAFAN1) in a T-pose.

    A joint with one child turns by the least rotation that aims that bone as in a T-pose;
    a joint with several (hips, upper spine) aims the central child up and its left child's
    side at +X; a leaf, or a top node above the hips (``joint_Root``), keeps its parent's
    rotation.
    """
    kids: dict[str, list] = {}
    for name, parent, off in rows:
        kids.setdefault(parent, []).append((name, np.array(off, float)))
    from engine.kinematics import quaternion as Q

    glob: dict[str, np.ndarray] = {}
    for name, parent, _ in rows:
        ch = kids.get(name, [])
        up = glob.get(parent, np.eye(3))
        if len(ch) > 1:
            mid = next(o for n, o in ch if _side(n) == 0)
            left = next(o for n, o in ch if _side(n) > 0) - next(o for n, o in ch if _side(n) < 0)
            glob[name] = _frame(np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])) @ _frame(mid, left).T
        elif ch and len(kids.get(ch[0][0], [])) < 2:
            child, off = ch[0]
            turn = Q.to_matrix(Q.from_to((up @ off)[None], _aim(child)[None]))[0]
            glob[name] = turn @ up
        else:
            glob[name] = up
    return glob
