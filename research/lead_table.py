"""DragPoser against IK per preset from ``evaluate --method dragposer,ik --json`` files:
Pos and Rot of each, DragPoser's lead over IK (positive: DragPoser lower), over all files
and over the files whose names hold any of ``--walks`` (issue 48's "walking clips alone").

    PYTHONPATH=. python research/lead_table.py runs/status17/dp_whole_*.json [--walks jog,sneak,example_2]
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path


def pooled(files: dict, keep) -> tuple[float, float, int]:
    """Frame-weighted mean Pos and Rot of the files ``keep(name)`` accepts."""
    rows = [r for name, r in files.items() if keep(name)]
    n = sum(r["frames"] for r in rows)
    if not n:
        return float("nan"), float("nan"), 0
    return (sum(r["pos_cm"] * r["frames"] for r in rows) / n, sum(r["rot_deg"] * r["frames"] for r in rows) / n, n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+", type=Path)
    ap.add_argument("--walks", default="", help="comma-separated name parts of the walking clips")
    a = ap.parse_args()
    walks = [w for w in a.walks.split(",") if w]
    print(
        f"{'file':28s} {'preset':13s} {'subset':7s} {'frames':>6s}  {'DP Pos/Rot':>13s}  {'IK Pos/Rot':>13s}  lead Pos / Rot"
    )
    for path in a.files:
        d = json.loads(path.read_text())
        preset = d["dragposer"]["preset"]
        subsets = [("all", lambda n: True)]
        if walks:
            subsets.append(("walks", lambda n: any(w in Path(n).name for w in walks)))
        for label, keep in subsets:
            dp, ik = pooled(d["dragposer"]["files"], keep), pooled(d["ik"]["files"], keep)
            if not dp[2]:
                continue
            lead = (1 - dp[0] / ik[0]) * 100, (1 - dp[1] / ik[1]) * 100
            stem = re.sub(r"_(6|5|5-paper|4|3-hip-hands|3-head-hands|6x3dof)$", "", path.stem)
            print(
                f"{stem:28s} {preset:13s} {label:7s} {dp[2]:6d}  {dp[0]:5.2f} / {dp[1]:5.2f}  {ik[0]:5.2f} / {ik[1]:5.2f}"
                f"  {lead[0]:+5.1f} % / {lead[1]:+5.1f} %"
            )


if __name__ == "__main__":
    main()
