"""Regenerate docs/evaluation.md: DragPoser against the IK baseline on the validation
files, every sensor preset, realtime and offline, with lost trackers, beside the paper.

    .venv/bin/python scripts/eval_table.py OUT_DIR [--jobs 2] [--realtime-frames 300]
        [--offline-frames 120] [--table-only] [--methods dragposer ik] [--doc docs/evaluation.md]
        [--vae VAE.pt --predictor PRED.pt]

Each run is one ``dragposer-studio evaluate`` call on the files of
``dragposer-studio data list --split val`` (its JSON lands in OUT_DIR; runs that already
have a JSON are kept, so an interrupted table resumes). At the end the tables are
printed and, with ``--doc``, written (atomically) as the whole of that Markdown file.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from engine.atomic import write_text  # noqa: E402
from engine.solver.settings import MODES  # noqa: E402

CLI = str(Path(sys.executable).parent / "dragposer-studio")
PRESETS = ("6", "5", "4", "3-hip-hands", "3-head-hands", "6x3dof")
METHODS = ("dragposer", "ik")
#: The VAE's own ceiling (encode the ground truth, decode it): what no solver on this
#: decoder can beat; one realtime run on preset 6 (the trackers do not matter to it).
CEILING = ("autoencoder", "6", "realtime")
#: Runs with trackers that fail: (label, preset, evaluate options), realtime only.
LOSSY = (("faulty 1%", "6", ("--faulty", "0.01")), ("gaps", "6", ("--gaps",)), ("gaps", "3-head-hands", ("--gaps",)))

#: DragPoser paper (Ponton et al. 2024), Tables 1 and 2: Pos cm (root aligned), Rot deg,
#: Vel cm/s, EE cm; means over their test sets (HUMAN4D, SOMA), trained on DanceDB.
PAPER = {
    "6": (2.18, 7.66, 10.7, 1.02),
    "5-paper": (4.95, 9.25, 15.3, 1.17),
    "4": (7.86, 10.6, 20.0, 1.12),
    "3-hip-hands": (9.95, 14.1, 23.1, 1.77),
    "3-head-hands": (15.5, 22.0, 34.0, 16.1),
    "6x3dof": (5.81, 25.9, 13.2, 1.56),
    "6 faulty 1%": (6.55, 12.0, 21.1, 10.2),
}
#: The paper's baselines on the same sets (Table 1).
PAPER_OTHERS = {
    "6": "FinalIK 3.31 / 11.5; SparsePoser 2.81 / 5.78; AvatarPoser+ 7.66 / 11.3",
    "4": "AvatarPoser 9.24 / 12.4",
    "3-head-hands": "AvatarPoser (3) 11.0 / 14.3",
}


def _name(method: str, preset: str, mode: str, extra: tuple[str, ...] = ()) -> str:
    tag = "".join(x.strip("-").replace(".", "") for x in extra)
    return f"{method}-{preset}-{mode}" + (f"-{tag}" if tag else "")


def run(
    out: Path,
    files: list[str],
    method: str,
    preset: str,
    mode: str,
    frames: int,
    extra: tuple[str, ...],
    models: list[str],
) -> str:
    name = _name(method, preset, mode, extra)
    target = out / f"{name}.json"
    if target.is_file():
        return f"kept {target.name}"
    cmd = [
        CLI,
        "evaluate",
        *files,
        "--method",
        method,
        "--sensors",
        preset,
        "--mode",
        mode,
        "--max-frames",
        str(frames),
        "--no-progress",
        "--json",
        str(target),
        *extra,
        "--jobs",
        "1",  # this script runs the evaluations side by side itself
        *(models if method == "dragposer" else _vae_only(models) if method == "autoencoder" else []),
    ]
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    t0 = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True, env=env)
    (out / f"{name}.txt").write_text(" ".join(cmd) + "\n\n" + res.stdout + res.stderr)
    return f"{'done' if res.returncode == 0 else 'FAILED'} {target.name} ({time.monotonic() - t0:.0f} s)"


def _vae_only(models: list[str]) -> list[str]:
    """The ``--vae PATH`` pair of the model options (the autoencoder has no predictor)."""
    return models[models.index("--vae") :][:2] if "--vae" in models else []


def _total(out: Path, name: str) -> dict | None:
    f = out / f"{name}.json"
    return json.loads(f.read_text())["total"] if f.is_file() else None


def _f(v, fmt: str) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)


def main_table(out: Path, methods) -> str:
    rows = [
        "| preset | mode | method | Pos cm | Pos cm (root aligned) | Rot deg | Vel cm/s | EE cm | "
        "Jitter | GT jitter | ms/frame |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for preset in PRESETS:
        for mode in MODES:
            for method in methods:
                t = _total(out, _name(method, preset, mode))
                if t is None:
                    continue
                bold = "**" if method == "dragposer" else ""
                rows.append(
                    f"| {preset} | {mode} | {method} | {bold}{_f(t['pos_cm'], '.2f')}{bold} | "
                    f"{_f(t.get('pos_rootaligned_cm'), '.2f')} | {bold}{_f(t['rot_deg'], '.1f')}{bold} | "
                    f"{_f(t['vel_cms'], '.1f')} | {_f(t['ee_cm'], '.2f')} | {_f(t['jitter'], '.1f')} | "
                    f"{_f(t['gt_jitter'], '.1f')} | {_f(t['ms_per_frame'], '.0f')} |"
                )
    t = _total(out, _name(*CEILING))
    if t is not None:
        rows.append(
            f"| (any) | | VAE ceiling | {_f(t['pos_cm'], '.2f')} | {_f(t.get('pos_rootaligned_cm'), '.2f')} | "
            f"{_f(t['rot_deg'], '.1f')} | {_f(t['vel_cms'], '.1f')} | {_f(t['ee_cm'], '.2f')} | "
            f"{_f(t['jitter'], '.1f')} | {_f(t['gt_jitter'], '.1f')} | {_f(t['ms_per_frame'], '.0f')} |"
        )
    return "\n".join(rows)


def lossy_table(out: Path, methods) -> str:
    rows = [
        "| trackers | preset | method | Pos cm | Pos cm (root aligned) | Rot deg | EE cm | Jitter | PJ | AUJ | "
        "transitions |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for label, preset, extra in LOSSY:
        for method in methods:
            t = _total(out, _name(method, preset, "realtime", extra))
            if t is None:
                continue
            rows.append(
                f"| {label} | {preset} | {method} | {_f(t['pos_cm'], '.2f')} | "
                f"{_f(t.get('pos_rootaligned_cm'), '.2f')} | {_f(t['rot_deg'], '.1f')} | {_f(t['ee_cm'], '.2f')} | "
                f"{_f(t['jitter'], '.1f')} | {_f(t.get('pj'), '.1f')} | {_f(t.get('auj'), '.0f')} | "
                f"{t.get('transitions', '-')} |"
            )
    return "\n".join(rows)


def paper_table(out: Path) -> str:
    rows = [
        "| sensors | paper Pos cm (root aligned) | ours, root aligned | ours, world | paper Rot deg | ours | "
        "paper EE cm | ours | paper's baselines (Pos / Rot) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for key, (p_pos, p_rot, _p_vel, p_ee) in PAPER.items():
        preset, extra = (key.split(" ")[0], ("--faulty", "0.01")) if "faulty" in key else (key, ())
        t = _total(out, _name("dragposer", preset, "realtime", extra))
        ours = (
            (("-",) * 4)
            if t is None
            else (
                _f(t.get("pos_rootaligned_cm"), ".2f"),
                _f(t["pos_cm"], ".2f"),
                _f(t["rot_deg"], ".1f"),
                _f(t["ee_cm"], ".2f"),
            )
        )
        rows.append(
            f"| {key} | {p_pos} | {ours[0]} | {ours[1]} | {p_rot} | {ours[2]} | {p_ee} | {ours[3]} | "
            f"{PAPER_OTHERS.get(key, '')} |"
        )
    return "\n".join(rows)


def _files_text(files: list[str], given: bool) -> str:
    """What the table was measured on, for the document's first paragraph."""
    if not given:
        return f"the {len(files)} validation files of the default split (`dragposer-studio data list\n--split val`)"
    names = ", ".join(f"`{Path(f).parent.name}/{Path(f).stem}`" for f in files)
    return f"{len(files)} files given with `--files` ({names})"


def document(out: Path, methods, args, files: list[str]) -> str:
    gt = _total(out, _name("ik", "6", "realtime")) or _total(out, _name("dragposer", "6", "realtime")) or {}
    models = (
        f"`{args.vae}` and `{args.predictor}`"
        if args.vae
        else "`assets/models` (see the [model card](../assets/models/README.md))"
    )
    lossy = args.lossy_frames or args.realtime_frames
    inputs = "FILE..." if args.files else "$(dragposer-studio data list --split val)"
    cmd = (
        f"python scripts/eval_table.py {args.out} --jobs {args.jobs} --realtime-frames {args.realtime_frames} "
        f"--offline-frames {args.offline_frames} --lossy-frames {lossy} --doc docs/evaluation.md"
        + (" --files FILE..." if args.files else "")
    )
    return f"""# Evaluation of the shipped models

Generated by `scripts/eval_table.py` (do not edit by hand) with the models in {models},
on {_files_text(files, args.files is not None)}, on a 2-core CPU machine with no GPU. Metrics are defined in
[metrics.md](metrics.md); solver settings are the defaults (per-sensor-set profiles,
[optimizer.md](optimizer.md)). Reproduce everything with

```bash
{cmd}
```

which runs, for every preset P, mode M and method X,
`dragposer-studio evaluate {inputs} --method X --sensors P --mode M --max-frames N --json {args.out}/X-P-M.json`,
first {args.realtime_frames} frames of each file in realtime mode, first {args.offline_frames} in
offline mode (offline costs up to 100 iterations per frame), first {lossy} with lost trackers. `ms/frame` was measured with
{args.jobs} evaluations sharing the two cores (idle-machine speed: `docs/performance.md`).
The ground truth's own jitter on the realtime frames is {_f(gt.get("gt_jitter"), ".1f")}.
What limits the figures that miss their targets, with the ablations that show it:
[accuracy.md](accuracy.md).
{(chr(10) + "**Note.** " + args.note + chr(10)) if args.note else ""}
## All sensor sets

{main_table(out, methods)}

Presets: `6` hips, head, hands, feet; `5` head, hands, feet (no hips; the paper's "5"
keeps the hips and drops the left foot, our `5-paper`); `4` hips, head, hands;
`3-hip-hands`; `3-head-hands`; `6x3dof` the six of `6` with positions only. `Pos` is
world space; `Pos (root aligned)` translates each reconstructed frame so its root
matches the ground truth's, as DragPoser's tables do. The **VAE ceiling** row encodes
the ground-truth pose and decodes it (`--method autoencoder`): the error of the decoder
itself, which no latent the solver finds can go below on the joints it decodes (the
solver's steps after the solve, reach and tracker rotations, act on tracked limbs only).

## Lost trackers (realtime)

`--faulty 0.01`: every frame, with probability 1 %, one sensor fails for 100 frames
(DragPoser sec. 5.2). `--gaps`: RPM's hand-tracking gaps. PJ / AUJ as FlowMDM defines them
and RPM uses them (sec. 4; [metrics.md](metrics.md)): the peak of the largest joint's jerk in
the second after a tracking change (averaged over the changes), and its summed distance from
the ground truth's jerk level (real motion scores about 0).

{lossy_table(out, methods)}

## Beside the paper

DragPoser's Tables 1 and 2 against our realtime rows:

{paper_table(out)}

What differs in the protocol, so the columns are not strictly comparable:

- **Data.** The paper trains on DanceDB and tests on HUMAN4D and SOMA (AMASS); we train
  on 200 CMU files on four rigs (retargeted, plus mirrors; about 30 minutes of motion) and
  test on held-out CMU takes of the same sources (dance, walks, basketball). Our VAE and
  predictor are trained on 2 CPU cores (the VAE 56 minutes, then fine-tunes of 36, 50 and
  47 minutes as the retargeting and the data changed; the predictor 25 minutes, then
  fine-tunes of 16 and 21), the paper's VAE for about a day on a GPU.
- **Skeleton.** Ours is the canonical 22-joint skeleton with each subject's bone lengths;
  the paper's is DanceDB's 22-joint rig.
- **Metric.** The paper aligns the root before measuring Pos; compare its Pos with our
  "root aligned" column. Our Rot averages all 22 joints including the root's world
  rotation (metrics.md). The paper does not state its realtime/offline setting for the
  tables; its realtime setting is 1 iteration per frame, ours 10 (its offline up to 10,
  ours up to 100).
- **Trackers** are simulated from the clips (exact positions and rotations, no noise);
  the paper's are too. Frames: the first {args.realtime_frames} (realtime) of each file, not whole clips.
- **`5`** is not the paper's five-sensor set (see above); the paper's row is `5-paper`,
  which this table does not run.
- **Head and hands**: the paper adds ad-hoc losses (feet near the floor, hips under the
  head); we anchor the body to the head tracker and limit the root heading to the
  facing of the head and hands (optimizer.md).
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path)
    ap.add_argument("--jobs", type=int, default=2, help="evaluations at once (default 2: the machine's cores)")
    ap.add_argument("--realtime-frames", type=int, default=300)
    ap.add_argument("--offline-frames", type=int, default=120)
    ap.add_argument(
        "--lossy-frames",
        type=int,
        help="frames of the --faulty/--gaps runs (default: --realtime-frames; "
        "PJ/AUJ need complete 1-s windows after tracking changes, so 300 or more)",
    )
    ap.add_argument("--no-ceiling", action="store_true", help="skip the VAE-ceiling (autoencoder) run")
    ap.add_argument("--table-only", action="store_true", help="print (and write) the tables from the JSONs present")
    ap.add_argument(
        "--methods",
        nargs="+",
        default=list(METHODS),
        choices=METHODS,
        help="run only these methods (e.g. ik while the models are still training)",
    )
    ap.add_argument("--presets", nargs="+", default=list(PRESETS), choices=PRESETS)
    ap.add_argument("--no-lossy", action="store_true", help="skip the --faulty / --gaps runs")
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES, help="solver modes (default: all)")
    ap.add_argument("--vae", help="evaluate these models instead of the shipped ones (with --predictor)")
    ap.add_argument("--predictor")
    ap.add_argument("--doc", type=Path, help="write the whole Markdown document here (docs/evaluation.md)")
    ap.add_argument("--note", help="a paragraph to state in the document (e.g. which runs are missing)")
    ap.add_argument(
        "--files",
        nargs="+",
        help="evaluate these BVH files instead of those of "
        "'dragposer-studio data list --split val' (e.g. an earlier split's validation files)",
    )
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    files = (
        args.files
        or subprocess.run(
            [CLI, "data", "list", "--split", "val"],
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        ).stdout.split()
    )
    models = [*(["--vae", args.vae] if args.vae else []), *(["--predictor", args.predictor] if args.predictor else [])]
    if not args.table_only:
        jobs = [
            (m, p, mode, args.realtime_frames if mode == "realtime" else args.offline_frames, ())
            for p in args.presets
            for mode in args.modes
            for m in args.methods
        ]
        if not args.no_lossy:
            lossy = args.lossy_frames or args.realtime_frames
            jobs += [(m, p, "realtime", lossy, extra) for _, p, extra in LOSSY for m in args.methods]
        if not args.no_ceiling:
            jobs.append((*CEILING, args.realtime_frames, ()))
        # realtime DragPoser first (the figures the targets are about), then IK, offline last
        jobs.sort(key=lambda j: (j[2] == "offline", bool(j[4]), j[0] != "dragposer"))
        with ThreadPoolExecutor(args.jobs) as pool:
            for msg in pool.map(lambda j: run(args.out, files, *j, models), jobs):
                print(msg, flush=True)
    print(main_table(args.out, args.methods))
    print(lossy_table(args.out, args.methods))
    print(paper_table(args.out))
    if args.doc:
        write_text(args.doc, document(args.out, args.methods, args, files))
        print(f"wrote {args.doc}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
