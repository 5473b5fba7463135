"""The text of docs/comparison.md, from the cached results of ``dragposer-studio compare``."""

from __future__ import annotations

import argparse
import math
from typing import Any

#: (preset, gaps, method variants) of the four passes.
PASSES = (
    ("6", False, ("dragposer", "sparseposer", "ik")),
    ("6", True, ("dragposer", "dragposer+blend", "sparseposer", "ik")),
    ("3-head-hands", False, ("dragposer", "rpm", "ik")),
    ("3-head-hands", True, ("dragposer", "dragposer+blend", "rpm", "ik")),
)


def fmt(v: Any, spec: str) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


_COLS = (
    ("pos_cm", "Pos cm", ".2f"),
    ("rot_deg", "Rot deg", ".1f"),
    ("vel_cms", "Vel cm/s", ".1f"),
    ("ee_cm", "EE cm", ".2f"),
    ("jitter", "Jitter", ".2f"),
    ("ms_per_frame", "ms/frame", ".1f"),
)
_GAP_COLS = (
    ("pj", "PJ", ".1f"),
    ("auj", "AUJ", ".0f"),
    ("pj_ts", "PJ T-S", ".1f"),
    ("auj_ts", "AUJ T-S", ".0f"),
    ("pj_st", "PJ S-T", ".1f"),
    ("auj_st", "AUJ S-T", ".0f"),
    ("pj_raw", "PJ raw", ".1f"),
    ("auj_raw", "AUJ raw", ".0f"),
)

PAPERS = """\
## The papers' own figures

Not comparable number for number (other data, skeletons, frame rates and trackers; see
below), but they show the scale each method reaches with its authors' training.

**SparsePoser** (Ponton et al. 2023, Table 1; six 6-DoF trackers, trained on DanceDB,
*Ours-0* = realtime, no future frames):

| test set | Pos cm | Rot deg | EE cm | Jitter | Vel cm/s |
|---|---:|---:|---:|---:|---:|
| HUMAN4D | 2.90 | 5.84 | 3.51 | 3.30 | 9.93 |
| SOMA | 2.72 | 5.72 | 3.36 | 3.99 | 11.8 |

**RPM** (Barquero et al. 2025, Table 1; head and wrists, AMASS protocol A-P1 at 60 fps,
hand-tracking losses "HT"; jerk in 10^2 m/s^3 over the second after a transition):

| variant | MPJPE cm | MPJVE cm/s | Jitter | PJ T-S | AUJ T-S | PJ S-T | AUJ S-T |
|---|---:|---:|---:|---:|---:|---:|---:|
| RPM reactive (W = 10) | 5.18 | 22.83 | 4.35 | 15.28 | 60.51 | 18.98 | 69.02 |
| RPM smooth (W = 20) | 5.44 | 24.04 | 4.29 | 8.41 | 84.81 | 12.12 | 50.23 |
| HMD-Poser (best stateful baseline) | 4.04 | 22.34 | 7.35 | 23.84 | 302.58 | 461.91 | 1236.47 |

## What differs in our protocol

- **Data.** Trained on the CMU-derived folders only (about 90 000 frames with mirrors,
  see `assets/models/README.md`); evaluated on the 9 validation files (never trained
  on), retargeted to the canonical 22-joint skeleton at 60 fps. The papers train on
  hours of data (SparsePoser: DanceDB; RPM: AMASS) for 6-13 hours on a GPU; ours had
  35 minutes each on a shared 2-core CPU, with smaller networks (SparsePoser must run in
  at most 5 ms per frame here).
- **Trackers** are simulated from the ground truth without noise (`engine.tracking`):
  SparsePoser's feet trackers sit on the ankles (the paper uses the toes). Gaps follow
  RPM's hand-tracking model (supplementary sec. C) but with our seed and clips.
- **Metrics** (`docs/metrics.md`): Pos is the mean joint error in world space (the
  body placed by the method: hips tracker for preset 6, head for 3-head-hands), not
  after root alignment; PJ/AUJ average all transitions, T-S and S-T split them.
- **SparsePoser** runs its realtime variant only (the method interface is causal; see
  `engine/methods/sparseposer.py`), with a smaller generator (kernel 3, 16/32/48
  channels per node), whose last output frame reads only the last 23 frames of its
  window; L_DQ covers only the last frames of each window (`assets/models/README.md`).
  The paper's learned IK, like ours, leaves the spine alone: the head tracker is met
  only as well as the generator meets it.
- **RPM** uses an MLP for `f` instead of the paper's cross-attention and four
  Transformer layers (supplementary sec. B), 0.5 s of free running during training
  (paper: 1 s) and the paper's smooth setting W = 20 with its cosine uncertainty.
- **DragPoser's blend** (`dragposer+blend`) is this project's addition (borrowed from
  RPM's idea), not part of the DragPoser paper.
"""


def _table(rows: dict[str, dict[str, Any]], gaps: bool) -> str:
    cols = _COLS + (_GAP_COLS if gaps else ())
    out = ["| method | " + " | ".join(h for _, h, _ in cols) + " |", "|---|" + "---:|" * len(cols)]
    for name, doc in rows.items():
        t = doc.get("total", {})
        cells = [fmt(t.get(k), spec) for k, _, spec in cols] if t else ["-"] * len(cols)
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def _ratio(a: Any, b: Any) -> float | None:
    try:
        return float(a) / float(b)
    except (TypeError, ValueError, ZeroDivisionError):
        return None


def _targets(res: dict, blend: float) -> list[str]:
    out = []
    dp, sp = res.get(("6", False, "dragposer")), res.get(("6", False, "sparseposer"))
    if dp and sp:
        r = _ratio(sp["total"]["pos_cm"], dp["total"]["pos_cm"])
        out.append(
            f"- SparsePoser, preset 6, accuracy: Pos {sp['total']['pos_cm']:.2f} cm against DragPoser's "
            f"{dp['total']['pos_cm']:.2f} cm on the same frames ({fmt(r, '.2f')}x; target <= 1.25x): "
            f"**{'met' if r is not None and r <= 1.25 else 'not met'}**."
        )
        out.append(
            "- SparsePoser, speed (target <= 5 ms per frame): the ms/frame above come from the machine "
            "that ran this command, busy with other jobs; the target is judged on the idle machine with "
            "`dragposer-studio bench --method dragposer --method sparseposer --sensors 6 --frames 300` "
            "(figure and verdict in `assets/models/README.md`, SparsePoser, Speed)."
        )
    dp, rpm = res.get(("3-head-hands", True, "dragposer")), res.get(("3-head-hands", True, "rpm"))
    if dp and rpm:
        pj, auj = (rpm["total"].get(k) for k in ("pj", "auj"))
        ok = pj is not None and auj is not None and pj < dp["total"]["pj"] and auj < dp["total"]["auj"]
        out.append(
            f"- RPM, 3-head-hands with gaps: PJ {fmt(pj, '.1f')} / AUJ {fmt(auj, '.0f')} against "
            f"DragPoser's {fmt(dp['total'].get('pj'), '.1f')} / {fmt(dp['total'].get('auj'), '.0f')} "
            f"without smoothing: **{'met' if ok else 'not met'}**."
        )
    bl = res.get(("3-head-hands", True, "dragposer+blend"))
    if dp and bl:
        r = _ratio(bl["total"].get("auj"), dp["total"].get("auj"))
        out.append(
            f"- DragPoser's AUJ with a {blend:g} s blend: {fmt(bl['total'].get('auj'), '.0f')} against "
            f"{fmt(dp['total'].get('auj'), '.0f')} without ({fmt(r, '.2f')}x; target <= 0.5x): "
            f"**{'met' if r is not None and r <= 0.5 else 'not met'}**; PJ "
            f"{fmt(bl['total'].get('pj'), '.1f')} against {fmt(dp['total'].get('pj'), '.1f')}."
        )
        out.append(_auj_note(dp, bl))
    return out


def _auj_note(dp: dict, bl: dict) -> str:
    """What PJ / AUJ measure here, and the plain sums (``PJ raw`` / ``AUJ raw``) beside them."""
    gt = dp["total"].get("gt_jerk")
    raw = _ratio(bl["total"].get("auj_raw"), dp["total"].get("auj_raw"))
    return (
        "  PJ / AUJ follow FlowMDM, as RPM uses them (docs/metrics.md): the 1-s windows after the "
        "changes are averaged into one curve of the largest joint jerk; PJ is its peak, AUJ its summed "
        f"distance from the ground truth's mean jerk ({fmt(gt, '.1f')} here), so motion as smooth as the "
        "real one scores AUJ ~ 0 up to the noise of averaging few windows: the ground truth itself, at the "
        f"same changes, scores PJ {fmt(dp['total'].get('gt_pj'), '.1f')} / AUJ "
        f"{fmt(dp['total'].get('gt_auj'), '.0f')}. With the plain sums (`PJ raw` / `AUJ raw`, which count the "
        f"motion's own jerk too) the blend gives {fmt(bl['total'].get('auj_raw'), '.0f')} against "
        f"{fmt(dp['total'].get('auj_raw'), '.0f')} ({fmt(raw, '.2f')}x)."
    )


def render(res: dict[tuple[str, bool, str], dict[str, Any]], args: argparse.Namespace) -> str:
    first = next(iter(res.values()), {})
    files = list(first.get("files", {}))
    frames = first.get("total", {}).get("frames")
    limit = f" --max-frames {args.max_frames}" if args.max_frames else ""
    lines = [
        "# DragPoser beside SparsePoser, RPM and the IK baseline",
        "",
        "Generated by `dragposer-studio compare" + limit + f" --blend {args.blend:g}` (do not edit by hand;",
        "re-run it, `--table-only` rebuilds this file from `runs/comparison/`). Realtime mode,",
        f"{len(files)} validation files, {fmt(frames, 'd')} frames per pass, tracker seed 0.",
        "`dragposer+blend` is DragPoser with trackers blended in over the blend time when they",
        "reconnect (`--set sensor_blend=S`; a lost tracker ends at once, docs/optimizer.md);",
        "`dragposer` lets the targets jump. PJ / AUJ follow FlowMDM (docs/metrics.md); `raw`",
        "columns are plain sums of the mean joint jerk.",
        "Timings (ms/frame) are from the machine that ran the command; see docs/optimizer.md",
        "for the idle-machine figures.",
        "",
    ]
    for i, (preset, gaps, variants) in enumerate(PASSES, start=1):
        rows = {v: res[(preset, gaps, v)] for v in variants if (preset, gaps, v) in res}
        lines += [f"## {i}. Preset `{preset}`{', with hand-tracking gaps' if gaps else ''}", ""]
        if not rows:
            lines += ["(not run yet)", ""]
            continue
        lines += [_table(rows, gaps), ""]
        for v, doc in rows.items():
            if "error" in doc:
                lines.append(f"- {v}: not evaluated: {doc['error']}")
        missing = [v for v in variants if v not in rows]
        if missing:
            lines.append(f"- not run yet: {', '.join(missing)} (the same command fills them in; cached rows are kept)")
        lines.append("")
    lines += ["## Targets", "", *(_targets(res, args.blend) or ["(results missing)"]), "", PAPERS]
    if files:
        lines += ["## Files", "", *[f"- `{f}`" for f in files], ""]
    return "\n".join(lines)
