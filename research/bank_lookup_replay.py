"""How much does a live pose-bank lookup cost with and without the rows kept near the last
queries (``bank_prefilter.Neighbourhood``), and at which ``SLACK``?

Runs realtime DragPoser on the bundled clip, records every lookup's query and hint, then
replays them through ``bank_prefilter.nearest`` in this process, whole-table bounds
against a ``Neighbourhood``, in interleaved rounds, checking each answer against the
recorded one. Prints CPU milliseconds per lookup (``time.thread_time``: what a busy
machine still gives) and how often the neighbourhood read the whole table.

    PYTHONPATH=. python research/bank_lookup_replay.py [--sensors 6] [--frames 1000] [--slack 0.5 1 1.5]
"""

from __future__ import annotations

import argparse
import time


def main() -> None:
    """Record the lookups of one run, then time their replays (see the module doc)."""
    import torch

    import engine.solver.bank_prefilter as bp
    import engine.solver.tracker_prior as tp
    from engine.cli.bench import DEFAULT_CLIP
    from engine.methods import driver, get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--slack", type=float, nargs="+", default=[bp.SLACK])
    args = ap.parse_args()
    torch.set_num_threads(1)
    recorded = []
    real = tp.nearest

    def recording(table, norms, q, q_cols, pre, hint, k, bound=None, near=None):
        got = real(table, norms, q, q_cols, pre, hint, k, bound, near)
        recorded.append((table, norms, q.clone(), q_cols.copy(), pre, None if hint is None else hint.clone(), k, got))
        return got

    tp.nearest = recording
    motion = load_motion(DEFAULT_CLIP)
    tracking = simulate(motion, args.sensors)
    method = get_method("dragposer", mode="realtime", iterations=10)
    driver.reset(method, motion.skeleton, motion.fps, reference=motion)
    for i in range(min(len(tracking), args.frames)):
        driver.step(method, tracking.frame(i))
    tp.nearest = real
    lookups = recorded[5:]  # past the first frames' full searches
    print(f"{len(lookups)} lookups of preset {args.sensors} on {DEFAULT_CLIP.name}")
    for rnd in range(args.rounds):
        for slack in [None, *args.slack]:
            near = None if slack is None else bp.Neighbourhood()
            if slack is not None:
                bp.SLACK = slack
            t = time.thread_time()
            for table, norms, q, q_cols, pre, hint, k, want in lookups:
                assert torch.equal(real(table, norms, q, q_cols, pre, hint, k, None, near), want)
            ms = 1000 * (time.thread_time() - t) / len(lookups)
            what = "whole-table bounds" if near is None else f"neighbourhood, SLACK {slack}"
            reads = "" if near is None else f", the table read every {len(lookups) / near.refreshed:.1f} lookups"
            print(f"round {rnd + 1}: {what:28s} {ms:.3f} ms CPU per lookup{reads}")


if __name__ == "__main__":
    main()
