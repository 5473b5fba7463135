"""Does anything but the bounded per-frame figures grow in a long `live` run? The live soak
(`scripts/soak.py live`) under tracemalloc: snapshots after ``--first`` and at the end
minute, compared by allocation traceback; prints the largest growths.

    PYTHONPATH=. python research/live_tracemalloc.py [--minutes 9] [--first 2] [--top 12]
"""

from __future__ import annotations

import argparse
import threading
import time
import tracemalloc

from scripts.soak import main as soak


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=int, default=9)
    ap.add_argument("--first", type=float, default=2.0, help="minute of the first snapshot")
    ap.add_argument("--top", type=int, default=12)
    a = ap.parse_args()
    tracemalloc.start(8)
    snaps: list[tracemalloc.Snapshot] = []

    def take() -> None:
        time.sleep(60.0 * a.first)
        snaps.append(tracemalloc.take_snapshot())
        time.sleep(60.0 * (a.minutes - a.first) - 30.0)  # the last minute's middle, before the soak ends
        snaps.append(tracemalloc.take_snapshot())

    t = threading.Thread(target=take, daemon=True)
    t.start()
    code = soak(["live", "--minutes", str(a.minutes)])
    t.join(timeout=5.0)
    if len(snaps) < 2:
        raise SystemExit("the soak ended before the second snapshot")
    stats = snaps[1].compare_to(snaps[0], "traceback")
    grown = sum(s.size_diff for s in stats)
    span = a.minutes - a.first - 0.5
    print(f"traced growth between minute {a.first:g} and {a.minutes - 0.5:g}: {grown / 1024:.1f} KiB ({span:g} min)")
    for s in stats[: a.top]:
        frame = s.traceback[-1] if len(s.traceback) else None
        where = f"{frame.filename}:{frame.lineno}" if frame else "?"
        print(f"{s.size_diff / 1024:9.1f} KiB {s.count_diff:+7d} blocks  {where}")
    raise SystemExit(code)


if __name__ == "__main__":
    main()
