"""The retargeting definitions the project compared with the current one, as strategies.

:data:`VERSIONS` maps each version number to its
:class:`engine.motion.retarget_strategy.RetargetStrategy`; pass one as ``strategy=`` to
:func:`engine.motion.retarget.load_motion` or :func:`~engine.motion.retarget.retarget`.
No shipped model or prepared data depends on the non-current ones (docs/skeleton.md,
*Versions*):

* **3**: every joint keeps the source's rotation with one constant alignment per joint
  (no body-defined twist, the file's own elbows). ``rpm.pt`` learnt it and is fed the
  current version, which it reconstructs as well.
* **4**: :data:`engine.motion.retarget_strategy.CURRENT`.
* **5**: version 4 with legs a profile draws bent read straight along the hip-to-ankle
  line (``straight_knees``) and a rig's toe tip read against a canonical tip on the
  sole's line; the shipped models reconstruct it slightly worse.
"""

from __future__ import annotations

import dataclasses

from engine.motion.retarget_strategy import CURRENT, RetargetStrategy

VERSION_3 = dataclasses.replace(CURRENT, version=3, body_twist=False, straight_elbows=False)
VERSION_5 = dataclasses.replace(CURRENT, version=5, straight_knees=True, sole_toe_tips=True)
VERSIONS: dict[int, RetargetStrategy] = {3: VERSION_3, CURRENT.version: CURRENT, 5: VERSION_5}
