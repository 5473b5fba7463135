"""Do the reconstructed legs step? Foot contact agreement with the truth and foot skating.

With head and hands only (presets ``3-head-hands``, ``4``) the legs are guessed: on a
walking clip they may glide instead of stepping. This script reconstructs clips with
simulated trackers (as ``evaluate`` does) and reports, per method and clip:

* ``pos_cm``: ``evaluate``'s Pos (world joint positions);
* ``jitter``: ``evaluate``'s jitter (mean joint jerk, 10^2 m/s^3) and ``ankle_jitter``, the
  same over the two ankles alone (the truth's rows give the truth's own);
* ``f1``: agreement of the per-frame contact label of each foot with the truth's (F1 of
  "in contact", averaged over the two feet) and ``acc`` (share of frames whose label agrees);
* ``skate_cms``: mean horizontal speed of a foot, cm/s, over the frames where the *truth*
  says that foot is in contact (the truth's own figure is its floor);
* ``steps``: contact changes per foot and second (truth: about 1 per second per foot at a walk).

A foot is in contact when its ankle is low (within :data:`HEIGHT_M` of the truth's floor:
the clip's 5th percentile of the truth's ankle heights) and slow (horizontal speed below
:data:`SPEED_MS`, smoothed over 3 frames). ``scan`` prints each clip's mean horizontal
head speed, to pick walking clips.

Run::

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/foot_contact.py scan FILE...
    PYTHONPATH=. OMP_NUM_THREADS=1 python research/foot_contact.py run FILE... \
        [--methods dragposer,ik] [--sensors 3-head-hands] [--max-frames 600] [--set KEY=VALUE] \
        [--gait KEY=VALUE] [--stance model|arms|truth] [--json OUT]

``--stance`` picks the gait planner's cue for the standing foot: ``model`` (the shipped
stance classifier, as the product runs), ``arms`` (the arm-swing rule alone, no
classifier) or ``truth`` (the truth's slower ankle each frame: the ceiling of a perfect
cue).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from engine import skeleton as sk

#: A foot is low when its ankle is within this height of the truth's floor, metres.
HEIGHT_M = 0.06
#: ... and slow when its horizontal speed is below this, metres per second.
SPEED_MS = 0.35
FEET = (sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"])
HEAD = sk.JOINT_INDEX["upperneck"]


def horizontal_speed(pos: np.ndarray, fps: float) -> np.ndarray:
    """Horizontal speed of each joint ``(F, J)``, m/s, from positions ``(F, J, 3)`` (central
    differences over 3 frames; the ends repeat their neighbours)."""
    v = np.zeros(pos.shape[:2])
    if len(pos) >= 3:
        v[1:-1] = np.linalg.norm(pos[2:, :, :2] - pos[:-2, :, :2], axis=-1) * fps / 2.0
        v[0], v[-1] = v[1], v[-2]
    return v


def floor_of(gt_pos: np.ndarray) -> float:
    """The truth's floor height: the 5th percentile of its ankle heights, metres."""
    return float(np.percentile(gt_pos[:, FEET, 2], 5))


def contacts(pos: np.ndarray, fps: float, floor: float) -> np.ndarray:
    """Per frame and foot ``(F, 2)``: whether the ankle is low and slow (module doc)."""
    feet = pos[:, FEET]
    low = feet[..., 2] < floor + HEIGHT_M
    slow = horizontal_speed(feet, fps) < SPEED_MS
    return low & slow


def agreement(truth: np.ndarray, rec: np.ndarray) -> dict[str, float]:
    """F1 of the contact label (mean over feet; a foot the truth never plants counts when
    the reconstruction never plants it either) and the share of agreeing frames."""
    f1 = []
    for k in range(truth.shape[1]):
        t, r = truth[:, k], rec[:, k]
        tp, fp, fn = np.sum(t & r), np.sum(~t & r), np.sum(t & ~r)
        f1.append(1.0 if tp + fp + fn == 0 else 2.0 * tp / (2.0 * tp + fp + fn))
    return {"f1": float(np.mean(f1)), "acc": float(np.mean(truth == rec))}


def skating_cms(rec_pos: np.ndarray, truth_contact: np.ndarray, fps: float) -> float:
    """Mean horizontal speed of the reconstructed feet while the truth plants them, cm/s."""
    speed = horizontal_speed(rec_pos[:, FEET], fps)
    return float(100.0 * speed[truth_contact].mean()) if truth_contact.any() else float("nan")


def steps_per_s(contact: np.ndarray, fps: float) -> float:
    """Contact changes per foot and second."""
    return float(np.abs(np.diff(contact.astype(int), axis=0)).sum() / contact.shape[1] / (len(contact) / fps))


def foot_metrics(gt_pos: np.ndarray, rec_pos: np.ndarray, fps: float) -> dict[str, float]:
    """The contact figures of one reconstruction ``(F, 22, 3)`` against its truth."""
    floor = floor_of(gt_pos)
    t, r = contacts(gt_pos, fps, floor), contacts(rec_pos, fps, floor)
    return {**agreement(t, r), "skate_cms": skating_cms(rec_pos, t, fps), "steps": steps_per_s(r, fps)}


def truth_metrics(gt_pos: np.ndarray, fps: float) -> dict[str, float]:
    t = contacts(gt_pos, fps, floor_of(gt_pos))
    return {
        "skate_cms": skating_cms(gt_pos, t, fps),
        "steps": steps_per_s(t, fps),
        "head_speed": float(horizontal_speed(gt_pos[:, [HEAD]], fps).mean()),
    }


def _load(path: Path, max_frames: int | None):
    from engine.motion.retarget import load_motion

    return load_motion(path, max_frames=max_frames)


def scan(files: list[Path], max_frames: int | None) -> None:
    for f in files:
        m = _load(f, max_frames)
        pos, _ = m.fk()
        t = truth_metrics(pos, m.fps)
        print(f"{t['head_speed']:5.2f} m/s  steps {t['steps']:4.2f}/s  {f}")


def gait_params(items: list[str]) -> None:
    """Make every new :class:`~engine.solver.gait.GaitPlanner` use these ``KEY=VALUE``
    constants of :class:`~engine.solver.gait.GaitParams` (the planner's tuning)."""
    if not items:
        return
    import dataclasses

    from engine.solver import gait

    params = dataclasses.replace(gait.GaitParams(), **{k: float(v) for k, v in (i.split("=", 1) for i in items)})
    init = gait.GaitPlanner.__init__
    gait.GaitPlanner.__init__ = lambda self, fps, p=None, stance=None: init(self, fps, p or params, stance)  # type: ignore[method-assign]


class _TruthStance:
    """Makes every gait planner name the truth's slower ankle as the standing foot, frame by
    frame of the clip being reconstructed (set :attr:`stance` per clip)."""

    def __init__(self) -> None:
        from engine.solver import gait

        self.stance = np.zeros(0, dtype=int)
        self.frame = 0
        update = gait.GaitPlanner.update

        def counted(planner, *args, **kwargs):
            out = update(planner, *args, **kwargs)
            self.frame += 1
            return out

        gait.GaitPlanner.update = counted  # type: ignore[method-assign]
        gait.GaitPlanner.learned_stance = lambda planner: int(self.stance[min(self.frame, len(self.stance) - 1)])  # type: ignore[method-assign]

    def start(self, gt_pos: np.ndarray, fps: float) -> None:
        self.stance = np.argmin(horizontal_speed(gt_pos[:, list(FEET)], fps), axis=1)
        self.frame = 0


def stance_cue(kind: str) -> _TruthStance | None:
    """Set the gait planner's standing-foot cue (see the module doc)."""
    if kind == "truth":
        return _TruthStance()
    if kind == "arms":
        from engine.models import stance

        stance._DEFAULT[:] = [None]
    return None


def run(
    files: list[Path],
    methods: list[str],
    sensors: str,
    max_frames: int | None,
    settings: list[str],
    json_out: Path | None,
    gait: list[str] = (),
    stance: str = "model",
) -> dict:
    from engine.cli.method_options import apply_settings
    from engine.methods import get_method, run_method
    from engine.metrics import evaluate_motion, jerk_curve
    from engine.tracking import simulate

    gait_params(list(gait))
    truth_cue = stance_cue(stance)
    built = {}
    for name in methods:
        built[name] = get_method(name, **({"mode": "realtime"} if name == "dragposer" else {}))
        if name == "dragposer" and settings:
            apply_settings(built[name], name, settings)
    out: dict = {
        "sensors": sensors,
        "max_frames": max_frames,
        "set": settings,
        "gait": list(gait),
        "stance": stance,
        "files": {},
    }
    for f in files:
        motion = _load(f, max_frames)
        gt_pos, _ = motion.fk()
        tracking = simulate(motion, sensors, seed=0)
        row = {
            "truth": {
                **truth_metrics(gt_pos, motion.fps),
                "jitter": float(np.nanmean(jerk_curve(gt_pos, motion.fps))),
                "ankle_jitter": float(np.nanmean(jerk_curve(gt_pos[:, list(FEET)], motion.fps))),
            }
        }
        for name, method in built.items():
            if truth_cue is not None:
                truth_cue.start(gt_pos, motion.fps)
            rec, _ = run_method(method, tracking, motion.skeleton, progress=False, reference=motion, light=True)
            rec_pos, _ = rec.fk()
            ev = evaluate_motion(motion, rec)
            row[name] = {
                "pos_cm": ev["pos_cm"],
                "jitter": ev["jitter"],
                "ankle_jitter": float(np.nanmean(jerk_curve(rec_pos[:, list(FEET)], motion.fps))),
                **foot_metrics(gt_pos, rec_pos, motion.fps),
            }
        out["files"][str(f)] = row
        print(f.name, json.dumps({k: {a: round(b, 3) for a, b in v.items()} for k, v in row.items()}), flush=True)
    keys = ("pos_cm", "jitter", "ankle_jitter", "f1", "acc", "skate_cms", "steps")
    out["mean"] = {
        name: {k: float(np.mean([r[name][k] for r in out["files"].values()])) for k in keys} for name in methods
    }
    out["mean"]["truth"] = {
        k: float(np.mean([r["truth"][k] for r in out["files"].values()]))
        for k in ("skate_cms", "steps", "head_speed", "jitter", "ankle_jitter")
    }
    print("mean", json.dumps({k: {a: round(b, 3) for a, b in v.items()} for k, v in out["mean"].items()}))
    if json_out:
        json_out.write_text(json.dumps(out, indent=1))
    return out


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("what", choices=("scan", "run"))
    p.add_argument("files", nargs="+", type=Path)
    p.add_argument("--methods", default="dragposer,ik")
    p.add_argument("--sensors", default="3-head-hands")
    p.add_argument("--max-frames", type=int, default=600)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a DragPoser setting")
    p.add_argument(
        "--gait",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a constant of engine.solver.gait.GaitParams, e.g. lead_s=0.2",
    )
    p.add_argument("--stance", choices=("model", "arms", "truth"), default="model", help="the standing-foot cue")
    p.add_argument("--json", type=Path)
    a = p.parse_args(argv)
    if a.what == "scan":
        scan(a.files, a.max_frames)
    else:
        run(a.files, a.methods.split(","), a.sensors, a.max_frames, a.set, a.json, a.gait, a.stance)


if __name__ == "__main__":
    main()
