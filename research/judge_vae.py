"""Judge a retrained VAE by the model card's rule (assets/models/README.md, "The decoder
trained again with pose authoring in the rule"): install it in a checkout, measure both
checkouts the same way, and print each criterion with its verdict.

    PYTHONPATH=. python research/judge_vae.py install CAND_VAE TREE [--predictor P] [--data prepared]
    PYTHONPATH=. python research/judge_vae.py measure TREE OUT [--data prepared]
    PYTHONPATH=. python research/judge_vae.py judge BASE_OUT CAND_OUT [--own BASE_CM CAND_CM]

``install`` makes TREE a detached checkout of HEAD (unless it exists) holding the candidate
``vae.pt`` (and ``predictor.pt`` when given: a VAE whose encoder moved needs its own), then
rebuilds the pose bank, the latent map, the tracker networks (about 4 minutes) and the
pose-task scenes for it there. ``measure``
writes into OUT what the rule reads: DragPoser on the validation files (first 150 frames;
presets 6, 4, 3-head-hands, 6x3dof), every 12th ``hdm05/`` clip whole and the first 600
frames of the ``dragposer/`` clips (presets 4 and 3-head-hands), and ``bench --pose-tasks``
at 10, 20, 30 and 40 drag events, plus the authoring tests' outcome. With ``--parts val``
in one process and ``--parts other tasks`` in another it took 3 minutes on the 2-core
machine; measure the baseline (a checkout of the same commit with the shipped files)
the same way. ``judge`` compares two OUT folders: criteria 2-4 from them, criterion 1 from
``--own`` (the runs' validation errors, ``val_pos_cm`` of their ``losses.csv``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MOCAP = ROOT.parent / "shared" / "data" / "mocap"
VAL_PRESETS = ("6", "4", "3-head-hands", "6x3dof")
OTHER_PRESETS = ("4", "3-head-hands")
EVENTS = (10, 20, 30, 40)
#: ``measure --parts``: the validation files, the other labs' clips, the pose tasks and tests.
PARTS = ("val", "other", "tasks")
AUTHORING_TESTS = ("tests/engine/authoring", "tests/engine/test_solver_batch.py")
#: The rule's bounds: tracking at most 3 % worse, a task's goal error at most 0.5 cm more,
#: its distance to real poses at most 10 % more.
TRACKING, GOAL_CM, NATURAL = 0.03, 0.5, 0.10


def _run(tree: Path, args: list[str], log: Path | None = None) -> int:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(tree)}
    out = open(log, "w") if log else None
    try:
        return subprocess.call([sys.executable, *args], cwd=tree, env=env, stdout=out, stderr=subprocess.STDOUT)
    finally:
        if out:
            out.close()


def install(a: argparse.Namespace) -> None:
    tree = Path(a.tree).resolve()
    if not tree.exists():
        subprocess.check_call(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), "HEAD"])
    models = tree / "assets" / "models"
    shutil.copyfile(a.vae, models / "vae.pt")
    if a.predictor:
        shutil.copyfile(a.predictor, models / "predictor.pt")
    nets = "assets/models/tracker_nets.npz"
    steps = [
        ["scripts/build_pose_bank.py", "--data", str(a.data), "--out", "assets/models/pose_bank.npz", "--stride", "4"],
        ["scripts/build_latent_map.py", "--out", "assets/models/latent_map.npz"],
        ["-m", "engine.cli.main", "train", "tracker-net", "--data", str(a.data), "--out", nets],
        ["scripts/pose_task_scenes.py"],
    ]
    for step in steps:
        if _run(tree, step):
            sys.exit(f"install: {' '.join(step)} failed in {tree}")


def _val_files(tree: Path, data: Path) -> list[str]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, "-m", "engine.cli.main", "data", "list", "--data", str(data), "--split", "val"]
    return subprocess.check_output(cmd, cwd=tree, env=env, text=True).split()


def measure(a: argparse.Namespace) -> None:
    tree, out = Path(a.tree).resolve(), Path(a.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    hdm = sorted(str(p) for p in (MOCAP / "hdm05").glob("*.amc"))[::12]
    dp = sorted(str(p) for p in (MOCAP / "dragposer").glob("*.bvh"))
    sets = []
    if "val" in a.parts:
        sets += [("val", _val_files(tree, Path(a.data)), VAL_PRESETS, ["--max-frames", "150"])]
    if "other" in a.parts:
        sets += [("hdm", hdm, OTHER_PRESETS, []), ("dp", dp, OTHER_PRESETS, ["--max-frames", "600"])]
    ev = ["-m", "engine.cli.main", "evaluate"]
    for name, files, presets, extra in sets:
        for p in presets:
            stem = out / f"{name}_{p}"
            args = [*ev, *files, "--method", "dragposer", "--sensors", p, *extra, "--no-progress"]
            _run(tree, [*args, "--json", f"{stem}.json"], Path(f"{stem}.log"))
    if "tasks" not in a.parts:
        return
    for e in EVENTS:
        stem = out / f"tasks_e{e}"
        args = ["-m", "engine.cli.main", "bench", "--pose-tasks", "--method", "pose-mode", "--events", str(e)]
        _run(tree, [*args, "--json", f"{stem}.json"], Path(f"{stem}.log"))
    code = _run(tree, ["-m", "pytest", "-q", "-p", "no:cacheprovider", *AUTHORING_TESTS], out / "authoring_tests.log")
    (out / "authoring_tests.json").write_text(json.dumps({"exit_status": code}))


def _total(path: Path) -> dict:
    return json.loads(path.read_text())["total"]


def pose_tasks(out: Path) -> dict[str, tuple[float, float, int]]:
    """Per task, over the drag speeds: mean goal error (cm), mean distance to the nearest
    real pose (cm) and how many ended outside the real poses' spread."""
    acc: dict[str, list] = {}
    for e in EVENTS:
        for t in json.loads((out / f"tasks_e{e}.json").read_text())["tasks"]:
            if t["poser"] != "pose-mode":
                continue
            err = max([g["error"] for g in t["goal_errors"] if g["kind"] == "position"], default=0.0)
            acc.setdefault(t["task"], []).append((err, t["naturalness_cm"], not t["within_spread"]))
    return {
        k: (sum(r[0] for r in v) / len(v), sum(r[1] for r in v) / len(v), sum(r[2] for r in v)) for k, v in acc.items()
    }


def judge(base: Path, cand: Path, own: tuple[float, float] | None) -> bool:
    """Print the four criteria; True when all that could be judged hold."""
    verdicts = []
    if own:
        ok = own[1] < own[0]
        verdicts.append(ok)
        print(f"1. own validation error {own[0]:.3f} -> {own[1]:.3f} cm: {'holds' if ok else 'fails'}")
    else:
        print("1. own validation error: not given (--own BASE_CM CAND_CM)")
    worst = 0.0
    for p in VAL_PRESETS:
        b, c = _total(base / f"val_{p}.json"), _total(cand / f"val_{p}.json")
        dp, dr = c["pos_cm"] / b["pos_cm"] - 1, c["rot_deg"] / b["rot_deg"] - 1
        worst = max(worst, dp, dr)
        print(f"   val {p:13s} Pos {b['pos_cm']:.3f} -> {c['pos_cm']:.3f} ({100 * dp:+.1f} %)  Rot {100 * dr:+.1f} %")
    verdicts.append(worst <= TRACKING)
    print(f"2. validation files, worst change {100 * worst:+.1f} %: {'holds' if verdicts[-1] else 'fails'}")
    changes = []
    for name in ("hdm", "dp"):
        for p in OTHER_PRESETS:
            b, c = _total(base / f"{name}_{p}.json"), _total(cand / f"{name}_{p}.json")
            changes.append(c["pos_cm"] / b["pos_cm"] - 1)
            print(f"   {name:3s} {p:13s} Pos {b['pos_cm']:.2f} -> {c['pos_cm']:.2f} ({100 * changes[-1]:+.1f} %)")
    mean = sum(changes) / len(changes)
    verdicts.append(max(changes) <= TRACKING and mean <= 0)
    print(
        f"3. other labs, worst {100 * max(changes):+.1f} %, mean {100 * mean:+.1f} %: {'holds' if verdicts[-1] else 'fails'}"
    )
    tb, tc = pose_tasks(base), pose_tasks(cand)
    ok = True
    for task, (be, bn, bo) in tb.items():
        ce, cn, co = tc[task]
        fine = ce <= be + GOAL_CM and cn <= bn * (1 + NATURAL) and co <= bo
        ok &= fine
        change = 100 * (cn / bn - 1)
        print(
            f"   {task:15s} err {be:.2f} -> {ce:.2f} cm  natural {bn:.2f} -> {cn:.2f} ({change:+.1f} %)  out {bo} -> {co}"
        )
    tests = json.loads((cand / "authoring_tests.json").read_text())["exit_status"]
    ok &= tests == 0
    verdicts.append(ok)
    passed = "pass" if tests == 0 else "fail"
    print(f"4. pose authoring (authoring tests {passed}): {'holds' if ok else 'fails'}")
    return all(verdicts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    i = sub.add_parser("install", help="a checkout of HEAD with the candidate and its bank, map and scenes")
    i.add_argument("vae", type=Path)
    i.add_argument("tree", type=Path)
    i.add_argument("--predictor", type=Path)
    i.add_argument("--data", type=Path, default=ROOT / "prepared")
    m = sub.add_parser("measure", help="what the rule reads, measured in one checkout")
    m.add_argument("tree", type=Path)
    m.add_argument("out", type=Path)
    m.add_argument("--data", type=Path, default=ROOT / "prepared")
    m.add_argument(
        "--parts",
        nargs="+",
        choices=PARTS,
        default=list(PARTS),
        help="what to measure (two processes with different parts fill two cores; same OUT)",
    )
    j = sub.add_parser("judge", help="the four criteria from two measure folders")
    j.add_argument("base", type=Path)
    j.add_argument("cand", type=Path)
    j.add_argument("--own", type=float, nargs=2, metavar=("BASE_CM", "CAND_CM"))
    a = ap.parse_args()
    if a.command == "install":
        install(a)
    elif a.command == "measure":
        measure(a)
    else:
        sys.exit(0 if judge(a.base, a.cand, tuple(a.own) if a.own else None) else 1)


if __name__ == "__main__":
    main()
