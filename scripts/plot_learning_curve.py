"""Plot a training run's validation curve (``losses.csv`` of ``train vae``) for the model card.

    PYTHONPATH=. python scripts/plot_learning_curve.py runs/vae/losses.csv --out docs/images/vae_curve.png
        [--start-cm 0.592 --start-deg 6.67] [--title TEXT]

Draws validation position error (cm, left axis) and rotation error (degrees, right axis) by
epoch; ``--start-*`` adds the starting model's figures as epoch 0 (a fine-tuning run).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from engine.atomic import atomic_path  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--start-cm", type=float)
    ap.add_argument("--start-deg", type=float)
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    rows = list(csv.DictReader(args.csv.open()))
    epochs = [int(r["epoch"]) for r in rows]
    cm = [float(r["val_pos_cm"]) for r in rows]
    deg = [float(r["val_rot_deg"]) for r in rows]
    if args.start_cm is not None and args.start_deg is not None:
        epochs, cm, deg = [0] + epochs, [args.start_cm] + cm, [args.start_deg] + deg
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(epochs, cm, "o-", color="tab:blue", label="position error (cm)")
    ax.set_xlabel("epoch")
    ax.set_ylabel("validation position error, cm", color="tab:blue")
    ax.grid(True, alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(epochs, deg, "s--", color="tab:orange", label="rotation error (deg)")
    ax2.set_ylabel("validation rotation error, deg", color="tab:orange")
    if args.title:
        ax.set_title(args.title, fontsize=9)
    fig.tight_layout()
    with atomic_path(args.out, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
