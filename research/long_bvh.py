"""Write a long BVH file by repeating the rows of a clip: the input of the memory figures
in docs/limits.md.

    python research/long_bvh.py assets/clips/example.bvh /tmp/long.bvh --frames 200000
    /usr/bin/time -v dragposer-studio info /tmp/long.bvh             # "Maximum resident set size"
    /usr/bin/time -v dragposer-studio reconstruct /tmp/long.bvh --out /tmp/o.bvh --max-frames 8
"""

from __future__ import annotations

import argparse


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("source")
    ap.add_argument("out")
    ap.add_argument("--frames", type=int, default=200_000)
    args = ap.parse_args()
    lines = open(args.source, encoding="utf-8").read().splitlines()
    m = next(i for i, s in enumerate(lines) if s.strip().upper() == "MOTION")
    rows = [r for r in lines[m + 3 :] if r.strip()]
    with open(args.out, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines[: m + 1]) + f"\nFrames: {args.frames}\n{lines[m + 2]}\n")
        for i in range(args.frames):
            fh.write(rows[i % len(rows)] + "\n")


if __name__ == "__main__":
    main()
